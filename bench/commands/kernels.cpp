// `bokehbench kernels`: the circular separable kernels for 1..6 components (Niemitalo 2010, Garcia
// 2018): measured ripple next to the published figures, cost at a given disc radius (taps, passes,
// intermediate bytes per precision) and the radial profile, written to results/circular_kernels.json
// and plotted by plots/plot_circular_kernels.py.
#include <fmt/format.h>

#include "circular_coefficients.hpp"
#include "circular_separable.hpp"
#include "commands.hpp"
#include "report.hpp"

namespace bokeh {

namespace {

// Max pass/stop-band error as published (README "Circular separable filter coefficients").
constexpr double kPublishedRipple[kMaxCircularComponents] = {0.232, 0.076, 0.027, 0.011, 0.0041, 0.0020};

struct KernelsOptions {
  double radius_px = 40;
  std::string out_path = "results/circular_kernels.json", plots_dir = "plots";
  double profile_max_r = 2.0;  // radial profile samples cover r / disc radius in [0, this]
  int profile_samples = 801;
  bool plot = true;
};

nlohmann::json cost_json(int components, int kernel_radius_px, int channels) {
  nlohmann::json bytes = nlohmann::json::object();
  for (IntermediatePrecision p :
       {IntermediatePrecision::f32, IntermediatePrecision::f16, IntermediatePrecision::bracketed10})
    bytes[to_string(p)] = circular_cost(components, kernel_radius_px, p, channels).intermediate_bytes_per_pixel;
  return bytes;
}

void kernels(const KernelsOptions& o) {
  check_writable_file(o.out_path);
  if (o.plot) check_writable_dir(o.plots_dir);
  nlohmann::json entries = nlohmann::json::array();
  fmt::print("circular separable kernels, disc radius {} px\n", o.radius_px);
  fmt::print("{:>5} {:>10} {:>10} {:>10} {:>8} {:>10} {:>22}\n", "comp", "passband", "stopband", "published", "R px",
             "taps/px", "bytes/px f32/f16/b10");
  for (int n = 1; n <= kMaxCircularComponents; ++n) {
    const RippleReport ripple = measure_ripple(n);  // 8001 samples over u in [0, 4]
    const double max_u = o.profile_max_r * kDiscEdgeU;
    const RippleReport profile = measure_ripple(n, kPassbandEndU, kStopbandStartU, max_u, o.profile_samples);
    const CircularKernel kernel = make_circular_kernel_for_disc(n, o.radius_px);
    const CircularCost cost = circular_cost(n, kernel.radius_px, IntermediatePrecision::f32);
    nlohmann::json r_over_disc = nlohmann::json::array(), k_values = nlohmann::json::array();
    for (const auto& [r, k] : profile.profile) r_over_disc.push_back(r), k_values.push_back(k);
    const nlohmann::json rgb = cost_json(n, kernel.radius_px, 3), rgba = cost_json(n, kernel.radius_px, 4);
    entries.push_back(
        {{"components", n},
         {"coefficients", [&] {
            nlohmann::json rows = nlohmann::json::array();
            for (const CircularComponent& c : circular_components(n))
              rows.push_back({{"a", c.a}, {"b", c.b}, {"A", c.A}, {"B", c.B}});
            return rows;
          }()},
         {"scale_s", circular_scale(n)},
         {"max_ripple_passband", ripple.max_ripple_passband},
         {"max_ripple_stopband", ripple.max_ripple_stopband},
         {"published_max_ripple", kPublishedRipple[n - 1]},
         {"kernel_radius_px", kernel.radius_px},
         {"taps_per_kernel_axis", kernel.tap_count()},
         {"taps_per_pixel", cost.taps_per_pixel},
         {"passes", cost.passes},
         {"intermediate_bytes_per_pixel", {{"rgb", rgb}, {"rgba", rgba}}},
         {"profile", {{"r_over_disc_radius", r_over_disc}, {"K", k_values}}}});
    fmt::print("{:>5} {:>10.4f} {:>10.4f} {:>10.4f} {:>8} {:>10} {:>10}/{}/{}\n", n, ripple.max_ripple_passband,
               ripple.max_ripple_stopband, kPublishedRipple[n - 1], kernel.radius_px, cost.taps_per_pixel,
               rgb["f32"].get<long>(), rgb["f16"].get<long>(), rgb["bracketed10"].get<long>());
  }
  write_results(
      o.out_path, "bokehbench.circular_kernels", run_context(nullptr),
      {{"config",
        {{"disc_radius_px", o.radius_px},
         {"passband_end_u", kPassbandEndU},
         {"stopband_start_u", kStopbandStartU},
         {"disc_edge_u", kDiscEdgeU},
         {"ripple",
          "measured on the continuous radial profile K(u) = sum_c exp(-a u^2) (A cos(b u^2) + B sin(b u^2)), 8001 "
          "samples over u in [0, 4]: passband max |K - 1| for u <= 1, stopband max |K| for u >= 1.2"},
         {"profile", "K at r / disc radius = u / 1.1, the height-1 disc normalisation of the published tables"},
         {"cost",
          "at the given disc radius: kernel radius R = ceil(s * disc / 1.1); taps_per_pixel = 2 C (2R + 1) complex "
          "multiply-adds per channel over both passes; passes: horizontal + vertical per convolution (the GPU filter "
          "runs one convolution each for the near and the far layer, plus a layer-split pass); "
          "intermediate_bytes_per_pixel: circular_cost for 3 (rgb) and 4 (rgba, what the GPU layers carry) channels"}}},
       {"kernels", entries}});
  fmt::print("wrote {}\n", o.out_path);
  if (o.plot) run_plot_script("plot_circular_kernels.py", o.out_path, o.plots_dir + "/circular_kernels");
}

}  // namespace

void add_kernels_command(CLI::App& app) {
  auto o = std::make_shared<KernelsOptions>();
  auto* cmd = app.add_subcommand("kernels", "Circular separable kernels (1..6 components): ripple, cost, radial profile");
  cmd->add_option("--radius", o->radius_px, "Disc radius in px for the cost figures")->check(CLI::Range(1.0, 1000.0));
  cmd->add_option("--out", o->out_path, "Results JSON");
  cmd->add_option("--plots-dir", o->plots_dir, "Where circular_kernels.png and .svg go");
  cmd->add_flag("!--no-plot", o->plot, "Skip the plot");
  cmd->callback([o] { kernels(*o); });
}

}  // namespace bokeh
