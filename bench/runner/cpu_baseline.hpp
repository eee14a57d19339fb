#pragma once
// figure9's CPU baseline (issue 44): what an engine programmer would use on the CPU instead of a bokeh
// method, OpenCV's cv::filter2D with one fixed disc kernel, timed beside FLAG in the same rounds.
//
// It is no Method: it ignores the circle of confusion (every pixel gets the pattern's largest disc),
// so it has no error against the exact reference, no place in accuracy rankings and no conformance
// checks. The sweep measures it as a runner Target, like the calibration probes, and writes it apart
// from the methods' points (SweepSettings::baselines, a document's "baselines").
//
// OpenCV is optional (CMake option BOKEH_OPENCV, found when installed): a build without it reports the
// baseline skipped, "not built with OpenCV", and nothing fails.
#include <memory>
#include <string>
#include <vector>

#include "gather_pattern.hpp"
#include "image.hpp"
#include "runner.hpp"

namespace bokeh::baseline {

// The baseline's name in results ("baseline" of a baselines entry, the start of its id).
inline constexpr const char* kFilter2dName = "opencv_filter2d";

// Whether this binary was built with OpenCV, and its version ("4.6.0"; "" without).
bool built_with_opencv();
std::string opencv_version();
// Why the baseline cannot run in this build: "" when it can.
std::string unavailable_reason();

// The disc as one 2D kernel: the taps FLAG's gather takes at its largest radius, laid out densely.
// Side 2 n k + 1 px (n = (N - 1) / 2, k the spacing), row-major; 1 / area at each lattice offset
// (i k, j k), |i|, |j| <= n, inside the disc of radius n k (in_disc), area = their count
// (discrete_disc_area), 0 everywhere else. Symmetric, so correlation (filter2D) equals convolution.
int disc_kernel_side_px(const GatherPattern& pattern);
std::vector<float> disc_kernel(const GatherPattern& pattern);

// `color` (3 channels, f32) correlated with disc_kernel by cv::filter2D on `threads` threads
// (cv::setNumThreads). Border: BORDER_CONSTANT 0 with the weights left as they are, which is the
// exact reference's convention (exact_scatter.hpp: the share beyond the border is lost, nothing comes
// in from beyond it) and naive's and FLAG's. Throws std::runtime_error (unavailable_reason) without OpenCV.
Image filter2d_disc(const Image& color, const GatherPattern& pattern, int threads);

// filter2d_disc as the runner times it: wall clock of whole frames into one output kept between them.
// `color` must outlive the target (the sweep's scene cache holds it).
std::unique_ptr<runner::Target> filter2d_target(const Image& color, const GatherPattern& pattern, int threads);

}  // namespace bokeh::baseline
