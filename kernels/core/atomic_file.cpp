#include "atomic_file.hpp"

#include <cerrno>
#include <csignal>
#include <cstring>
#include <filesystem>
#include <mutex>
#include <stdexcept>
#include <utility>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <fmt/format.h>

namespace bokeh {

namespace {

struct ProtectedInput {
  dev_t device;
  ino_t inode;
  std::string path;
};

std::mutex g_inputs_mutex;
std::vector<ProtectedInput> g_inputs;

std::string errno_text(int error) { return std::strerror(error); }

// Creates the temporary (O_EXCL: reserved for this write). Throws the reason on failure.
std::string reserve_temporary(const std::string& path) {
  for (int n = 0;; ++n) {
    const std::string temporary =
        n == 0 ? fmt::format("{}.tmp.{}", path, ::getpid()) : fmt::format("{}.tmp.{}-{}", path, ::getpid(), n);
    const int fd = ::open(temporary.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
    if (fd >= 0) {
      ::close(fd);
      return temporary;
    }
    if (errno != EEXIST || n >= 1000)
      throw std::runtime_error(fmt::format("cannot create a temporary file in its folder: {}", errno_text(errno)));
  }
}

void fsync_path(const std::string& path, bool directory) {
  const int fd = ::open(path.c_str(), (directory ? O_RDONLY | O_DIRECTORY : O_RDONLY) | O_CLOEXEC);
  if (fd < 0) {
    if (directory) return;  // best effort: the rename itself has happened
    throw std::runtime_error(fmt::format("cannot reopen the temporary to flush it: {}", errno_text(errno)));
  }
  const int rc = ::fsync(fd);
  const int error = errno;
  ::close(fd);
  if (rc != 0 && !directory) throw std::runtime_error(fmt::format("flushing to disk failed: {}", errno_text(error)));
}

}  // namespace

void write_whole_file(const std::string& file, std::string_view text) {
  const int fd = ::open(file.c_str(), O_WRONLY | O_TRUNC | O_CLOEXEC);
  if (fd < 0) throw std::runtime_error(errno_text(errno));
  std::size_t done = 0;
  while (done < text.size()) {
    const ssize_t n = ::write(fd, text.data() + done, text.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      const int error = n < 0 ? errno : EIO;
      ::close(fd);
      throw std::runtime_error(fmt::format("after {} of {} bytes: {}", done, text.size(), errno_text(error)));
    }
    done += static_cast<std::size_t>(n);
  }
  if (::close(fd) != 0) throw std::runtime_error(errno_text(errno));
}

void protect_inputs(const std::vector<std::string>& inputs) {
  const std::lock_guard lock(g_inputs_mutex);
  for (const std::string& input : inputs) {
    struct stat st {};
    if (input.empty() || ::stat(input.c_str(), &st) != 0) continue;
    bool known = false;
    for (const ProtectedInput& p : g_inputs) known = known || (p.device == st.st_dev && p.inode == st.st_ino);
    if (!known) g_inputs.push_back({st.st_dev, st.st_ino, input});
  }
}

void refuse_input_as_output(const std::string& path, const std::vector<std::string>& inputs) {
  struct stat target {};
  if (path.empty() || ::stat(path.c_str(), &target) != 0) return;  // a file that does not exist is no input
  auto refuse = [&](const std::string& input) {
    throw std::runtime_error(fmt::format("output '{}' is the input '{}': choose another output path", path, input));
  };
  for (const std::string& input : inputs) {
    struct stat st {};
    if (!input.empty() && ::stat(input.c_str(), &st) == 0 && st.st_dev == target.st_dev && st.st_ino == target.st_ino)
      refuse(input);
  }
  const std::lock_guard lock(g_inputs_mutex);
  for (const ProtectedInput& p : g_inputs)
    if (p.device == target.st_dev && p.inode == target.st_ino) refuse(p.path);
}

void write_file_atomically(const std::string& path, const std::function<void(const std::string&)>& fill,
                           const std::string& what) {
  auto fail = [&](const std::string& why) {
    throw std::runtime_error(fmt::format("cannot write {} '{}': {}", what, path, why));
  };
  if (path.empty()) throw std::runtime_error(fmt::format("cannot write {}: its path is empty", what));
  refuse_input_as_output(path);
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) fail("it is a directory");
  const std::filesystem::path parent = std::filesystem::path(path).parent_path();
  std::string temporary;
  try {
    temporary = reserve_temporary(path);
  } catch (const std::exception& e) {
    fail(e.what());
  }
  try {
    fill(temporary);
    fsync_path(temporary, /*directory=*/false);
    if (::rename(temporary.c_str(), path.c_str()) != 0) throw std::runtime_error(fmt::format("rename: {}", errno_text(errno)));
  } catch (const std::exception& e) {
    ::unlink(temporary.c_str());
    fail(e.what());
  } catch (...) {
    ::unlink(temporary.c_str());
    throw;
  }
  fsync_path(parent.empty() ? std::string(".") : parent.string(), /*directory=*/true);
}

void write_text_file_atomically(const std::string& path, std::string_view text, const std::string& what) {
  write_file_atomically(path, [&](const std::string& temporary) { write_whole_file(temporary, text); }, what);
}

int remove_stale_temporaries(const std::string& dir) {
  std::error_code ec;
  int removed = 0;
  for (const auto& entry : std::filesystem::directory_iterator(dir, ec)) {
    const std::string name = entry.path().filename().string();
    const auto dot = name.rfind(".tmp.");
    if (dot == std::string::npos) continue;
    std::string pid = name.substr(dot + 5);
    const auto dash = pid.find('-');
    if (dash != std::string::npos) {
      const std::string n = pid.substr(dash + 1);
      if (n.empty() || n.find_first_not_of("0123456789") != std::string::npos) continue;
      pid.resize(dash);
    }
    if (pid.empty() || pid.size() > 9 || pid.find_first_not_of("0123456789") != std::string::npos) continue;
    if (::kill(static_cast<pid_t>(std::stol(pid)), 0) == 0 || errno != ESRCH) continue;  // still running
    if (std::filesystem::remove(entry.path(), ec)) ++removed;
  }
  return removed;
}

}  // namespace bokeh
