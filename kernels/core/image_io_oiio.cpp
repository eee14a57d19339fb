// The OpenImageIO back-end (BOKEH_IMAGE_IO=oiio, the default): reads every format OpenImageIO knows,
// writes EXR and PNG (write_display_image: any 8-bit format), and draws text with its font renderer.
#include <stdexcept>

#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/imagebufalgo.h>
#include <OpenImageIO/imageio.h>
#include <fmt/format.h>

#include "image_backend.hpp"

namespace bokeh::image_backend {

ImageFileInfo read_info(const std::string& path) {
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

Image read(const std::string& path, const std::string& what) {
  OIIO::ImageBuf buf(path);
  if (!buf.read(0, 0, true, OIIO::TypeDesc::FLOAT))
    throw std::runtime_error(fmt::format("cannot read {} '{}': {}", what, path, buf.geterror()));
  const auto& spec = buf.spec();
  // OpenImageIO 2.4 reads a deep file into a deep buffer, whose get_pixels crashes.
  if (spec.deep) throw std::runtime_error(fmt::format("cannot read {} '{}': {}", what, path, kDeepPixels));
  Image img(spec.width, spec.height, spec.nchannels);
  OIIO::ROI roi(spec.x, spec.x + spec.width, spec.y, spec.y + spec.height, 0, 1, 0, spec.nchannels);
  if (!buf.get_pixels(roi, OIIO::TypeDesc::FLOAT, img.pixels.data()))
    throw std::runtime_error(fmt::format("cannot read pixels of '{}': {}", path, buf.geterror()));
  return img;
}

namespace {

void write_buffer(OIIO::ImageBuf& buf, const std::string& path) {
  if (!buf.write(path)) {
    const std::string why = buf.geterror();
    throw std::runtime_error(fmt::format("cannot write image '{}': {}", path, why.empty() ? OIIO::geterror() : why));
  }
}

}  // namespace

void write_exr_float(const Image& image, const std::string& path) {
  // ImageBuf wraps the caller's pixels without copying; writing only reads them.
  OIIO::ImageBuf buf(OIIO::ImageSpec(image.width, image.height, image.channels, OIIO::TypeDesc::FLOAT),
                     const_cast<float*>(image.pixels.data()));
  buf.set_write_format(OIIO::TypeDesc::FLOAT);
  write_buffer(buf, path);
}

void write_8bit(const std::vector<std::uint8_t>& bytes, int width, int height, int channels, const std::string& path,
                bool srgb_tagged) {
  OIIO::ImageSpec spec(width, height, channels, OIIO::TypeDesc::UINT8);
  if (srgb_tagged) spec.attribute("oiio:ColorSpace", "sRGB");
  OIIO::ImageBuf buf(spec, const_cast<std::uint8_t*>(bytes.data()));
  write_buffer(buf, path);
}

bool draw_text(Image& rgb, int x_px, int baseline_y_px, const std::string& text, int size_px,
               const std::array<float, 3>& colour) {
  OIIO::ImageBuf buf(OIIO::ImageSpec(rgb.width, rgb.height, 3, OIIO::TypeDesc::FLOAT), rgb.pixels.data());
  if (OIIO::ImageBufAlgo::render_text(buf, x_px, baseline_y_px, text, size_px, "DejaVuSans", colour)) return true;
  buf.geterror();  // no usable font: the caller decides what that means; the error is consumed
  return false;
}

ImageIoBackend describe() { return {"oiio", "OpenImageIO " OIIO_VERSION_STRING}; }

}  // namespace bokeh::image_backend
