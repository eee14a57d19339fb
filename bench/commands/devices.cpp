// `bokehbench devices` and `bokehbench methods`: what there is to choose from (--device, --method).
#include <fmt/format.h>
#include <fmt/ranges.h>

#include "commands.hpp"
#include "method.hpp"
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

void add_methods_command(CLI::App& app) {
  auto* cmd = app.add_subcommand("methods", "List the registered methods (and the method packages named: PACKAGE...): "
                                             "precisions, buffer scales and their own options");
  // Packages named here were loaded before parsing (main.cpp); the words only need accepting.
  static std::vector<std::string> packages;
  cmd->add_option("packages", packages, "Method package folders to list beside the built-ins");
  cmd->callback([] {
    for (const Method* method : known_methods()) {
      const Method& m = *method;
      fmt::print("{}{}: {}\n", m.name, m.in_default_sweeps ? "" : " (not in default sweeps: name it)", m.description);
      if (!m.package.is_null())
        fmt::print("    method package {} (content hash {})\n", m.package["path"].get<std::string>(),
                   m.package["hash"].get<std::string>());
      fmt::print("    precisions {} (default first), buffer scales {}\n", fmt::join(m.precisions, ", "),
                 fmt::join(m.buffer_scales, ", "));
      for (const OptionSpec& spec : m.options) {
        const std::string values = spec.choices.empty()
                                       ? fmt::format("{} .. {}", spec.min, spec.max)
                                       : fmt::format("{}", fmt::join(spec.choices, " | "));
        fmt::print("    {} {} (default {})\n", spec.flag(), values, spec.to_json(spec.default_value).dump());
      }
      // What it draws (Method::aperture_unsupported), probed at its defaults on a few apertures.
      std::vector<std::string> draws;
      std::string first_refusal;
      for (const char* shape : {"disc", "blades5", "blades6", "blades6-rot30", "blades7-curv0.5"}) {
        FilterOptions o = m.defaults({41, 2});
        o.aperture = parse_aperture(shape);
        if (const std::string why = aperture_unsupported(m, o); why.empty()) draws.push_back(shape);
        else if (first_refusal.empty()) first_refusal = why;
      }
      fmt::print("    apertures at its defaults: {}{}\n", fmt::join(draws, ", "),
                 first_refusal.empty() ? "" : " (not the others: " + first_refusal + ")");
    }
  });
}

}  // namespace bokeh
