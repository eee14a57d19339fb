// The OpenImageIO back-end (BOKEH_IMAGE_IO=oiio, the default): reads every format OpenImageIO knows,
// writes EXR and PNG (write_display_image: any 8-bit format), and draws text with its font renderer.
#include <stdexcept>

#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/imagebufalgo.h>
#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imageio.h>
#include <fmt/format.h>

#include "atomic_file.hpp"
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

std::string read_exr_string_attribute(const std::string& path, const std::string& name) {
  auto input = OIIO::ImageInput::open(path);
  if (!input) throw std::runtime_error(fmt::format("cannot read image '{}': {}", path, OIIO::geterror()));
  if (std::string(input->format_name()) != "openexr") return {};
  return input->spec().get_string_attribute(name);
}

namespace {

// `file` is written in `format` (OpenImageIO's format name or extension), whatever its name ends in.
// Encoded in memory and then written by write_whole_file where the format allows it: OpenImageIO's PNG
// writer ignores short writes, so a full disk would leave a truncated file reported as written.
void write_buffer(OIIO::ImageBuf& buf, const std::string& file, const std::string& format) {
  auto fail = [&] {
    const std::string why = buf.geterror();
    throw std::runtime_error(why.empty() ? OIIO::geterror() : why);
  };
  const auto output = OIIO::ImageOutput::create(format);
  if (!output || !output->supports("ioproxy")) {
    if (!buf.write(file, OIIO::TypeUnknown, format)) fail();
    return;
  }
  OIIO::Filesystem::IOVecOutput memory;
  buf.set_write_ioproxy(&memory);
  const bool ok = buf.write(file, OIIO::TypeUnknown, format);
  buf.set_write_ioproxy(nullptr);
  if (!ok) fail();
  const std::vector<unsigned char>& bytes = memory.buffer();
  write_whole_file(file, std::string_view(reinterpret_cast<const char*>(bytes.data()), bytes.size()));
}

}  // namespace

void write_exr_float(const Image& image, const std::string& file, const ExrAttributes& attributes) {
  OIIO::ImageSpec spec(image.width, image.height, image.channels, OIIO::TypeDesc::FLOAT);
  for (const auto& [name, value] : attributes) spec.attribute(name, value);
  // ImageBuf wraps the caller's pixels without copying; writing only reads them.
  OIIO::ImageBuf buf(spec, const_cast<float*>(image.pixels.data()));
  buf.set_write_format(OIIO::TypeDesc::FLOAT);
  write_buffer(buf, file, "openexr");
}

void write_8bit(const std::vector<std::uint8_t>& bytes, int width, int height, int channels, const std::string& file,
                const std::string& extension, bool srgb_tagged) {
  OIIO::ImageSpec spec(width, height, channels, OIIO::TypeDesc::UINT8);
  if (srgb_tagged) spec.attribute("oiio:ColorSpace", "sRGB");
  OIIO::ImageBuf buf(spec, const_cast<std::uint8_t*>(bytes.data()));
  write_buffer(buf, file, extension.empty() ? std::string() : extension.substr(1));
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
