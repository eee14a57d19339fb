// What both image back-ends share (the back-end itself: image_io_oiio.cpp or image_io_lean.cpp).
#include "image_io.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <stdexcept>

#include <fmt/format.h>

#include "atomic_file.hpp"
#include "image_backend.hpp"

namespace bokeh {

namespace image_backend {

std::string lower_extension(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  return ext;
}

}  // namespace image_backend

namespace {

void check_writable_shape(const Image& image, const std::string& path) {
  // Checked before any back-end opens the file (OpenImageIO would leave it empty).
  if (image_backend::lower_extension(path) == ".png" && image.channels > 4)
    throw std::invalid_argument(
        fmt::format("cannot write image '{}': PNG holds 1 to 4 channels, not {}", path, image.channels));
  if (image.width < 1 || image.height < 1 || image.channels < 1)
    throw std::invalid_argument(fmt::format("cannot write image '{}': it is empty ({}x{} pixels, {} channels)", path,
                                            image.width, image.height, image.channels));
  if (image.pixels.size() != image.pixel_count() * static_cast<std::size_t>(image.channels))
    throw std::invalid_argument(fmt::format("cannot write image '{}': {} values for {}x{} pixels of {} channels", path,
                                            image.pixels.size(), image.width, image.height, image.channels));
}

// encoded_channels: how many leading channels go through encode_srgb (the rest, alpha, are stored as is).
std::vector<std::uint8_t> to_8bit(const Image& image, int encoded_channels) {
  std::vector<std::uint8_t> bytes(image.pixels.size());
  for (std::size_t i = 0; i < bytes.size(); ++i) {
    const float v = image.pixels[i];
    const bool encode = static_cast<int>(i % static_cast<std::size_t>(image.channels)) < encoded_channels;
    bytes[i] = quantize_unit_to_8bit(encode ? static_cast<float>(encode_srgb(v)) : v);
  }
  return bytes;
}

}  // namespace

ImageFileInfo read_image_info(const std::string& path) { return image_backend::read_info(path); }

void check_image_extension(const std::string& path) {
  const std::string ext = image_backend::lower_extension(path);
  if (ext != ".exr" && ext != ".png")
    throw std::invalid_argument(
        fmt::format("output '{}': the extension must be .exr (linear float) or .png (tone-mapped 8-bit sRGB), not '{}'",
                    path, ext.empty() ? "(none)" : ext));
}

Image read_image(const std::string& path, int channels, const std::string& what, bool float_only) {
  if (float_only) {
    const ImageFileInfo info = read_image_info(path);
    if (!info.is_float)
      throw std::runtime_error(fmt::format(
          "{} file '{}' stores {} values, not floats: {} must be float (e.g. EXR half or float), since integer "
          "pixels would be read as fractions 0..1",
          what, path, info.pixel_type, what));
  }
  Image all = image_backend::read(path, what);
  if (all.channels < channels)
    throw std::runtime_error(fmt::format("{} '{}' has {} channels, need {}", what, path, all.channels, channels));
  if (all.channels == channels) return all;
  Image img(all.width, all.height, channels);
  for (std::size_t p = 0; p < img.pixel_count(); ++p)
    std::copy_n(all.pixels.begin() + static_cast<std::ptrdiff_t>(p * all.channels), channels,
                img.pixels.begin() + static_cast<std::ptrdiff_t>(p * channels));
  return img;
}

Image tone_map_for_display(const Image& linear) {
  Image out = linear;
  for (std::size_t p = 0; p < linear.pixel_count(); ++p) {
    float* c = out.pixels.data() + p * out.channels;
    const int rgb = std::min(3, out.channels);
    float lum = 0.0f;
    const float weights[3] = {0.2126f, 0.7152f, 0.0722f};
    for (int k = 0; k < rgb; ++k) lum += (rgb == 3 ? weights[k] : 1.0f / rgb) * std::max(c[k], 0.0f);
    const float scale = lum > 0.0f ? 1.0f / (1.0f + lum) : 1.0f;
    for (int k = 0; k < rgb; ++k) c[k] = std::clamp(c[k] * scale, 0.0f, 1.0f);
  }
  return out;
}

double encode_srgb(double linear) {
  return linear <= 0.0031308 ? 12.92 * linear : 1.055 * std::pow(linear, 1.0 / 2.4) - 0.055;
}

unsigned char quantize_unit_to_8bit(float value) {
  const float unit = value > 0.0f ? std::min(value, 1.0f) : 0.0f;  // NaN fails the test: 0
  return static_cast<unsigned char>(unit * 255.0f + 0.5f);
}

void write_image(const Image& image, const std::string& path, const ExrAttributes& exr_attributes) {
  check_image_extension(path);
  check_writable_shape(image, path);
  const std::string ext = image_backend::lower_extension(path);
  if (ext == ".exr") {
    write_file_atomically(
        path, [&](const std::string& file) { image_backend::write_exr_float(image, file, exr_attributes); }, "image");
    return;
  }
  if (!exr_attributes.empty())
    throw std::invalid_argument(fmt::format("cannot write image '{}': header attributes need .exr", path));
  // Colour channels are encoded; a fourth (alpha) is stored as is, as OpenImageIO's colour conversion did.
  const std::vector<std::uint8_t> bytes = to_8bit(tone_map_for_display(image), std::min(3, image.channels));
  write_file_atomically(
      path,
      [&](const std::string& file) {
        image_backend::write_8bit(bytes, image.width, image.height, image.channels, file, ext, /*srgb_tagged=*/true);
      },
      "image");
}

void write_display_image(const Image& display_srgb, const std::string& path) {
  check_writable_shape(display_srgb, path);
  const std::string ext = image_backend::lower_extension(path);
  if (ext == ".exr") {
    write_file_atomically(
        path, [&](const std::string& file) { image_backend::write_exr_float(display_srgb, file, {}); }, "image");
    return;
  }
  const std::vector<std::uint8_t> bytes = to_8bit(display_srgb, 0);
  write_file_atomically(
      path,
      [&](const std::string& file) {
        image_backend::write_8bit(bytes, display_srgb.width, display_srgb.height, display_srgb.channels, file, ext,
                                  /*srgb_tagged=*/false);
      },
      "image");
}

std::string read_image_attribute(const std::string& path, const std::string& name) {
  return image_backend::read_exr_string_attribute(path, name);
}

bool draw_text(Image& rgb, int x_px, int baseline_y_px, const std::string& text, int size_px,
               const std::array<float, 3>& colour) {
  if (rgb.channels != 3 || rgb.pixels.size() != rgb.pixel_count() * 3)
    throw std::invalid_argument(fmt::format("draw_text: the image has {} channels, need 3", rgb.channels));
  return image_backend::draw_text(rgb, x_px, baseline_y_px, text, size_px, colour);
}

ImageIoBackend image_io_backend() { return image_backend::describe(); }

}  // namespace bokeh
