#pragma once
// How far a filter's output is from the exact reference, and pictures that show where.
#include <string>
#include <utility>
#include <vector>

#include "image.hpp"
#include "image_io.hpp"  // write_display_image, for the display images below

namespace bokeh {

// All sums run in double over every pixel and the first three (RGB, linear) channels; both images need
// the same width, height and channel count (>= 3), else std::invalid_argument. N = 3 * pixels.
//   rmse          = sqrt( sum (result - reference)^2 / N ).
//   psnr_db       = 20 log10(peak / rmse), peak = the reference's largest RGB value (HDR has no fixed
//                   white; this makes PSNR relative to the brightest thing in the frame), or 1 when that
//                   is <= 0. rmse == 0 gives +infinity (never NaN); JSON writers print it as "inf".
//   max_abs_error = max |result - reference|.
//   mean_relative_energy_error = |sum(result) - sum(reference)| / |sum(reference)|: energy a filter
//                   gains or loses overall; 0 when both sums are 0, +infinity when only the reference's is.
//   ssim          = SSIM (Wang et al. 2004) of the luminances Y = 0.2126 R + 0.7152 G + 0.0722 B of
//                   tone_map_for_display(result) and tone_map_for_display(reference) (values in [0,1],
//                   so C1 = 0.01^2, C2 = 0.03^2): 11x11 Gaussian window, sigma 1.5, normalised; means,
//                   variances and covariance are window-weighted (population form); the mean over every
//                   window lying wholly inside the image. Images narrower or shorter than 11 px use the
//                   largest odd window that fits (down to 1x1, renormalised), so tiny tests stay defined.
struct ErrorMetrics {
  double rmse = 0.0;
  double psnr_db = 0.0;
  double max_abs_error = 0.0;
  double mean_relative_energy_error = 0.0;
  double ssim = 0.0;
};

ErrorMetrics compare_images(const Image& result, const Image& reference);

// compare_images over the interior: both images cropped by margin_px on every side (the peak is the
// cropped reference's). With margin_px = the largest CoC radius, no pixel there receives light from
// beyond the border, so a result's error there is its own, not the border convention's (README,
// Accuracy). Every metric is NaN when nothing is left (2 margin_px >= width or height).
ErrorMetrics compare_interior(const Image& result, const Image& reference, int margin_px);

// Display images below hold sRGB-encoded values in [0,1], ready to store as 8 bit without further
// transforms (write_image would tone-map them again, so use write_display_image, image_io.hpp).

// tone_map_for_display followed by the sRGB transfer function: what write_image puts in a PNG.
Image to_display_srgb(const Image& linear);

// |Y(result) - Y(reference)| per pixel on linear luminance, divided by the 99th percentile of that
// error (the maximum if the percentile is 0) and clamped to [0,1], through the viridis colour ramp
// (dark purple = no error, yellow = at or above the scale). 3 channels, display-encoded.
Image error_heat_map(const Image& result, const Image& reference);

// Panels (display-encoded, 1 or 3 channels, any sizes) left to right, top-aligned, 8 px apart on a dark
// grey sheet. Non-empty labels are drawn above their panel (draw_text: OpenImageIO's text renderer, DejaVu
// Sans); where no font can be found, and always with the lean image back-end (BOKEH_IMAGE_IO=lean), the
// label strip stays blank.
Image contact_sheet(const std::vector<std::pair<std::string, Image>>& panels);

}  // namespace bokeh
