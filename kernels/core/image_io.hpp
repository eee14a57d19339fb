#pragma once
// Image files through OpenImageIO: EXR (linear, as is) and PNG (tone-mapped for people).
#include <string>

#include "image.hpp"

namespace bokeh {

// How a file stores its pixels, read from its header only (no pixels are loaded).
struct ImageFileInfo {
  int width = 0, height = 0, channels = 0;
  std::string pixel_type;  // OpenImageIO's name: "uint8", "uint16", "half", "float", ...
  bool is_float = false;   // half, float or double: can hold metres or linear HDR values as they are
};
// Throws naming the file when it cannot be opened.
ImageFileInfo read_image_info(const std::string& path);

// Reads the first `channels` channels as float; throws naming the file on failure or too few channels.
// `what` names the file's role in messages ("colour", "depth"). With float_only, a file that stores
// integers (an 8-bit PNG read as depth would give 0..1 "metres") is refused with its pixel type named.
Image read_image(const std::string& path, int channels, const std::string& what = "image", bool float_only = false);

// The image files bokehbench writes: .exr (linear float, as is) and .png (tone-mapped, 8-bit sRGB).
// Throws std::invalid_argument naming the path unless its extension (any case) is one of them.
void check_image_extension(const std::string& path);

// .exr: linear floats unchanged. .png: Reinhard tone map on luminance, then sRGB, 8 bit. Other
// extensions are refused (check_image_extension).
void write_image(const Image& image, const std::string& path);

// The display transform write_image uses for PNG (linear HDR -> display-referred [0,1] sRGB).
Image tone_map_for_display(const Image& linear);

}  // namespace bokeh
