#pragma once
// Each bokehbench subcommand registers itself on the CLI11 app; main() only dispatches.
#include <stdexcept>
#include <string>
#include <utility>

#include <CLI/CLI.hpp>

namespace bokeh {

// "AxB" with two positive integers (a resolution WIDTHxHEIGHT, a pattern NxK). Throws
// std::invalid_argument naming `what` and showing `example` for anything else.
inline std::pair<int, int> parse_int_pair(const std::string& text, const std::string& what, const std::string& example) {
  const auto bad = [&] { return std::invalid_argument(what + " '" + text + "' is not of the form " + example); };
  const auto x = text.find('x');
  if (x == std::string::npos) throw bad();
  auto number = [&](const std::string& part) {
    if (part.empty() || part.size() > 6 || part.find_first_not_of("0123456789") != std::string::npos) throw bad();
    return std::stoi(part);
  };
  return {number(text.substr(0, x)), number(text.substr(x + 1))};
}

void add_devices_command(CLI::App& app);
void add_render_command(CLI::App& app);
void add_memory_command(CLI::App& app);
void add_buffers_command(CLI::App& app);
void add_figure9_command(CLI::App& app);
void add_kernels_command(CLI::App& app);
void add_tradeoff_command(CLI::App& app);

}  // namespace bokeh
