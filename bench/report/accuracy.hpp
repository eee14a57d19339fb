#pragma once
// Accuracy next to every timing: a result's error against the exact scatter references of the
// same scene, lens and resolution (kernels/core/exact_scatter.hpp, cached on disk).
#include <nlohmann/json.hpp>

#include "exact_scatter.hpp"
#include "lens.hpp"
#include "metrics.hpp"
#include "scene.hpp"

namespace bokeh {

// energy_sum: every pixel spreads its colour uniformly over its disc (what naive and FLAG
// approximate; the headline metric). depth_ordered: the same discs composited front to back (what a
// camera would show, as far as one image allows).
// interior_margin_px: the largest CoC radius in the frame, rounded up; the interior metrics leave it
// out on every side (compare_interior, metrics.hpp).
struct ExactReferences {
  Image energy_sum;
  Image depth_ordered;
  int interior_margin_px = 0;
};

// The CoC radii are the ones every method sees: equation (1) clamped to max_radius_px.
ExactReferences exact_references(const Scene& scene, const Lens& lens, float max_radius_px,
                                 ExactReferenceCache& cache);

// {"vs_energy_sum": metrics, "vs_depth_ordered": metrics, "non_finite_values": count,
//  "interior_margin_px": margin, "vs_energy_sum_interior": metrics, "vs_depth_ordered_interior": metrics}:
// the whole image, then the interior (every metric null when the margin leaves nothing). JSON has no
// infinity or NaN: PSNR is null when the result is exact (RMSE 0), and every metric is null when the
// result holds inf/NaN (counted in non_finite_values, and warned about on stderr).
nlohmann::json error_json(const Image& result, const ExactReferences& references);
nlohmann::json metrics_json(const ErrorMetrics& m);
std::size_t count_non_finite(const Image& image);

// PSNR of a metrics_json object for ranking: +inf when exact (RMSE 0), -inf when the result was not
// finite (no usable metrics), else the value. psnr_text: "exact", "n/a" or "42.1 dB".
double psnr_for_ranking(const nlohmann::json& metrics);
std::string psnr_text(const nlohmann::json& metrics);

}  // namespace bokeh
