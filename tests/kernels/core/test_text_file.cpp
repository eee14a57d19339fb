// Reading a text file (results JSON, lens files): every failure names the path and what is wrong.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <random>
#include <stdexcept>
#include <string>

#include "lens.hpp"
#include "text_file.hpp"

namespace bokeh {
namespace {

namespace fs = std::filesystem;

std::string error_of(const std::string& path) {
  try {
    read_text_file(path, "results file");
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "no error";
}

TEST(TextFile, FailuresNameThePathAndTheProblem) {
  const fs::path dir = fs::temp_directory_path() / ("bokeh-text-file-" + std::to_string(std::random_device{}()));
  fs::create_directories(dir);
  const std::string file = (dir / "a.json").string();
  std::ofstream(file) << "{\"x\": 1}\n";
  EXPECT_EQ(read_text_file(file, "results file"), "{\"x\": 1}\n");
  EXPECT_EQ(error_of(dir.string()), dir.string() + ": it is a directory, not a file (results file)");
  EXPECT_EQ(error_of((dir / "none.json").string()), (dir / "none.json").string() + ": no such file (results file)");
  // A lens file that is a directory (a caller without CLI11's existence check) is named too.
  try {
    load_lens_json(dir.string());
    ADD_FAILURE() << "a directory was read as a lens file";
  } catch (const std::runtime_error& e) {
    EXPECT_EQ(std::string(e.what()), dir.string() + ": it is a directory, not a file (lens file)");
  }
  fs::remove_all(dir);
}

}  // namespace
}  // namespace bokeh
