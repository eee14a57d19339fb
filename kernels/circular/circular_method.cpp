// circular1 .. circular6: Garcia's circular separable convolution depth of field (GDC 2018) with
// 1 to 6 complex components, near/far split, intermediates in f32, f16 or bracketed 10-bit.
#include <algorithm>
#include <complex>
#include <limits>
#include <stdexcept>
#include <string>

#include <fmt/format.h>

#include "circular_gpu.hpp"
#include "circular_separable.hpp"
#include "method.hpp"

namespace bokeh::methods {

namespace {

std::string m_name(int components) { return "circular" + std::to_string(components); }

// Both kernels blur a disc of the pattern's max radius k (N - 1) / 2: the circular filters take
// their (fixed) kernel from the same gather-size axis as naive and FLAG, so a sweep compares them at
// the same largest CoC; the per-pixel CoC enters through the near/far alpha w = radius / max radius.
int tap_radius(int components, const FilterOptions& o) {
  return make_circular_kernel_for_disc(components, std::max(1.0f, o.pattern.max_radius_px())).radius_px;
}

// Both fields as if present (the model cannot see the scene): an empty field's passes do no work
// on either backend (its horizontal and, near, vertical pass dispatch nothing on the GPU; the far
// vertical pass then only composites).
std::vector<PassWork> circular_work(int far, const FilterOptions& o, int w, int h) {
  const double px = static_cast<double>(w) * h;
  const IntermediatePrecision precision = intermediate_precision_from_string(o.precision);
  const double component = static_cast<double>(circular_component_bytes_per_pixel(precision));
  const double box = precision == IntermediatePrecision::bracketed10 ? 8 : 0;
  // layers: colour, depth, packed input -> both layers (the channel maxima and dispatch sizes are
  // a few bytes).
  std::vector<PassWork> work = {{"layers", px, px * 36, px * 32}};
  for (const auto& [field, c] : {std::pair<std::string, int>{"far", far}, {"near", o.integer("near_components")}}) {
    const double taps = px * c * (2.0 * tap_radius(c, o) + 1);  // complex RGBA multiply-adds
    work.push_back({field + "_horizontal", taps, px * 16, px * (c * component + box)});
    // Reads the intermediates and the colour and its own layer's alpha (far) or the far result
    // (near); writes the output.
    const double composite_in = field == "far" ? 32 : 16;
    work.push_back({field + "_vertical", taps, px * (c * component + box + composite_in), px * 16});
  }
  return work;
}

Method circular_method(int components) {
  Method m;
  m.name = m_name(components);
  m.description = std::to_string(components) +
                  "-component circular separable convolution (Garcia 2018): complex-Gaussian horizontal + vertical "
                  "passes on near/far layers, fixed disc of radius k(N-1)/2";
  m.precisions = {"f32", "f16", "bracketed10"};
  m.samples_pattern = false;
  m.in_default_sweeps = components <= 2;  // 3..6 refine the same algorithm: run them by name
  m.options = {{"near_components",
                "Circular filters: near-field components (default: the method's own count; circular2 with 1 is "
                "Garcia's production choice)",
                static_cast<double>(components), 1, kMaxCircularComponents, true}};
  m.device = [](const FilterOptions&) {
    vk::DeviceRequirements needs;
    needs.subgroup_arithmetic = true;  // the layers pass reduces channel maxima with subgroupMax
    return needs;
  };
  m.unsupported = [](const FilterOptions& o, int, int) -> std::string {
    if (o.pattern.max_radius_px() < 1.0f) return "circular filters need a max radius k (N - 1) / 2 >= 1 px";
    return "";
  };
  m.cpu_reference = [components](const CpuInput& in) {
    CircularFilterConfig config;
    config.far_components = components;
    config.near_components = in.options.integer("near_components");
    config.max_radius_px = static_cast<int>(in.options.pattern.max_radius_px());
    config.precision = intermediate_precision_from_string(in.options.precision);
    return circular_blur(in.color, in.radius_px, in.depth_m, in.lens.focus_distance_m, config, in.threads);
  };
  m.make_gpu = [components](gpu::GpuFrame& frame, const FilterOptions& o) {
    return make_circular_gpu(frame, o, components);
  };
  m.work = [components](const FilterOptions& o, int w, int h) { return circular_work(components, o, w, h); };
  m.gpu_memory = [components](const FilterOptions& o, int w, int h, vk::Context* ctx) {
    const auto px = static_cast<std::uint64_t>(w) * h;
    const IntermediatePrecision precision = intermediate_precision_from_string(o.precision);
    const int near = o.integer("near_components");
    const float disc = std::max(1.0f, o.pattern.max_radius_px());
    const std::uint64_t far_kernel = circular_kernel_block_bytes(make_circular_kernel_for_disc(components, disc));
    const std::uint64_t near_kernel = circular_kernel_block_bytes(make_circular_kernel_for_disc(near, disc));
    // The kernels live in uniform buffers: say so before allocating when the device's are too small.
    if (ctx && std::max(far_kernel, near_kernel) > ctx->info().max_uniform_buffer_range_bytes)
      throw std::runtime_error(fmt::format("{}: a kernel of {} bytes exceeds {}'s maxUniformBufferRange of {} bytes "
                                           "(a smaller max radius or fewer components fits)",
                                           m_name(components), std::max(far_kernel, near_kernel), ctx->info().name,
                                           ctx->info().max_uniform_buffer_range_bytes));
    const std::uint64_t inter = std::max(components, near) * px * circular_component_bytes_per_pixel(precision);
    const std::uint64_t layers = 2 * px * 16, box = precision == IntermediatePrecision::bracketed10 ? px * 8 : 0;
    MemoryUse use;
    use.bytes = inter + layers + box + far_kernel + near_kernel;
    use.details = {{"component_buffers_bytes", inter},
                   {"near_far_layers_bytes", layers},
                   {"box_sum_bytes", box},
                   {"kernel_bytes", far_kernel + near_kernel}};
    return use;
  };
  // The near and far RGBA layers, one convolution's intermediates (real and imaginary planes of 4
  // channels per component, held as f32 at every precision) and its blurred RGBA output; near and far
  // convolve one after the other.
  m.cpu_memory_bytes = [components](const FilterOptions& o, int w, int h) {
    const auto px = static_cast<std::uint64_t>(w) * h;
    return 2 * px * 4 * sizeof(float) + std::max(components, o.integer("near_components")) * px * 8 * sizeof(float) +
           px * 4 * sizeof(float);
  };
  // Same taps, weights and order as the CPU, so f32 differs by rounding only (measured 1.4e-6 at 6
  // components); stored f16 or 10-bit parts may round the other way on the GPU (Vulkan allows either):
  // two units of the storage bound (circular_storage_bound, relative to the largest value).
  auto storage = [components](const FilterOptions& o, double units) {
    const IntermediatePrecision p = intermediate_precision_from_string(o.precision);
    const double disc = std::max(1.0f, o.pattern.max_radius_px());
    return std::max(circular_storage_bound(make_circular_kernel_for_disc(components, disc), p, units),
                    circular_storage_bound(make_circular_kernel_for_disc(o.integer("near_components"), disc), p, units));
  };
  m.gpu_tolerance = [storage](const FilterOptions& o) { return 1e-5 + storage(o, 2); };
  m.storage_tolerance = [storage](const FilterOptions& o) { return storage(o, 1); };
  // The horizontal pass stores sum_i tap_i J (complex) per component: |Re|, |Im| <= S J with
  // S = max_c sum_i (|Re tap_i| + |Im tap_i|) (about the tap count: S grows with the radius). f16
  // intermediates overflow at 65504 / S; f32 and bracketed10 (whose vertical pass rebuilds I in f32)
  // at f32's largest value over the vertical pass's second sum, 2 S^2.
  m.input_limit = [components](const FilterOptions& o) {
    const double disc = std::max(1.0f, o.pattern.max_radius_px());
    double s = 0;
    for (int c : {components, o.integer("near_components")})
      for (const auto& taps : make_circular_kernel_for_disc(c, disc).taps) {
        double sum = 0;
        for (std::complex<float> t : taps) sum += std::abs(t.real()) + std::abs(t.imag());
        s = std::max(s, sum);
      }
    if (intermediate_precision_from_string(o.precision) == IntermediatePrecision::f16) return 65504.0 / s;
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
