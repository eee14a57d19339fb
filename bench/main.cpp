// bokehbench: benchmarks and checks bokeh depth-of-field filters (see README.md).
#include <cerrno>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <new>

#include <fmt/format.h>

#include "commands.hpp"
#include "package.hpp"
#include "report.hpp"
#include "vk/handle.hpp"

namespace {

// The exit status states what the output says: output that could not be written (a full disk, a closed
// pipe, stdout redirected to /dev/full) lost its last lines, the verdict among them, so the run fails.
int with_output_written(int code) {
  if (std::fflush(stdout) == 0 && !std::ferror(stdout)) return code;
  if (code != 0) return code;  // already a failure (or a verdict other than 0), reported on stderr
  const int error = errno;
  fmt::print(stderr, "bokehbench: error: cannot write standard output ({}): its last lines are lost\n",
             error != 0 ? std::strerror(error) : "a write failed");
  return 1;
}

// Method packages named anywhere on the command line are loaded (and their shaders compiled) before
// the CLI is built, so their own options become flags and a bad package fails before any work.
void load_packages(int argc, char** argv) {
  for (int i = 1; i < argc; ++i) {
    std::string word = argv[i];
    if (word.rfind("--", 0) == 0 && word.find('=') != std::string::npos) word = word.substr(word.find('=') + 1);
    if (bokeh::is_package_reference(word)) bokeh::load_package(word);
  }
}

int run(int argc, char** argv) {
  bokeh::set_command_line(argc, argv);
  try {
    load_packages(argc, argv);
  } catch (const std::exception& e) {
    fmt::print(stderr, "bokehbench: error: {}\n", e.what());
    return 1;
  }
  CLI::App app{"bokehbench: cost, memory and accuracy of bokeh depth-of-field filters"};
  app.require_subcommand(1);
  bokeh::add_figure9_command(app);
  bokeh::add_kernels_command(app);
  bokeh::add_tradeoff_command(app);
  bokeh::add_memory_command(app);
  bokeh::add_buffers_command(app);
  bokeh::add_adaptive_command(app);
  bokeh::add_render_command(app);
  bokeh::add_stability_command(app);
  bokeh::add_devices_command(app);
  bokeh::add_methods_command(app);
  bokeh::add_compare_command(app);
  bokeh::add_selftest_compare_command(app);
  bokeh::add_ab_command(app);
  bokeh::add_history_command(app);
  bokeh::add_report_command(app);
  bokeh::add_merge_command(app);
  bokeh::add_check_command(app);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  } catch (const bokeh::ExitStatus& status) {
    return status.code;
  } catch (const std::bad_alloc&) {
    fmt::print(stderr, "bokehbench: error: out of host memory (std::bad_alloc): this configuration needs more memory "
                       "than the machine has; lower the resolution or gather size\n");
    return 1;
  } catch (const std::exception& e) {
    fmt::print(stderr, "bokehbench: error: {}\n", e.what());
    return 1;
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  const int status = with_output_written(run(argc, argv));
  // A runaway GPU submission still runs on the device's threads: a normal exit would join them
  // (Mesa's teardown) and never return. Everything finished is written by now.
  if (bokeh::vk::device_abandoned()) {
    std::fflush(nullptr);
    std::_Exit(status);
  }
  return status;
}
