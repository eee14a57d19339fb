#!/usr/bin/env bash
# Makes the image files that tests/kernels/core/test_image_io.cpp reads (they are committed: run this only to
# change them). Needs both builds (build/: BOKEH_IMAGE_IO=oiio, build-lean/: BOKEH_IMAGE_IO=lean), oiiotool
# (openimageio-tools), and g++ with libopenexr-dev for the two files neither back-end writes.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../../.." && pwd)
cd "$here"

# Written through image_io.hpp by each back-end (<backend>_written_*): the closed forms are in the test.
for build in build build-lean; do
  BOKEH_IMAGE_IO_FIXTURES=$here "$root/$build/tests/test_core" --gtest_also_run_disabled_tests \
    --gtest_filter=ImageIo.DISABLED_WriteFixtures
done

# Written by OpenImageIO's oiiotool: what a scene may be given but bokehbench never writes. Checkers of 1-px
# cells: (x + y) even holds color1.
oiiotool --pattern checker:width=1:height=1:color1=0.5,-2,1024:color2=0.00006103515625,65504,0.333251953125 5x3 3 \
  -d half -o oiiotool_half_checker.exr
oiiotool --pattern checker:width=1:height=1:color1=1,2,3,4,5:color2=6,7,8,9,10 4x3 5 --chnames Z,depth.Y,A,G,R \
  --origin +2+1 --tile 2 2 -d float -o oiiotool_channels_tiled_window.exr
oiiotool --pattern checker:width=1:height=1:color1=0.25:color2=0.75 5x3 1 -d uint16 -o oiiotool_gray16.png
oiiotool --pattern checker:width=1:height=1:color1=0.8,0.4,0.2,0.5:color2=1,1,1,0 4x3 4 -d uint8 \
  --attrib oiio:UnassociatedAlpha 1 -o oiiotool_rgba_unassociated.png

# Written by OpenEXR directly: a deep file and a luminance-chroma one (subsampled channels), both refused.
tool=$(mktemp -d)
trap 'rm -rf "$tool"' EXIT
cat > "$tool/make.cpp" <<'CPP'
#include <ImfChannelList.h>
#include <ImfDeepFrameBuffer.h>
#include <ImfDeepScanLineOutputFile.h>
#include <ImfPartType.h>
#include <ImfRgbaFile.h>
#include <vector>
int main() {
  const int w = 4, h = 2;
  std::vector<Imf::Rgba> rgba(w * h, Imf::Rgba(0.25f, 0.5f, 1.0f, 1.0f));
  Imf::RgbaOutputFile lc("openexr_luminance_chroma.exr", w, h, Imf::WRITE_YC);
  lc.setFrameBuffer(rgba.data(), 1, w);
  lc.writePixels(h);
  Imf::Header header(w, h);
  header.setType(Imf::DEEPSCANLINE);
  header.compression() = Imf::ZIPS_COMPRESSION;
  header.channels().insert("Z", Imf::Channel(Imf::FLOAT));
  std::vector<unsigned> counts(w * h, 1);
  std::vector<float> z(w * h, 2.0f);
  std::vector<float*> samples(w * h);
  for (int i = 0; i < w * h; ++i) samples[i] = &z[i];
  Imf::DeepFrameBuffer frame;
  frame.insertSampleCountSlice(Imf::Slice(Imf::UINT, (char*)counts.data(), sizeof(unsigned), sizeof(unsigned) * w));
  frame.insert("Z", Imf::DeepSlice(Imf::FLOAT, (char*)samples.data(), sizeof(float*), sizeof(float*) * w, sizeof(float)));
  Imf::DeepScanLineOutputFile deep("openexr_deep.exr", header);
  deep.setFrameBuffer(frame);
  deep.writePixels(h);
}
CPP
g++ -std=c++17 -I/usr/include/OpenEXR -I/usr/include/Imath "$tool/make.cpp" -o "$tool/make" \
  -lOpenEXR-3_1 -lIex-3_1 -lIlmThread-3_1 -lImath-3_1
"$tool/make"
ls -l "$here"
