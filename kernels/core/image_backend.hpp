#pragma once
// What an image back-end (image_io_oiio.cpp or image_io_lean.cpp, one per build: BOKEH_IMAGE_IO) must
// provide. image_io.cpp builds the public functions (image_io.hpp) on these: the extension rules, the
// channel-count and float checks, the tone map, the sRGB encoding and the 8-bit quantization live there,
// once, so both back-ends write the same bytes.
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "image.hpp"
#include "image_io.hpp"

namespace bokeh::image_backend {

// The file's header. Throws std::runtime_error naming the file when it cannot be read.
ImageFileInfo read_info(const std::string& path);

// Every channel of the file as float, in OpenImageIO's channel order and conversions (see read_image).
// Throws std::runtime_error naming `what`, the file and the problem.
Image read(const std::string& path, const std::string& what);

// Writers: `file` is the file to write (write_file_atomically's temporary, whose name ends in ".tmp.PID");
// the format is given, not taken from its name. They throw std::runtime_error with the reason only:
// write_file_atomically names the target.
//
// 32-bit float OpenEXR, ZIP compressed, channels named as OpenImageIO names them (1: Y; 2: R G;
// 3: R G B; 4: R G B A; more: R G B A channel4 ...), and `attributes` as string attributes of the header.
void write_exr_float(const Image& image, const std::string& file, const ExrAttributes& attributes);

// 8 bits a channel, row-major and interleaved (`bytes.size() == width * height * channels`), in the format
// `extension` names (".png", ...; the lean back-end: PNG only). srgb_tagged: mark the file as sRGB-encoded
// (PNG's sRGB, gAMA and cHRM chunks).
void write_8bit(const std::vector<std::uint8_t>& bytes, int width, int height, int channels, const std::string& file,
                const std::string& extension, bool srgb_tagged);

// The string attribute `name` of an EXR file's header; empty when it has none. Throws std::runtime_error
// naming the file when it cannot be read.
std::string read_exr_string_attribute(const std::string& path, const std::string& name);

// See draw_text in image_io.hpp.
bool draw_text(Image& rgb, int x_px, int baseline_y_px, const std::string& text, int size_px,
               const std::array<float, 3>& colour);

// "oiio" or "lean", and the libraries with their versions.
ImageIoBackend describe();

// Shared helpers (image_io.cpp) and messages for the back-ends.
inline constexpr const char* kDeepPixels = "it holds deep (multi-sample) pixels, which cannot be read as an image";
std::string lower_extension(const std::string& path);  // ".exr", ".png", "" when none

}  // namespace bokeh::image_backend
