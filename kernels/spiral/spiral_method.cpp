// spiral: single-pass golden-angle spiral gather with the blog's fixed-weight blend (Godot 4's circle
// mode); see spiral.hpp.
#include <cstdint>
#include <vector>

#include <fmt/format.h>

#include "method.hpp"
#include "signed_coc.hpp"
#include "spiral.hpp"
#include "spiral_gpu.hpp"

namespace bokeh::methods {

namespace {

// The table is 32 bytes per sample; past this the spiral is not a real-time method any more.
constexpr std::int64_t kMaxSpiralSamples = std::int64_t{1} << 20;

// The method's options, parsed once per call (spiral_config).
struct SpiralConfig {
  double spacing_px = 0;     // spiral_spacing_px: the blog's RAD_SCALE
  double max_radius_px = 0;  // the pattern's k (N - 1) / 2: where the spiral ends
  float clamp_factor = 0;    // spiral_clamp_factor
  std::int64_t samples() const { return spiral_sample_count(spacing_px, max_radius_px); }
  std::vector<SpiralSample> spiral() const { return spiral_samples(spacing_px, max_radius_px); }
};

SpiralConfig spiral_config(const FilterOptions& o) {
  return {o.number("spiral_spacing_px"), o.pattern.max_radius_px(), static_cast<float>(o.number("spiral_clamp_factor"))};
}

}  // namespace

void declare_spiral(std::vector<Method>& methods) {
  Method m;
  m.name = "spiral";
  m.description = "single-pass golden-angle spiral gather to the largest CoC k(N-1)/2, fixed-weight blend with the "
                  "running average, background CoC clamp (blog 2018; Godot's circle bokeh)";
  m.precisions = {"f32"};
  m.samples_pattern = false;  // the spiral depends on the largest radius and its spacing only
  m.options = {
      {"spiral_spacing_px",
       "Spiral: the blog's RAD_SCALE (Godot's blur_scale) in px: the first radius, and each sample steps the radius "
       "by it / radius, so a CoC of R px takes ~R^2 / (2 x it) samples; smaller is smoother and slower. Godot's "
       "presets: 0.5 high, 1 medium, 4 low, 8 very low",
       1.0, 0.5, 16.0, false, {}, {0.5, 1.0, 4.0, 8.0}},
      {"spiral_clamp_factor",
       "Spiral: a sample behind the pixel blurs into it only as far as this x the pixel's own CoC (Godot and the "
       "blog: 2)",
       2.0, 1.0, 16.0}};
  m.unsupported = [](const FilterOptions& o, int, int) -> std::string {
    const SpiralConfig c = spiral_config(o);
    const std::int64_t n = c.samples();
    if (n > kMaxSpiralSamples)
      return fmt::format("the spiral to radius {} px at spacing {} px has {} samples, more than the {} allowed",
                         c.max_radius_px, c.spacing_px, n, kMaxSpiralSamples);
    return "";
  };
  m.cpu_reference = [](const CpuInput& in) {
    const SpiralConfig c = spiral_config(in.options);
    const Image input = signed_coc_image(in.color, in.radius_px, in.depth_m, static_cast<float>(in.lens.focus_distance_m));
    return spiral_blur(input, c.spiral(), c.clamp_factor, in.threads);
  };
  m.make_gpu = [](gpu::GpuFrame& frame, const FilterOptions& o) {
    const SpiralConfig c = spiral_config(o);
    return make_spiral_gpu(frame, c.spiral(), c.clamp_factor);
  };
  // prepare reads colour, depth and the packed CoC and writes RGBA; the spiral pass evaluates the
  // centre and every sample (each a bilinear fetch of four texels), reading the RGBA image and the table.
  m.work = [](const FilterOptions& o, int w, int h) {
    const double px = static_cast<double>(w) * h, n = static_cast<double>(spiral_config(o).samples());
    return std::vector<PassWork>{{"prepare", px, px * 36, px * 16},
                                 {"spiral", px * (n + 1), px * 16 + n * sizeof(SpiralSample), px * 16}};
  };
  m.gpu_memory = [](const FilterOptions& o, int w, int h, vk::Context*) {
    const std::int64_t samples = spiral_config(o).samples();
    MemoryUse use;
    const std::uint64_t image = static_cast<std::uint64_t>(w) * h * 16;
    const std::uint64_t table = std::max<std::uint64_t>(sizeof(SpiralSample), samples * sizeof(SpiralSample));
    use.bytes = image + table;
    use.details = {{"signed_coc_bytes", image}, {"spiral_table_bytes", table}, {"spiral_samples", samples}};
    return use;
  };
  m.cpu_memory_bytes = [](const FilterOptions& o, int w, int h) {
    return static_cast<std::uint64_t>(w) * h * 16 + spiral_config(o).samples() * sizeof(SpiralSample);
  };
  // The same table and the same float operations in the same order, none fused (`precise`); lavapipe
  // matches the CPU bit for bit (measured: 0). What Vulkan lets another GPU do differently: the CoC
  // pass's division (2.5 ulp). Every step is continuous in the CoC (smoothstep, slope 1.5 per px; the
  // clamp meets the unclamped size where the comparison flips) and the output is a convex blend of
  // input values, so this moves it by a few ulps of the largest value: 1e-5 as for the other f32 methods.
  m.gpu_tolerance = [](const FilterOptions&) { return 1e-5; };
  // f32 storage; radius 0 leaves every m = 0, and the running-average form then adds exact zeros.
  m.storage_tolerance = [](const FilterOptions&) { return 0.0; };
  m.conserves_energy = false;
  m.energy_note =
      "not conserved in general: at a constant CoC it is a normalised convolution (conserved away from the "
      "borders), but where samples stop contributing the blend keeps the running average, which weights a "
      "sample found after i others by 1 / (i + 2): a blurred foreground light over a sharp background gains energy";
  methods.push_back(std::move(m));
}

}  // namespace bokeh::methods
