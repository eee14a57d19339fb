// circular1 .. circular6: Garcia's circular separable convolution depth of field (GDC 2018) with
// 1 to 6 complex components, near/far split, intermediates in f32, f16 or bracketed 10-bit.
#include <algorithm>
#include <cmath>
#include <complex>
#include <limits>
#include <stdexcept>
#include <string>

#include <fmt/format.h>

#include "circular_config.hpp"
#include "circular_gpu.hpp"
#include "circular_separable.hpp"
#include "coc_tiles_gpu.hpp"
#include "method.hpp"

namespace bokeh::methods {

namespace {

std::string m_name(int components) { return "circular" + std::to_string(components); }

// Both kernels blur a disc of the pattern's max radius k (N - 1) / 2: the circular filters take
// their (fixed) kernel from the same gather-size axis as naive and FLAG, so a sweep compares them at
// the same largest CoC; the per-pixel CoC enters through the near/far alpha w = radius / max radius.
float disc_radius_px(const CircularFilterConfig& c) { return std::max(1.0f, static_cast<float>(c.max_radius_px)); }

int tap_radius(int components, const CircularFilterConfig& c) {
  return make_circular_kernel_for_disc(components, disc_radius_px(c)).radius_px;
}

int bucket_count(const CircularFilterConfig& c) { return circular_buckets(disc_radius_px(c)).count(); }

// The kernels one field convolves with: the max radius's (adaptive off), or every bucket's (on).
std::vector<CircularKernel> field_kernels(int components, const CircularFilterConfig& c) {
  const float disc = disc_radius_px(c);
  if (!c.adaptive) return {make_circular_kernel_for_disc(components, disc)};
  std::vector<CircularKernel> kernels;
  for (float rho : circular_buckets(disc).disc_radius_px)
    kernels.push_back(make_circular_kernel_for_disc(components, rho));
  return kernels;
}

// Tiles of the radius-following mode's lists (kTilePx squares).
double tile_count(int w, int h) {
  return std::ceil(static_cast<double>(w) / kTilePx) * std::ceil(static_cast<double>(h) / kTilePx);
}

// Radius-following: every bucket of both fields on every tile (the model cannot see the scene; a
// frame runs the buckets its pixels touch on the tiles they reach: its stats list them, with the
// taps they cost, far below this bound when the scene spans few radii or little area).
//   layers: as off, plus the per-tile bucket masks (a word per subgroup);
//   tiles:  the masks spread along rows and columns, and the lists (a word per tile and list);
//   far, near: per bucket, the horizontal pass (layer in, intermediates out) and the vertical pass
//           (intermediates in, the field's sum read and written); the sum zeroed first; the
//           composite reads colour, both layers and the sum and writes (near: reads too) the output.
std::vector<PassWork> adaptive_work(const CircularFilterConfig& config, int w, int h) {
  const double px = static_cast<double>(w) * h, tiles = tile_count(w, h);
  const double component = static_cast<double>(circular_component_bytes_per_pixel(config.precision));
  const double box = config.precision == IntermediatePrecision::bracketed10 ? 8 : 0;
  const int buckets = bucket_count(config);
  std::vector<PassWork> work = {{"layers", px, px * 36, px * 32},
                                {"tiles", 0, tiles * 2 * 4 * 2, tiles * 2 * 4 * (1 + 2.0 * buckets)}};
  for (const auto& [field, c] : {std::pair<std::string, int>{"far", config.far_components},
                                 {"near", config.near_components}}) {
    PassWork pass{field, 0, px * (16 * 4 + (field == "near" ? 16 : 0)), px * (16 + 16)};
    for (const CircularKernel& k : field_kernels(c, config)) {
      pass.taps += 2 * px * c * (2.0 * k.radius_px + 1);
      pass.bytes_read += px * (16 + c * component + box + 16);
      pass.bytes_written += px * (c * component + box + 16);
    }
    work.push_back(pass);
  }
  return work;
}

// Both fields as if present (the model cannot see the scene): an empty field's passes do no work
// on either backend (its horizontal and, near, vertical pass dispatch nothing on the GPU; the far
// vertical pass then only composites).
std::vector<PassWork> circular_work(const CircularFilterConfig& config, int w, int h) {
  if (config.adaptive) return adaptive_work(config, w, h);
  const double px = static_cast<double>(w) * h;
  const double component = static_cast<double>(circular_component_bytes_per_pixel(config.precision));
  const double box = config.precision == IntermediatePrecision::bracketed10 ? 8 : 0;
  // layers: colour, depth, packed input -> both layers (the channel maxima and dispatch sizes are
  // a few bytes).
  std::vector<PassWork> work = {{"layers", px, px * 36, px * 32}};
  for (const auto& [field, c] : {std::pair<std::string, int>{"far", config.far_components},
                                 {"near", config.near_components}}) {
    const double taps = px * c * (2.0 * tap_radius(c, config) + 1);  // complex RGBA multiply-adds
    work.push_back({field + "_horizontal", taps, px * 16, px * (c * component + box)});
    // Reads the intermediates and the colour and its own layer's alpha (far) or the far result
    // (near); writes the output.
    const double composite_in = field == "far" ? 32 : 16;
    work.push_back({field + "_vertical", taps, px * (c * component + box + composite_in), px * 16});
  }
  return work;
}

// The GPU filter's intermediates: component buffers, near/far layers, box sums, kernels' uniform
// buffers and (adaptive) the tile lists; throws when a kernel exceeds the device's uniform range.
MemoryUse circular_gpu_memory(int components, const FilterOptions& o, int w, int h, vk::Context* ctx) {
  const CircularFilterConfig config = circular_config(o, components);
  const auto px = static_cast<std::uint64_t>(w) * h;
  const int near = config.near_components;
  // Every kernel (one a field, or one a bucket and field) has its uniform buffer.
  std::uint64_t kernels = 0, largest = 0;
  for (int c : {components, near})
    for (const CircularKernel& k : field_kernels(c, config)) {
      kernels += circular_kernel_block_bytes(k);
      largest = std::max(largest, circular_kernel_block_bytes(k));
    }
  // The kernels live in uniform buffers: say so before allocating when the device's are too small.
  if (ctx && largest > ctx->info().max_uniform_buffer_range_bytes)
    throw std::runtime_error(fmt::format("{}: a kernel of {} bytes exceeds {}'s maxUniformBufferRange of {} bytes "
                                         "(a smaller max radius or fewer components fits)",
                                         m_name(components), largest, ctx->info().name,
                                         ctx->info().max_uniform_buffer_range_bytes));
  const std::uint64_t inter =
      std::max(components, near) * px * circular_component_bytes_per_pixel(config.precision);
  const std::uint64_t layers = 2 * px * 16;
  const std::uint64_t box = config.precision == IntermediatePrecision::bracketed10 ? px * 8 : 0;
  MemoryUse use;
  use.bytes = inter + layers + box + kernels;
  use.details = {{"component_buffers_bytes", inter},
                 {"near_far_layers_bytes", layers},
                 {"box_sum_bytes", box},
                 {"kernel_bytes", kernels}};
  if (config.adaptive) {
    // The field's sum (RGBA f32), the bucket table, and the tiles: list counts and two masks per
    // field and tile, and one list per bucket, field and pass (tiles.glsl).
    const auto tiles = static_cast<std::uint64_t>(tile_count(w, h));
    const int buckets = bucket_count(config);
    const std::uint64_t sum = px * 16, table = kCircularBucketTableBytes;
    const std::uint64_t tile_bytes =
        4 * (4 * 32 + 4 * tiles) + 4 * (64 + 2 * static_cast<std::uint64_t>(buckets)) * tiles;
    use.bytes += sum + table + tile_bytes;
    use.details["field_sum_bytes"] = sum;
    use.details["bucket_table_bytes"] = table;
    use.details["tile_bytes"] = tile_bytes;
  }
  return use;
}

Method circular_method(int components) {
  Method m;
  m.name = m_name(components);
  m.description = std::to_string(components) +
                  "-component circular separable convolution (Garcia 2018): complex-Gaussian horizontal + vertical "
                  "passes on near/far layers, fixed disc of radius k(N-1)/2 (adaptive on: a disc of each pixel's "
                  "own CoC, from kernels 1.5 px apart)";
  m.precisions = {"f32", "f16", "bracketed10"};
  m.samples_pattern = false;
  m.in_default_sweeps = components <= 2;  // 3..6 refine the same algorithm: run them by name
  OptionSpec adaptive = adaptive_option(
      "Circular filters: off blurs every pixel with one disc of the max radius, blended by CoC; on spreads each "
      "pixel over a disc of its own CoC (kernels for radius ranges, Garcia's proposal)");
  adaptive.tradeoff = {0, 1};  // `tradeoff` runs both
  m.options = {{"near_components",
                "Circular filters: near-field components (default: the method's own count; circular2 with 1 is "
                "Garcia's production choice)",
                static_cast<double>(components), 1, kMaxCircularComponents, true},
               adaptive};
  m.device = [](const FilterOptions&) {
    vk::DeviceRequirements needs;
    needs.subgroup_operations = VK_SUBGROUP_FEATURE_ARITHMETIC_BIT;  // the layers pass reduces channel maxima with subgroupMax
    return needs;
  };
  // Every function below parses the options once (circular_config) and reads only the config.
  m.unsupported = [components](const FilterOptions& o, int w, int h) -> std::string {
    const CircularFilterConfig c = circular_config(o, components);
    if (c.max_radius_px < 1) return "circular filters need a max radius k (N - 1) / 2 >= 1 px";
    // A bucket's pass dispatches one workgroup column per listed tile: at most every tile, which
    // must stay within the 65535 workgroups every device accepts along x (8192 x 8192 does not).
    if (c.adaptive && tile_count(w, h) > 65535)
      return fmt::format("adaptive on lists up to {} tiles of {} px a pass, over the 65535 workgroups a dispatch may "
                         "count (an image up to about 8000 x 8000 fits)",
                         tile_count(w, h), kTilePx);
    return "";
  };
  m.cpu_reference = [components](const CpuInput& in) {
    const CircularFilterConfig config = circular_config(in.options, components);
    if (!config.adaptive)
      return circular_blur(in.color, in.radius_px, in.depth_m, in.lens.focus_distance_m, config, in.threads);
    AdaptiveWork work;
    Image out = circular_blur_adaptive(in.color, in.radius_px, in.depth_m, in.lens.focus_distance_m, config,
                                       in.threads, in.stats ? &work : nullptr);
    if (in.stats) *in.stats = bucket_stats(circular_buckets(config.max_radius_px), work);
    return out;
  };
  m.make_gpu = [components](gpu::GpuFrame& frame, const FilterOptions& o) {
    return make_circular_gpu(frame, o, components);
  };
  m.work = [components](const FilterOptions& o, int w, int h) {
    return circular_work(circular_config(o, components), w, h);
  };
  m.gpu_memory = [components](const FilterOptions& o, int w, int h, vk::Context* ctx) {
    return circular_gpu_memory(components, o, w, h, ctx);
  };
  // The near and far RGBA layers, one convolution's intermediates (real and imaginary planes of 4
  // channels per component, held as f32 at every precision) and its blurred RGBA output; near and far
  // convolve one after the other.
  // Radius-following adds the two fields' sums and the bucket's layer (RGBA f32 each, a bucket's
  // window at most the frame).
  m.cpu_memory_bytes = [components](const FilterOptions& o, int w, int h) {
    const CircularFilterConfig config = circular_config(o, components);
    const auto px = static_cast<std::uint64_t>(w) * h;
    const std::uint64_t fixed = 2 * px * 4 * sizeof(float) +
                                std::max(components, config.near_components) * px * 8 * sizeof(float) +
                                px * 4 * sizeof(float);
    return fixed + (config.adaptive ? 3 * px * 4 * sizeof(float) : 0);
  };
  // Same taps, weights and order as the CPU, so f32 differs by rounding only (measured 1.4e-6 at 6
  // components); stored f16 or 10-bit parts may round the other way on the GPU (Vulkan allows either):
  // two units of the storage bound (circular_storage_bound, relative to the largest value).
  // Radius-following: a pixel's field sum gathers every bucket whose kernel reaches it, each
  // rounded in storage as above (relative to the field's maxima: rgb <= the largest value, alpha 1),
  // so the bound sums over the buckets (the larger field's); the composite divides the sum by its
  // alpha, about 1 inside a field, which at most doubles it (numerator and denominator both off):
  // 1e-5 + 2 sum_k storage_k. Where a field's coverage is small (an isolated pixel, down to 1e-4) the
  // division amplifies more, as it does for off; tests/kernels/circular/test_gpu_circular.cpp measures both.
  // Measured on lavapipe: <= 3e-7 of the largest value at every precision (it rounds like the CPU).
  auto storage = [](const CircularFilterConfig& config, double units) {
    double bound = 0;
    for (int c : {config.far_components, config.near_components}) {
      double field = 0;
      for (const CircularKernel& k : field_kernels(c, config))
        field += circular_storage_bound(k, config.precision, units);
      bound = std::max(bound, field);
    }
    return bound;
  };
  // f32: rounding alone, but the GPU may round or contract differently, and the tap sums amplify it as
  // they do f16's: the f16 model at f32's unit (2^-24 against 2^-11). fully_defocused with adaptive on
  // measured 1.1e-5 at 6 components (hoops: 1.4e-6), over a flat 1e-5.
  m.gpu_tolerance = [components, storage](const FilterOptions& o) {
    CircularFilterConfig config = circular_config(o, components);
    const double fields = config.adaptive ? 2 : 1;
    if (config.precision != IntermediatePrecision::f32) return 1e-5 + fields * storage(config, 2);
    config.precision = IntermediatePrecision::f16;
    return 1e-5 + fields * storage(config, 2) * std::ldexp(1.0, -13);
  };
  m.storage_tolerance = [components, storage](const FilterOptions& o) {
    return storage(circular_config(o, components), 1);
  };
  // The horizontal pass stores sum_i tap_i J (complex) per component: |Re|, |Im| <= S J with
  // S = max_c sum_i (|Re tap_i| + |Im tap_i|) (about the tap count: S grows with the radius). f16
  // intermediates overflow at 65504 / S; f32 and bracketed10 (whose vertical pass rebuilds I in f32)
  // at f32's largest value over the vertical pass's second sum, 2 S^2.
  m.input_limit = [components](const FilterOptions& o) {
    const CircularFilterConfig config = circular_config(o, components);
    const double disc = disc_radius_px(config);
    double s = 0;
    for (int c : {components, config.near_components})
      for (const auto& taps : make_circular_kernel_for_disc(c, disc).taps) {
        double sum = 0;
        for (std::complex<float> t : taps) sum += std::abs(t.real()) + std::abs(t.imag());
        s = std::max(s, sum);
      }
    if (config.precision == IntermediatePrecision::f16) return 65504.0 / s;
    return static_cast<double>(std::numeric_limits<float>::max()) / (2 * s * s);
  };
  m.energy_note = "the kernels sum to one; a constant-radius image is one convolution";
  return m;
}

}  // namespace

void declare_circular(std::vector<Method>& methods) {
  for (int c = 1; c <= kMaxCircularComponents; ++c) methods.push_back(circular_method(c));
}

}  // namespace bokeh::methods
