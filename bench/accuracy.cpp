#include "accuracy.hpp"

#include <chrono>
#include <cmath>

#include <fmt/format.h>

#include "coc.hpp"

namespace bokeh {

ExactReferences exact_references(const Scene& scene, const Lens& lens, float max_radius_px,
                                 ExactReferenceCache& cache) {
  const Image radius = coc_radius_image(scene.depth_m, lens, max_radius_px);
  const auto start = std::chrono::steady_clock::now();
  ExactReferences refs{cache.get(scene.color, radius, scene.depth_m, ScatterComposite::energy_sum),
                       cache.get(scene.color, radius, scene.depth_m, ScatterComposite::depth_ordered)};
  fmt::print("exact references for {}x{}, max radius {} px: {:.2f} s (cache: {})\n", scene.color.width,
             scene.color.height, max_radius_px,
             std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(),
             cache.directory().string());
  return refs;
}

nlohmann::json metrics_json(const ErrorMetrics& m) {
  auto finite_or_null = [](double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr); };
  return {{"rmse", m.rmse},
          {"psnr_db", finite_or_null(m.psnr_db)},
          {"max_abs_error", m.max_abs_error},
          {"mean_relative_energy_error", finite_or_null(m.mean_relative_energy_error)},
          {"ssim", m.ssim}};
}

nlohmann::json error_json(const Image& result, const ExactReferences& references) {
  return {{"vs_energy_sum", metrics_json(compare_images(result, references.energy_sum))},
          {"vs_depth_ordered", metrics_json(compare_images(result, references.depth_ordered))}};
}

}  // namespace bokeh
