// hexagon: the two-pass, three-rhombus hexagonal bokeh (Need for Speed: The Run); see hexagon.hpp.
#include <cmath>
#include <limits>

#include "hexagon.hpp"
#include "hexagon_gpu.hpp"
#include "method.hpp"
#include "signed_coc.hpp"

namespace bokeh::methods {

namespace {

// The blurs reach the pattern's largest CoC k (N - 1) / 2, in whole pixels (the soft edge gives a
// CoC r weight up to t < r + 1, so an integer largest radius needs no further tap).
int taps_of(const FilterOptions& o) { return static_cast<int>(o.pattern.max_radius_px()); }
// The blur directions: the aperture's rotation (the disc: the hexagon at rotation 0).
HexagonDirections directions_of(const FilterOptions& o) { return hexagon_directions(o.aperture.rotation_deg); }

}  // namespace

void declare_hexagon(std::vector<Method>& methods) {
  Method m;
  m.name = "hexagon";
  m.description = "two-pass hexagonal blur, two outputs, three rhombi (Need for Speed: The Run, SIGGRAPH 2011), "
                  "per-pixel CoC to k(N-1)/2 with the write-up's near/far rule and soft edge";
  m.precisions = {"f32"};
  m.samples_pattern = false;  // the blurs depend on the largest radius only
  // Its rhombi tile a hexagon of circumradius r with vertices straight up and down (hexagon.hpp): the
  // aperture blades6 with straight blades, at rotation 0 or, turning the three directions with it, any
  // other (hexagon_directions). The disc stays accepted as before, approximated by the hexagon at 0 and
  // scored against the disc, so the sweeps over the disc keep it; blades6 scores it against its own
  // shape (issue 23).
  m.aperture_unsupported = [](const FilterOptions& o) -> std::string {
    const Aperture& a = o.aperture;
    if (a.is_disc() || (a.blades == 6 && a.curvature == 0)) return "";
    return "hexagon draws a hexagon (blades6 at any rotation, straight blades), not the aperture " + a.name();
  };
  m.cpu_reference = [](const CpuInput& in) {
    const Image input = signed_coc_image(in.color, in.radius_px, in.depth_m, static_cast<float>(in.lens.focus_distance_m));
    return hexagon_blur(input, taps_of(in.options), in.threads, directions_of(in.options));
  };
  m.make_gpu = [](gpu::GpuFrame& frame, const FilterOptions& o) {
    return make_hexagon_gpu(frame, taps_of(o), directions_of(o));
  };
  // Per pixel: pass 1 evaluates T + 1 samples up (one texel each) and T + 1 down-left (bilinear, four
  // texels); pass 2 T + 1 down-left and T + 1 down-right (bilinear), and reads the pixel's own CoC.
  // Taps count samples (a bilinear one as one), as the other methods count theirs.
  m.work = [](const FilterOptions& o, int w, int h) {
    const double px = static_cast<double>(w) * h, taps = 2.0 * (taps_of(o) + 1);
    return std::vector<PassWork>{{"prepare", px, px * 36, px * 16},
                                 {"up_and_downleft", px * taps, px * 16, px * 32},
                                 {"rhombi", px * taps, px * 48, px * 16}};
  };
  m.gpu_memory = [](const FilterOptions&, int w, int h, vk::Context*) {
    MemoryUse use;
    const std::uint64_t image = static_cast<std::uint64_t>(w) * h * 16;
    use.bytes = 3 * image;
    use.details = {{"signed_coc_bytes", image}, {"pass1_outputs_bytes", 2 * image}};
    return use;
  };
  m.cpu_memory_bytes = [](const FilterOptions&, int w, int h) {
    return static_cast<std::uint64_t>(w) * h * (16 + 2 * 16);  // signed CoC + the two RGBA outputs of pass 1
  };
  // The same float operations in the same order, none fused (`precise`); lavapipe matches the CPU bit
  // for bit (measured: 0). What Vulkan lets another GPU do differently: the CoC pass's division and the
  // blurs' divisions (by extent, and the CoC means) to within 2.5 ulp. Every weight is continuous in
  // the CoCs with slope at most 2 per px, and the result is a sum of non-negative terms of at most the
  // largest value, so these move it by a few ulps of that value: 1e-5 as for the other f32 methods.
  m.gpu_tolerance = [](const FilterOptions&) { return 1e-5; };
  // f32 storage; radius 0: every weight but the pixel's own is 0 and the mean form is exact.
  m.storage_tolerance = [](const FilterOptions&) { return 0.0; };
  // Pass 1 adds two blurs before halving them ((up + down-left) * 0.5) and pass 2 sums three rhombi:
  // in f32 a value above a quarter of the largest float overflows there (3e38 in focus gave NaN).
  m.input_limit = [](const FilterOptions&) { return static_cast<double>(std::numeric_limits<float>::max()) / 4; };
  m.energy_note = "each texel's light is spread over its own CoC's extent with weights summing to one, in each "
                  "pass; the near/far rule drops what it deems hidden (a background behind a sharper foreground) "
                  "and fills a blurred pixel's hidden share with the mean of what it sees";
  methods.push_back(std::move(m));
}

}  // namespace bokeh::methods
