#include "image_io.hpp"

#include <algorithm>
#include <stdexcept>

#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/imageio.h>
#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imagebufalgo.h>
#include <fmt/format.h>

namespace bokeh {

ImageFileInfo read_image_info(const std::string& path) {
  auto input = OIIO::ImageInput::open(path);
  if (!input) throw std::runtime_error(fmt::format("cannot read image '{}': {}", path, OIIO::geterror()));
  const OIIO::ImageSpec& spec = input->spec();
  ImageFileInfo info;
  info.width = spec.width;
  info.height = spec.height;
  info.channels = spec.nchannels;
  info.pixel_type = spec.format.c_str();
  info.is_float = spec.format.is_floating_point();
  return info;
}

void check_image_extension(const std::string& path) {
  const std::string ext = OIIO::Strutil::lower(OIIO::Filesystem::extension(path));
  if (ext != ".exr" && ext != ".png")
    throw std::invalid_argument(fmt::format(
        "output '{}': the extension must be .exr (linear float) or .png (tone-mapped 8-bit sRGB), not '{}'", path,
        ext.empty() ? "(none)" : ext));
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
  OIIO::ImageBuf buf(path);
  if (!buf.read(0, 0, true, OIIO::TypeDesc::FLOAT))
    throw std::runtime_error(fmt::format("cannot read {} '{}': {}", what, path, buf.geterror()));
  const auto& spec = buf.spec();
  if (spec.nchannels < channels)
    throw std::runtime_error(fmt::format("{} '{}' has {} channels, need {}", what, path, spec.nchannels, channels));
  Image img(spec.width, spec.height, channels);
  OIIO::ROI roi(spec.x, spec.x + spec.width, spec.y, spec.y + spec.height, 0, 1, 0, channels);
  if (!buf.get_pixels(roi, OIIO::TypeDesc::FLOAT, img.pixels.data()))
    throw std::runtime_error(fmt::format("cannot read pixels of '{}': {}", path, buf.geterror()));
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

void write_image(const Image& image, const std::string& path) {
  check_image_extension(path);
  const bool linear_file = OIIO::Strutil::lower(OIIO::Filesystem::extension(path)) == ".exr";
  const Image& src = linear_file ? image : tone_map_for_display(image);
  OIIO::ImageSpec spec(src.width, src.height, src.channels, OIIO::TypeDesc::FLOAT);
  OIIO::ImageBuf buf(spec, const_cast<float*>(src.pixels.data()));
  OIIO::ImageBuf to_write = buf;
  if (!linear_file) {
    if (!OIIO::ImageBufAlgo::colorconvert(to_write, buf, "linear", "sRGB"))
      throw std::runtime_error(fmt::format("colour conversion for '{}' failed: {}", path, OIIO::geterror()));
    to_write.set_write_format(OIIO::TypeDesc::UINT8);
  } else {
    to_write.set_write_format(OIIO::TypeDesc::FLOAT);
  }
  if (!to_write.write(path)) {
    const std::string why = to_write.geterror();
    throw std::runtime_error(fmt::format("cannot write image '{}': {}", path, why.empty() ? OIIO::geterror() : why));
  }
}

}  // namespace bokeh
