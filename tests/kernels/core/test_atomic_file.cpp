// The one write path (atomic_file.hpp) under faults: a write that fails (the writer throws, a file-size
// limit standing in for a full disk, a read-only folder) leaves the old file byte for byte, no temporary,
// and an error naming the target; results text and images (EXR, PNG) alike. Inputs are never targets.
#include <gtest/gtest.h>

#include <csignal>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>
#include <stdexcept>
#include <string>

#include <sys/resource.h>
#include <unistd.h>

#include <fmt/format.h>

#include "atomic_file.hpp"
#include "image_io.hpp"
#include "test_support.hpp"

namespace bokeh {
namespace {

namespace fs = std::filesystem;
using test::random_image;

class AtomicFile : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("bokeh-atomic-" + std::to_string(std::random_device{}()));
    fs::create_directories(dir_);
  }
  void TearDown() override {
    fs::permissions(dir_, fs::perms::owner_all);
    fs::remove_all(dir_);
  }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }
  // Every name in the folder: a temporary left behind shows here.
  std::string listing() const {
    std::string names;
    for (const auto& e : fs::directory_iterator(dir_)) names += e.path().filename().string() + " ";
    return names;
  }
  static std::string read(const std::string& p) {
    std::ifstream in(p, std::ios::binary);
    std::stringstream s;
    s << in.rdbuf();
    return s.str();
  }
  fs::path dir_;
};

// Writes past `bytes` fail with EFBIG (SIGXFSZ ignored) while it lives: a full disk, without root.
class FileSizeLimit {
 public:
  explicit FileSizeLimit(rlim_t bytes) {
    old_handler_ = std::signal(SIGXFSZ, SIG_IGN);
    getrlimit(RLIMIT_FSIZE, &old_);
    rlimit limit = old_;
    limit.rlim_cur = bytes;
    setrlimit(RLIMIT_FSIZE, &limit);
  }
  ~FileSizeLimit() {
    setrlimit(RLIMIT_FSIZE, &old_);
    std::signal(SIGXFSZ, old_handler_);
  }

 private:
  rlimit old_{};
  void (*old_handler_)(int) = nullptr;
};

// Runs `write`, which must throw std::runtime_error naming `target`.
template <typename Write>
void expect_failed_write(Write write, const std::string& target) {
  try {
    write();
    ADD_FAILURE() << "the write of '" << target << "' did not fail";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("'" + target + "'"), std::string::npos) << e.what();
  }
}

TEST_F(AtomicFile, WritesAndReplacesLeavingNoTemporary) {
  const std::string target = path("a.json");
  write_text_file_atomically(target, "first\n");
  EXPECT_EQ(read(target), "first\n");
  write_text_file_atomically(target, "second, longer\n");
  EXPECT_EQ(read(target), "second, longer\n");
  EXPECT_EQ(listing(), "a.json ");
  // A missing folder is an error naming the target (callers create folders they mean to).
  expect_failed_write([&] { write_text_file_atomically(path("sub/b.json"), "x"); }, path("sub/b.json"));
  EXPECT_FALSE(fs::exists(path("sub")));
}

TEST_F(AtomicFile, AWriterThatThrowsLeavesTheOldFileAndNoTemporary) {
  const std::string target = path("a.json");
  write_text_file_atomically(target, "old content\n");
  expect_failed_write(
      [&] {
        write_file_atomically(target, [](const std::string& temporary) {
          std::ofstream(temporary) << "half";
          throw std::runtime_error("encoder failed");
        });
      },
      target);
  EXPECT_EQ(read(target), "old content\n");
  EXPECT_EQ(listing(), "a.json ");
}

TEST_F(AtomicFile, AFullDiskLeavesTheOldFileAndNoTemporary) {
  const std::string json = path("results.json"), exr = path("out.exr"), png = path("out.png");
  const std::string old_text(3000, 'o');
  write_text_file_atomically(json, old_text);
  const Image small = random_image(8, 8, 3, 0.0f, 1.0f, 1), big = random_image(96, 96, 3, 0.0f, 1.0f, 2);
  write_image(small, exr);
  write_image(small, png);
  const std::string old_exr = read(exr), old_png = read(png);
  {
    const FileSizeLimit limit(1024);
    expect_failed_write([&] { write_text_file_atomically(json, std::string(5000, 'n')); }, json);
    expect_failed_write([&] { write_image(big, exr); }, exr);
    // OpenImageIO's PNG writer ignores short writes: the bytes go through write_whole_file instead.
    expect_failed_write([&] { write_image(big, png); }, png);
    expect_failed_write([&] { write_display_image(big, png); }, png);
  }
  EXPECT_EQ(read(json), old_text);
  EXPECT_EQ(read(exr), old_exr);
  EXPECT_EQ(read(png), old_png);
  EXPECT_EQ(listing(), "out.exr out.png results.json ");
  // Without a file that existed before, nothing is left.
  {
    const FileSizeLimit limit(1024);
    expect_failed_write([&] { write_image(big, path("new.exr")); }, path("new.exr"));
  }
  EXPECT_FALSE(fs::exists(path("new.exr")));
}

TEST_F(AtomicFile, AReadOnlyFolderLeavesTheOldFile) {
  const std::string target = path("a.json");
  write_text_file_atomically(target, "old\n");
  fs::permissions(dir_, fs::perms::owner_read | fs::perms::owner_exec);
  if (::access(dir_.c_str(), W_OK) == 0)  // root ignores permissions (the CLI test uses a read-only mount)
    GTEST_SKIP() << "permissions do not stop this user (root): covered by tests/bench/write_faults_test.py";
  expect_failed_write([&] { write_text_file_atomically(target, "new\n"); }, target);
  expect_failed_write([&] { write_image(random_image(4, 4, 3, 0.0f, 1.0f, 3), path("b.exr")); }, path("b.exr"));
  fs::permissions(dir_, fs::perms::owner_all);
  EXPECT_EQ(read(target), "old\n");
  EXPECT_EQ(listing(), "a.json ");
}

TEST_F(AtomicFile, ATargetThatIsAnInputIsRefusedByAnyName) {
  const std::string input = path("color.exr"), link = path("link.exr");
  write_image(random_image(4, 4, 3, 0.0f, 1.0f, 4), input);
  const std::string before = read(input);
  fs::create_hard_link(input, link);
  EXPECT_THROW(refuse_input_as_output(link, {input}), std::runtime_error);
  EXPECT_NO_THROW(refuse_input_as_output(path("other.exr"), {input}));
  protect_inputs({input});
  try {
    write_image(random_image(4, 4, 3, 0.0f, 1.0f, 5), link);
    ADD_FAILURE() << "an input was overwritten";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("is the input '" + input + "'"), std::string::npos) << e.what();
  }
  EXPECT_EQ(read(input), before);
}

TEST_F(AtomicFile, StaleTemporariesOfDeadProcessesAreRemoved) {
  // PID 4194304 is above Linux's pid_max limit: never a running process.
  std::ofstream(path("r.json.tmp.4194304")) << "x";
  std::ofstream(path("r.json.tmp.4194304-2")) << "x";
  std::ofstream(path(fmt::format("r.json.tmp.{}", ::getpid()))) << "x";  // this process: still running
  std::ofstream(path("r.json.tmp.notapid")) << "x";
  EXPECT_EQ(remove_stale_temporaries(dir_.string()), 2);
  EXPECT_TRUE(fs::exists(path(fmt::format("r.json.tmp.{}", ::getpid()))));
  EXPECT_TRUE(fs::exists(path("r.json.tmp.notapid")));
}

}  // namespace
}  // namespace bokeh
