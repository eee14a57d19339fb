#include "cpu_baseline.hpp"

#include <algorithm>
#include <chrono>
#include <stdexcept>

#include <fmt/format.h>

#if defined(BOKEH_HAVE_OPENCV)
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#endif

namespace bokeh::baseline {

bool built_with_opencv() {
#if defined(BOKEH_HAVE_OPENCV)
  return true;
#else
  return false;
#endif
}

std::string opencv_version() {
#if defined(BOKEH_HAVE_OPENCV)
  return CV_VERSION;
#else
  return "";
#endif
}

std::string unavailable_reason() {
  if (built_with_opencv()) return "";
  return "not built with OpenCV (install Debian's libopencv-imgproc-dev, which `bash .ci/setup` does, and "
         "reconfigure; CMake option BOKEH_OPENCV)";
}

int disc_kernel_side_px(const GatherPattern& pattern) { return 2 * pattern.half() * pattern.spacing_px + 1; }

std::vector<float> disc_kernel(const GatherPattern& pattern) {
  validate(pattern);
  const int n = pattern.half(), k = pattern.spacing_px, side_px = disc_kernel_side_px(pattern);
  const float radius_px = pattern.max_radius_px();
  const float weight = 1.0f / static_cast<float>(discrete_disc_area(radius_px, pattern));
  std::vector<float> kernel(static_cast<std::size_t>(side_px) * side_px, 0.0f);
  for (int j = -n; j <= n; ++j)
    for (int i = -n; i <= n; ++i)
      if (in_disc(radius_px * radius_px, i * k, j * k))
        kernel[static_cast<std::size_t>(j * k + n * k) * side_px + static_cast<std::size_t>(i * k + n * k)] = weight;
  return kernel;
}

namespace {

#if defined(BOKEH_HAVE_OPENCV)
void check_color(const Image& color) {
  if (color.channels != 3 || color.pixels.size() != color.pixel_count() * 3)
    throw std::invalid_argument(fmt::format("filter2D baseline: the colour image must have 3 channels, not {}", color.channels));
}

// OpenCV's thread count is process-wide: set it where it differs from what this call wants.
void use_threads(int threads) {
  if (cv::getNumThreads() != threads) cv::setNumThreads(threads);
}

// The image's pixels as an OpenCV matrix, without a copy (filter2D only reads its source).
cv::Mat view_of(const Image& color) {
  check_color(color);
  return cv::Mat(color.height, color.width, CV_32FC3, const_cast<float*>(color.pixels.data()));
}

// The baseline's one call: correlation with the kernel, border constant 0, weights as they are.
void filter(const cv::Mat& source, cv::Mat& output, const cv::Mat& kernel) {
  cv::filter2D(source, output, CV_32F, kernel, cv::Point(-1, -1), 0, cv::BORDER_CONSTANT);
}

class Filter2dTarget final : public runner::Target {
 public:
  Filter2dTarget(const Image& color, const GatherPattern& pattern, int threads)
      : source_(view_of(color)), kernel_values_(disc_kernel(pattern)), threads_(std::max(1, threads)) {
    const int side_px = disc_kernel_side_px(pattern);
    kernel_ = cv::Mat(side_px, side_px, CV_32F, kernel_values_.data());
  }
  void warm_up() override { frame(); }  // the first call allocates the output and plans its DFTs
  runner::Sample measure(int frames) override {
    const auto start = std::chrono::steady_clock::now();
    for (int f = 0; f < frames; ++f) frame();
    return {std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count() / frames, {}};
  }
  std::uint64_t resident_bytes() const override {
    return static_cast<std::uint64_t>(source_.total()) * source_.elemSize() + kernel_values_.size() * sizeof(float);
  }

 private:
  void frame() {
    use_threads(threads_);
    filter(source_, output_, kernel_);
  }

  cv::Mat source_, output_, kernel_;
  std::vector<float> kernel_values_;
  int threads_;
};
#endif

}  // namespace

Image filter2d_disc(const Image& color, const GatherPattern& pattern, int threads) {
#if defined(BOKEH_HAVE_OPENCV)
  use_threads(std::max(1, threads));
  std::vector<float> values = disc_kernel(pattern);
  const int side_px = disc_kernel_side_px(pattern);
  Image out(color.width, color.height, 3);
  cv::Mat dst(out.height, out.width, CV_32FC3, out.pixels.data());
  filter(view_of(color), dst, cv::Mat(side_px, side_px, CV_32F, values.data()));
  if (dst.data != reinterpret_cast<uchar*>(out.pixels.data()))
    throw std::logic_error("filter2D baseline: OpenCV reallocated the output");  // it writes into `out` in place
  return out;
#else
  (void)color, (void)pattern, (void)threads;
  throw std::runtime_error("filter2D baseline: " + unavailable_reason());
#endif
}

std::unique_ptr<runner::Target> filter2d_target(const Image& color, const GatherPattern& pattern, int threads) {
#if defined(BOKEH_HAVE_OPENCV)
  return std::make_unique<Filter2dTarget>(color, pattern, threads);
#else
  (void)color, (void)pattern, (void)threads;
  throw std::runtime_error(unavailable_reason());
#endif
}

}  // namespace bokeh::baseline
