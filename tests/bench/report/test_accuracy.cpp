// Errors next to timings: exact results, non-finite results, and how they rank.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include <fmt/format.h>

#include "accuracy.hpp"

namespace bokeh {
namespace {

ExactReferences flat_references(float value) {
  return {Image(6, 4, 3, value), Image(6, 4, 3, value), 1};
}

// The interior blocks sit beside the whole-image ones: an error on the border shows only in the latter.
TEST(Accuracy, InteriorMetricsLeaveTheBorderOut) {
  Image result(6, 4, 3, 2.0f);
  result.px(0, 2)[1] = 3.0f;  // on the left edge
  const nlohmann::json e = error_json(result, flat_references(2.0f));
  EXPECT_EQ(e["interior_margin_px"], 1);
  EXPECT_GT(e["vs_energy_sum"]["rmse"].get<double>(), 0.0);
  EXPECT_EQ(e["vs_energy_sum_interior"]["rmse"].get<double>(), 0.0);
  EXPECT_EQ(psnr_text(e["vs_depth_ordered_interior"]), "exact");
}

TEST(Accuracy, ExactResultRanksAboveEverything) {
  const nlohmann::json e = error_json(Image(6, 4, 3, 2.0f), flat_references(2.0f));
  EXPECT_EQ(e["non_finite_values"], 0);
  EXPECT_TRUE(e["vs_energy_sum"]["psnr_db"].is_null());
  EXPECT_EQ(e["vs_energy_sum"]["rmse"].get<double>(), 0.0);
  EXPECT_EQ(psnr_for_ranking(e["vs_energy_sum"]), std::numeric_limits<double>::infinity());
  EXPECT_EQ(psnr_text(e["vs_energy_sum"]), "exact");
}

TEST(Accuracy, FiniteErrorHasItsPsnr) {
  Image result(6, 4, 3, 2.0f);
  result.px(0, 0)[0] = 3.0f;  // one value off by 1 of 72: RMSE = sqrt(1/72), peak 2
  const nlohmann::json e = error_json(result, flat_references(2.0f));
  const double expected = 20.0 * std::log10(2.0 / std::sqrt(1.0 / 72.0));
  EXPECT_NEAR(psnr_for_ranking(e["vs_energy_sum"]), expected, 1e-9);
  EXPECT_EQ(psnr_text(e["vs_energy_sum"]), fmt::format("{:.2f} dB", expected));
}

// A result holding inf or NaN (e.g. a half-float overflow on some drivers) has no meaningful metric:
// every metric is null, the count says why, and it ranks below every finite result.
TEST(Accuracy, NonFiniteResultIsFlaggedAndRanksLast) {
  Image result(6, 4, 3, 2.0f);
  result.px(1, 1)[2] = std::numeric_limits<float>::infinity();
  result.px(2, 1)[0] = std::numeric_limits<float>::quiet_NaN();
  const nlohmann::json e = error_json(result, flat_references(2.0f));
  EXPECT_EQ(e["non_finite_values"], 2);
  for (const char* key : {"rmse", "psnr_db", "max_abs_error"})
    EXPECT_TRUE(e["vs_energy_sum"][key].is_null()) << key;
  EXPECT_EQ(psnr_for_ranking(e["vs_energy_sum"]), -std::numeric_limits<double>::infinity());
  EXPECT_EQ(psnr_text(e["vs_energy_sum"]), "n/a");
  EXPECT_EQ(e.dump().find("nan"), std::string::npos);
}

}  // namespace
}  // namespace bokeh
