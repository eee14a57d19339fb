#pragma once
// Image files: EXR (linear, as is) and PNG (tone-mapped for people). Two back-ends implement this, chosen
// when configuring (CMake option BOKEH_IMAGE_IO): OpenImageIO ("oiio", the default), or OpenEXR + libpng
// ("lean": ~10x fewer Debian packages, for machines that carry few). Both read and write the same EXR and
// PNG files to the same values; the lean one reads no other formats and draws no text (draw_text).
#include <array>
#include <string>
#include <utility>
#include <vector>

#include "image.hpp"

namespace bokeh {

// How a file stores its pixels, read from its header only (no pixels are loaded).
struct ImageFileInfo {
  int width = 0, height = 0, channels = 0;
  std::string pixel_type;  // OpenImageIO's name: "uint8", "uint16", "uint", "half", "float", ...
  bool is_float = false;   // half, float or double: can hold metres or linear HDR values as they are
};
// Throws naming the file when it cannot be opened.
ImageFileInfo read_image_info(const std::string& path);

// Reads the first `channels` channels as float; throws naming the file on failure or too few channels.
// `what` names the file's role in messages ("colour", "depth"). With float_only, a file that stores
// integers (an 8-bit PNG read as depth would give 0..1 "metres") is refused with its pixel type named.
// Channels come in OpenImageIO's order (R, G, B, Y, A, Z, then others by name; layers after), integers
// are scaled to 0..1 (n / 255 for 8 bit), and PNG colour is multiplied by its alpha (associated).
Image read_image(const std::string& path, int channels, const std::string& what = "image", bool float_only = false);

// The image files bokehbench writes: .exr (linear float, as is) and .png (tone-mapped, 8-bit sRGB).
// Throws std::invalid_argument naming the path unless its extension (any case) is one of them.
void check_image_extension(const std::string& path);

// String attributes of an EXR header (name, value), e.g. what a cached reference was computed from.
using ExrAttributes = std::vector<std::pair<std::string, std::string>>;

// .exr: linear floats unchanged (32-bit float, ZIP), with `exr_attributes` in its header. .png: Reinhard
// tone map on luminance, then sRGB (encode_srgb), 8 bit (quantize_unit_to_8bit), tagged sRGB (attributes
// refused). Other extensions are refused (check_image_extension). Written atomically (write_file_atomically,
// atomic_file.hpp): a failed write leaves the old file and no temporary, and throws naming `path`.
void write_image(const Image& image, const std::string& path, const ExrAttributes& exr_attributes = {});

// The string attribute `name` in an EXR file's header (written by write_image); empty when absent or
// when the file is not EXR. Throws naming the file when it cannot be read.
std::string read_image_attribute(const std::string& path, const std::string& name);

// Writes a display-encoded image ([0,1], e.g. to_display_srgb) as is, without write_image's tone map:
// 8 bit (quantize_unit_to_8bit) for PNG, or any 8-bit format OpenImageIO knows by the extension (the
// lean back-end: PNG only); 32-bit float for .exr. Written atomically, as write_image.
void write_display_image(const Image& display_srgb, const std::string& path);

// The display transform write_image uses for PNG (linear HDR -> display-referred [0,1], still linear).
Image tone_map_for_display(const Image& linear);

// The sRGB transfer function (IEC 61966-2-1), computed in double: linear [0,1] -> encoded [0,1].
double encode_srgb(double linear);

// [0,1] -> 0..255 as OpenImageIO converts float to uint8: clamp, then round half up; NaN -> 0.
unsigned char quantize_unit_to_8bit(float value);

// Draws `text` (DejaVu Sans, `size_px` high) into a 3-channel image with its baseline starting at
// (x_px, baseline_y_px). Returns false, having drawn nothing, where it cannot: no such font installed
// (Debian: fonts-dejavu-core), or the lean back-end, which has no text renderer.
bool draw_text(Image& rgb, int x_px, int baseline_y_px, const std::string& text, int size_px,
               const std::array<float, 3>& colour);

// This build's back-end: the value of BOKEH_IMAGE_IO ("oiio" or "lean") and the libraries it uses, with
// their versions (e.g. "OpenEXR 3.1.5, libpng 1.6.39").
struct ImageIoBackend {
  std::string name;
  std::string libraries;
};
ImageIoBackend image_io_backend();

}  // namespace bokeh
