#pragma once
// Each bokehbench subcommand registers itself on the CLI11 app; main() only dispatches.
#include <CLI/CLI.hpp>

namespace bokeh {

void add_devices_command(CLI::App& app);
void add_render_command(CLI::App& app);
void add_memory_command(CLI::App& app);
void add_buffers_command(CLI::App& app);
void add_figure9_command(CLI::App& app);
void add_kernels_command(CLI::App& app);
void add_tradeoff_command(CLI::App& app);

}  // namespace bokeh
