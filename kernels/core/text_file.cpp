#include "text_file.hpp"

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include <fmt/format.h>

namespace bokeh {

std::string read_text_file(const std::string& path, const std::string& what) {
  auto fail = [&](const std::string& why) {
    throw std::runtime_error(fmt::format("{}: {} ({})", path, why, what));
  };
  std::error_code ec;
  const auto status = std::filesystem::status(path, ec);
  if (status.type() == std::filesystem::file_type::not_found) fail("no such file");
  if (status.type() == std::filesystem::file_type::directory) fail("it is a directory, not a file");
  std::ifstream in(path, std::ios::binary);
  if (!in) fail(fmt::format("cannot be opened: {}", std::strerror(errno)));
  std::ostringstream text;
  try {
    text << in.rdbuf();  // a read error (e.g. EIO) throws from the stream buffer
  } catch (const std::exception& e) {
    fail(fmt::format("cannot be read: {}", e.what()));
  }
  if (in.bad()) fail("cannot be read");
  return text.str();
}

}  // namespace bokeh
