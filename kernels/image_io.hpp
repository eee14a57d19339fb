#pragma once
// Image files through OpenImageIO: EXR (linear, as is) and PNG (tone-mapped for people).
#include <string>

#include "image.hpp"

namespace bokeh {

// Reads the first `channels` channels as float; throws naming the file on failure or too few channels.
Image read_image(const std::string& path, int channels);

// .exr: linear floats unchanged. .png/.jpg/.tif: Reinhard tone map on luminance, then sRGB, 8 bit.
void write_image(const Image& image, const std::string& path);

// The display transform write_image uses for PNG (linear HDR -> display-referred [0,1] sRGB).
Image tone_map_for_display(const Image& linear);

}  // namespace bokeh
