#include "accuracy.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>

#include <fmt/format.h>

#include "coc.hpp"

namespace bokeh {

ExactReferences exact_references(const Scene& scene, const Lens& lens, float max_radius_px,
                                 ExactReferenceCache& cache) {
  const Image radius = coc_radius_image(scene.depth_m, lens, max_radius_px);
  const auto start = std::chrono::steady_clock::now();
  const float largest_radius_px = *std::max_element(radius.pixels.begin(), radius.pixels.end());
  const int threads = default_cpu_threads();
  ExactReferences refs{cache.get(scene.color, radius, scene.depth_m, ScatterComposite::energy_sum, threads, lens.aperture),
                       cache.get(scene.color, radius, scene.depth_m, ScatterComposite::depth_ordered, threads, lens.aperture),
                       static_cast<int>(std::ceil(largest_radius_px))};
  fmt::print("exact references for {}x{}, max radius {} px, aperture {}: {:.2f} s (cache: {})\n", scene.color.width,
             scene.color.height, max_radius_px, lens.aperture.name(),
             std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(),
             cache.directory().string());
  return refs;
}

nlohmann::json metrics_json(const ErrorMetrics& m) {
  auto finite_or_null = [](double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr); };
  return {{"rmse", finite_or_null(m.rmse)},
          {"psnr_db", finite_or_null(m.psnr_db)},
          {"max_abs_error", finite_or_null(m.max_abs_error)},
          {"mean_relative_energy_error", finite_or_null(m.mean_relative_energy_error)},
          {"ssim", finite_or_null(m.ssim)}};
}

std::size_t count_non_finite(const Image& image) {
  return static_cast<std::size_t>(
      std::count_if(image.pixels.begin(), image.pixels.end(), [](float v) { return !std::isfinite(v); }));
}

double psnr_for_ranking(const nlohmann::json& metrics) {
  const auto& psnr = metrics["psnr_db"];
  if (!psnr.is_null()) return psnr.get<double>();
  const bool exact = !metrics["rmse"].is_null() && metrics["rmse"].get<double>() == 0.0;
  return exact ? std::numeric_limits<double>::infinity() : -std::numeric_limits<double>::infinity();
}

std::string psnr_text(const nlohmann::json& metrics) {
  if (metrics.is_null()) return "-";  // no such reference for this point
  const double psnr = psnr_for_ranking(metrics);
  return std::isinf(psnr) ? (psnr > 0 ? "exact" : "n/a") : fmt::format("{:.2f} dB", psnr);
}

nlohmann::json error_json(const Image& result, const ExactReferences& references) {
  const std::size_t non_finite = count_non_finite(result);
  if (non_finite > 0)  // e.g. an HDR highlight overflowing a half-float buffer on a driver that rounds to inf
    fmt::print(stderr, "warning: the result has {} non-finite values (inf/NaN): its metrics are null\n", non_finite);
  return {{"vs_energy_sum", metrics_json(compare_images(result, references.energy_sum))},
          {"vs_depth_ordered", metrics_json(compare_images(result, references.depth_ordered))},
          {"non_finite_values", non_finite},
          {"interior_margin_px", references.interior_margin_px},
          {"vs_energy_sum_interior",
           metrics_json(compare_interior(result, references.energy_sum, references.interior_margin_px))},
          {"vs_depth_ordered_interior",
           metrics_json(compare_interior(result, references.depth_ordered, references.interior_margin_px))}};
}

}  // namespace bokeh
