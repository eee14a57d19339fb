// `bokehbench devices`: what the Vulkan loader sees, in `--device` order, and the default choice.
#include <fmt/format.h>

#include "commands.hpp"
#include "vk/context.hpp"

namespace bokeh {

void add_devices_command(CLI::App& app) {
  auto* cmd = app.add_subcommand("devices", "List Vulkan devices (the index or a name part is what --device takes)");
  cmd->callback([] {
    const auto devices = vk::list_devices();
    const vk::Context chosen;
    fmt::print("{:>5}  {:<40} {:<11} {:<12} {}\n", "index", "name", "type", "driver", "driver info");
    for (const auto& d : devices)
      fmt::print("{:>5}  {:<40} {:<11} {:<12} {}{}\n", d.index, d.name, d.type, d.driver_name, d.driver_info,
                 d.index == chosen.info().index ? "  (default)" : "");
  });
}

}  // namespace bokeh
