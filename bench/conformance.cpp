#include "conformance.hpp"

#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>

#include "coc.hpp"
#include "run.hpp"
#include "scene.hpp"

namespace bokeh::conformance {

namespace {

// The lens carries the aperture the method is asked to draw (run_cpu and run_gpu refuse a mismatch).
Lens with_aperture(Lens lens, const FilterOptions& options) {
  lens.aperture = options.aperture;
  return lens;
}

}  // namespace

const char* to_string(Backend backend) { return backend == Backend::gpu ? "GPU" : "CPU"; }

double max_abs(const Image& image) {
  double m = 0;
  for (float v : image.pixels) m = std::max(m, double(std::abs(v)));
  return m;
}

double max_abs_diff(const Image& a, const Image& b) {
  if (!a.same_shape(b)) throw std::invalid_argument("max_abs_diff: the images' shapes differ");
  double m = 0.0;
  for (std::size_t i = 0; i < a.pixels.size(); ++i) {
    const double diff = std::abs(double(a.pixels[i]) - b.pixels[i]);
    if (std::isnan(diff)) return diff;  // std::max would drop it, and a NaN output would look exact
    m = std::max(m, diff);
  }
  return m;
}

double rgb_sum(const Image& image) {
  double s = 0.0;
  for (std::size_t p = 0; p < image.pixel_count(); ++p)
    for (int c = 0; c < 3; ++c) s += image.pixels[p * image.channels + c];
  return s;
}

Image random_image_in_black_border(int w, int h, int margin, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(0.0f, 4.0f);
  Image img(w, h, 3);
  for (float& v : img.pixels) v = u(rng);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      if (x < margin || y < margin || x >= w - margin || y >= h - margin)
        for (int c = 0; c < 3; ++c) img.px(x, y)[c] = 0.0f;
  return img;
}

Image run(Backend backend, vk::Context* ctx, const Method& method, const Image& color, const Image& depth_m,
          const Lens& lens, const FilterOptions& options, std::vector<vk::PassTime>* passes) {
  if (backend == Backend::cpu) return run_cpu(method, color, depth_m, lens, options, 2);
  if (!ctx) throw std::logic_error("conformance::run: the GPU backend needs a Vulkan context");
  return run_gpu(*ctx, method, color, depth_m, lens, options, passes);
}

Measure identity_at_radius_zero(Backend backend, vk::Context* ctx, const Method& method, const FilterOptions& options) {
  Scene s = make_scene("pillars", 64, 48);
  s.lens.f_stop = 1e12;  // a pinhole: every radius 0
  s.lens.aperture = options.aperture;
  const double largest = max_abs(s.color);
  const Image out = run(backend, ctx, method, s.color, s.depth_m, s.lens, options);
  return {max_abs_diff(out, s.color), method.storage_tolerance(options) * largest + 1e-6 * largest};
}

Measure uniform_stays_uniform(Backend backend, vk::Context* ctx, const Method& method, const FilterOptions& options) {
  const int w = 80, h = 64, margin = 2 * static_cast<int>(options.pattern.max_radius_px()) + 2;
  Image color(w, h, 3);
  for (std::size_t p = 0; p < color.pixel_count(); ++p)
    for (int ch = 0; ch < 3; ++ch) color.pixels[p * 3 + ch] = 1.0f + ch;
  const Image depth(w, h, 1, 10.0f);
  const Lens lens = with_aperture(with_max_coc_radius(Lens{}, depth, options.pattern.max_radius_px() * 2), options);
  const Image out = run(backend, ctx, method, color, depth, lens, options);
  double worst = 0;
  for (int y = margin; y < h - margin; ++y)
    for (int x = margin; x < w - margin; ++x)
      for (int ch = 0; ch < 3; ++ch) {
        const double diff = std::abs(double(out.px(x, y)[ch]) - (1.0 + ch));
        if (std::isnan(diff)) return {diff, (method.storage_tolerance(options) + 1e-5) * max_abs(color)};
        worst = std::max(worst, diff);
      }
  return {worst, (method.storage_tolerance(options) + 1e-5) * max_abs(color)};
}

Measure energy_conserved(Backend backend, vk::Context* ctx, const Method& method, const FilterOptions& options) {
  // Every pixel behind the focus at the largest radius; light only inside a margin of twice it.
  const int w = 80, h = 64, margin = 2 * static_cast<int>(options.pattern.max_radius_px()) + 2;
  const Image color = random_image_in_black_border(w, h, margin, 7);
  const Image depth(w, h, 1, 10.0f);
  const Lens lens = with_aperture(with_max_coc_radius(Lens{}, depth, options.pattern.max_radius_px() * 2), options);
  const double in = rgb_sum(color);
  const double bound =
      method.storage_tolerance(options) * max_abs(color) * static_cast<double>(color.pixels.size()) / in + 1e-5;
  const Image out = run(backend, ctx, method, color, depth, lens, options);
  return {std::abs(rgb_sum(out) / in - 1.0), bound};
}

Measure gpu_matches_cpu(vk::Context& ctx, const Method& method, const FilterOptions& options, const std::string& scene,
                        std::vector<vk::PassTime>* passes, bool* finite) {
  const Scene s = make_scene(scene, 63, 46);
  // 1.2x: some pixels clamp at the largest radius, the rest spread below it.
  const Lens lens = with_aperture(with_max_coc_radius(s.lens, s.depth_m, options.pattern.max_radius_px() * 1.2), options);
  const Image cpu = run_cpu(method, s.color, s.depth_m, lens, options, 2);
  const Image gpu = run_gpu(ctx, method, s.color, s.depth_m, lens, options, passes);
  if (finite) *finite = std::all_of(gpu.pixels.begin(), gpu.pixels.end(), [](float v) { return std::isfinite(v); });
  return {max_abs_diff(gpu, cpu) / max_abs(cpu), method.gpu_tolerance(options)};
}

}  // namespace bokeh::conformance
