// Image files under whichever back-end this build has (BOKEH_IMAGE_IO: oiio or lean): round trips against
// closed forms, and committed files (tests/data/image_io, made by make_fixtures.sh) written by each back-end
// and by other tools, read to the same exact values by both. Bad files and paths give messages naming
// them, never a crash.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "image_io.hpp"

namespace bokeh {
namespace {

namespace fs = std::filesystem;

const std::string kData = std::string(BOKEH_TEST_DATA_DIR) + "/image_io/";
constexpr float kInf = std::numeric_limits<float>::infinity();

bool lean() { return image_io_backend().name == "lean"; }

// A fresh file name in the temporary directory, removed when the test ends.
class TempFile {
 public:
  explicit TempFile(const std::string& extension)
      : path_((fs::temp_directory_path() / ("bokeh-image-io-" + std::to_string(std::random_device{}()) + extension))
                  .string()) {}
  ~TempFile() { fs::remove(path_); }
  const std::string& path() const { return path_; }

 private:
  std::string path_;
};

std::uint32_t bits(float v) {
  std::uint32_t b;
  std::memcpy(&b, &v, sizeof b);
  return b;
}

// ---- The closed forms the fixtures and round trips are checked against ----

// Linear floats as a renderer writes them: signs, zero and -0, a float denormal, fractions that half cannot
// hold, HDR up to just below float's maximum, infinities and a NaN.
float exr_value(int x, int y, int c) {
  static const float kValues[] = {0.0f,   -0.0f,       1.0f,     0.1f,   -2.5f,
                                  1e-40f, 3e38f,       65504.0f, 1.0e6f, kInf,
                                  -kInf,  0.33333334f, 1024.5f,  7e-3f,  std::numeric_limits<float>::quiet_NaN()};
  constexpr int kCount = sizeof kValues / sizeof kValues[0];
  return kValues[(y * 5 + x + c * 7) % kCount];
}
Image exr_image(int channels) {
  Image image(5, 3, channels);
  for (int y = 0; y < 3; ++y)
    for (int x = 0; x < 5; ++x)
      for (int c = 0; c < channels; ++c) image.px(x, y)[c] = exr_value(x, y, c);
  return image;
}

// 16x16: every byte value in every channel.
std::uint8_t display_byte(int x, int y, int c) { return static_cast<std::uint8_t>((x + 16 * y + 85 * c) % 256); }
Image display_image() {
  Image image(16, 16, 3);
  for (int y = 0; y < 16; ++y)
    for (int x = 0; x < 16; ++x)
      for (int c = 0; c < 3; ++c) image.px(x, y)[c] = display_byte(x, y, c) / 255.0f;
  return image;
}

// Linear HDR colours for write_image's PNG: greys, primaries, negatives, very bright.
Image tone_mapped_input() {
  Image image(8, 2, 3);
  const float greys[8] = {0.0f, 0.01f, 0.18f, 0.5f, 1.0f, 3.0f, 100.0f, 1e6f};
  for (int x = 0; x < 8; ++x) {
    for (int c = 0; c < 3; ++c) image.px(x, 0)[c] = greys[x];
    for (int c = 0; c < 3; ++c) image.px(x, 1)[c] = c == x % 3 ? greys[x] * 4.0f : (x == 7 ? -1.0f : 0.0f);
  }
  return image;
}

// What write_image's PNG holds, worked out here in double: Reinhard on luminance, clamp, sRGB, x 255.
// Returns the unrounded value; the stored byte is it rounded to nearest.
std::array<double, 3> tone_mapped_255(const float* rgb) {
  const double w[3] = {0.2126, 0.7152, 0.0722};
  double lum = 0.0;
  for (int k = 0; k < 3; ++k) lum += w[k] * std::max(0.0, static_cast<double>(rgb[k]));
  std::array<double, 3> out;
  for (int k = 0; k < 3; ++k) {
    const double v = std::clamp(rgb[k] / (1.0 + lum), 0.0, 1.0);
    out[k] = 255.0 * (v <= 0.0031308 ? 12.92 * v : 1.055 * std::pow(v, 1.0 / 2.4) - 0.055);
  }
  return out;
}

// ---- Checks shared by the round trips and the fixtures ----

void expect_exr_values(const std::string& path, int channels) {
  const ImageFileInfo info = read_image_info(path);
  EXPECT_EQ(info.width, 5);
  EXPECT_EQ(info.height, 3);
  EXPECT_EQ(info.channels, channels);
  EXPECT_EQ(info.pixel_type, "float");
  EXPECT_TRUE(info.is_float);
  const Image back = read_image(path, channels);
  ASSERT_EQ(back.channels, channels);
  for (int y = 0; y < 3; ++y)
    for (int x = 0; x < 5; ++x)
      for (int c = 0; c < channels; ++c)  // bit for bit: -0, the denormal, the NaN and the infinities too
        ASSERT_EQ(bits(back.px(x, y)[c]), bits(exr_value(x, y, c)))
            << path << " (" << x << ", " << y << ") channel " << c;
}

void expect_display_values(const std::string& path) {
  const ImageFileInfo info = read_image_info(path);
  EXPECT_EQ(info.pixel_type, "uint8");
  EXPECT_FALSE(info.is_float);
  EXPECT_EQ(info.channels, 3);
  const Image back = read_image(path, 3);
  ASSERT_EQ(back.width, 16);
  ASSERT_EQ(back.height, 16);
  for (int y = 0; y < 16; ++y)
    for (int x = 0; x < 16; ++x)
      for (int c = 0; c < 3; ++c)
        ASSERT_FLOAT_EQ(back.px(x, y)[c], display_byte(x, y, c) / 255.0f) << path << " (" << x << ", " << y << ")";
}

void expect_tone_mapped_values(const std::string& path) {
  const Image input = tone_mapped_input();
  const Image back = read_image(path, 3);
  ASSERT_TRUE(back.same_shape(input)) << path;
  for (int y = 0; y < input.height; ++y)
    for (int x = 0; x < input.width; ++x) {
      const auto expected = tone_mapped_255(input.px(x, y));
      for (int c = 0; c < 3; ++c) {
        const double stored = back.px(x, y)[c] * 255.0;
        EXPECT_NEAR(stored, std::round(stored), 1e-3) << "not a byte";
        // Round to nearest; within 1e-3 of a tie either byte is right.
        EXPECT_LE(std::abs(stored - expected[c]), 0.5 + 1e-3) << path << " (" << x << ", " << y << ") channel " << c;
      }
    }
}

// Throws, its message naming the file and containing `problem`.
template <typename F>
void expect_error(F&& f, const std::string& path, const std::string& problem) {
  try {
    f();
    ADD_FAILURE() << "no error for " << path;
  } catch (const std::exception& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find(path), std::string::npos) << message;
    EXPECT_NE(message.find(problem), std::string::npos) << "'" << message << "' lacks '" << problem << "'";
  }
}

// ---- Round trips in this build's back-end ----

TEST(ImageIo, BackendIsNamed) {
  const ImageIoBackend backend = image_io_backend();
  EXPECT_TRUE(backend.name == "oiio" || backend.name == "lean") << backend.name;
  EXPECT_FALSE(backend.libraries.empty());
  RecordProperty("image_io_backend", backend.name + ": " + backend.libraries);
}

TEST(ImageIo, ExrFloatRoundTripIsBitExact) {
  for (int channels : {1, 3, 4, 5}) {
    const TempFile file(".exr");
    write_image(exr_image(channels), file.path());
    expect_exr_values(file.path(), channels);
    // Fewer channels than the file holds: the first ones (the order is the file's: R, G, B, A, ...).
    if (channels > 1) {
      const Image first = read_image(file.path(), 1);
      ASSERT_EQ(first.channels, 1);
      EXPECT_EQ(bits(first.px(4, 2)[0]), bits(exr_value(4, 2, 0)));
    }
  }
}

TEST(ImageIo, ExrExtensionInAnyCase) {
  const TempFile file(".EXR");
  write_image(exr_image(3), file.path());
  expect_exr_values(file.path(), 3);
}

TEST(ImageIo, PngOf8BitDisplayValuesRoundTripsExactly) {
  const TempFile file(".png");
  write_display_image(display_image(), file.path());
  expect_display_values(file.path());
}

TEST(ImageIo, DisplayValuesRoundHalfUpToBytes) {
  // quantize_unit_to_8bit: clamp to [0,1], x 255, round half up; NaN is 0. Grey, one channel.
  Image image(6, 1, 1);
  const float values[6] = {-0.5f, 100.4f / 255.0f, 100.6f / 255.0f, 2.0f, std::numeric_limits<float>::quiet_NaN(),
                           kInf};
  const int bytes[6] = {0, 100, 101, 255, 0, 255};
  std::copy(std::begin(values), std::end(values), image.pixels.begin());
  const TempFile file(".png");
  write_display_image(image, file.path());
  EXPECT_EQ(read_image_info(file.path()).channels, 1);
  const Image back = read_image(file.path(), 1);
  for (int x = 0; x < 6; ++x) EXPECT_FLOAT_EQ(back.px(x, 0)[0], bytes[x] / 255.0f) << "value " << values[x];
  for (int b = 0; b < 256; ++b) {
    EXPECT_EQ(quantize_unit_to_8bit((b - 0.49f) / 255.0f), b == 0 ? 0 : b);
    EXPECT_EQ(quantize_unit_to_8bit((b + 0.49f) / 255.0f), b);
    EXPECT_EQ(quantize_unit_to_8bit((b + 0.51f) / 255.0f), std::min(b + 1, 255));
  }
}

TEST(ImageIo, PngIsToneMappedSrgb8Bit) {
  const TempFile file(".png");
  write_image(tone_mapped_input(), file.path());
  const ImageFileInfo info = read_image_info(file.path());
  EXPECT_EQ(info.pixel_type, "uint8");
  EXPECT_EQ(info.channels, 3);
  expect_tone_mapped_values(file.path());
  // Anchors: grey 1 -> Reinhard 0.5 -> sRGB 0.7354 -> 187.5157 -> 188; black 0; 1e6 -> 255.
  const Image back = read_image(file.path(), 3);
  EXPECT_FLOAT_EQ(back.px(4, 0)[1], 188.0f / 255.0f);
  EXPECT_FLOAT_EQ(back.px(0, 0)[0], 0.0f);
  EXPECT_FLOAT_EQ(back.px(7, 0)[2], 1.0f);
}

// ---- Files written by each back-end, read by this one (the other build reads them too) ----

TEST(ImageIo, ReadsExrWrittenByEitherBackend) {
  for (const char* writer : {"oiio", "lean"}) expect_exr_values(kData + writer + "_written_f32.exr", 3);
}

TEST(ImageIo, ReadsDisplayPngWrittenByEitherBackend) {
  for (const char* writer : {"oiio", "lean"}) expect_display_values(kData + writer + "_written_display.png");
}

TEST(ImageIo, ReadsToneMappedPngWrittenByEitherBackend) {
  for (const char* writer : {"oiio", "lean"}) expect_tone_mapped_values(kData + writer + "_written_tonemapped.png");
}

// Writes the *_written_* fixtures with this build's back-end (make_fixtures.sh runs it in both builds).
TEST(ImageIo, DISABLED_WriteFixtures) {
  const char* dir = std::getenv("BOKEH_IMAGE_IO_FIXTURES");
  if (!dir) GTEST_SKIP() << "set BOKEH_IMAGE_IO_FIXTURES to the folder to write into";
  const std::string prefix = std::string(dir) + "/" + image_io_backend().name + "_written_";
  write_image(exr_image(3), prefix + "f32.exr");
  write_display_image(display_image(), prefix + "display.png");
  write_image(tone_mapped_input(), prefix + "tonemapped.png");
}

// ---- Files from other writers (oiiotool: make_fixtures.sh): what scenes may be given ----

// Checkers of 1-px cells: pixel (x, y) holds color1 where x + y is even, else color2.
template <std::size_t N>
std::array<float, N> checker(int x, int y, const std::array<float, N>& color1, const std::array<float, N>& color2) {
  return (x + y) % 2 == 0 ? color1 : color2;
}

TEST(ImageIo, ReadsHalfExr) {
  // Half-precision values exactly: 2^-14 (smallest normal), 65504 (largest), 1365/4096 (half's 1/3).
  const std::string path = kData + "oiiotool_half_checker.exr";
  const ImageFileInfo info = read_image_info(path);
  EXPECT_EQ(info.pixel_type, "half");
  EXPECT_TRUE(info.is_float);
  const Image image = read_image(path, 3, "colour", /*float_only=*/true);
  ASSERT_EQ(image.width, 5);
  ASSERT_EQ(image.height, 3);
  for (int y = 0; y < 3; ++y)
    for (int x = 0; x < 5; ++x)
      for (int c = 0; c < 3; ++c)
        EXPECT_EQ(image.px(x, y)[c],
                  checker<3>(x, y, {0.5f, -2.0f, 1024.0f}, {0.00006103515625f, 65504.0f, 0.333251953125f})[c]);
}

TEST(ImageIo, ReadsChannelsInOpenImageIOsOrderFromTiledExrWithDataWindow) {
  // Written with channels Z, depth.Y, A, G, R = color (1..5 | 6..10), tiled 2x2, data window at (2, 1):
  // read as R, G, A, Z, then the layer depth.Y; the data window's pixels, from its corner.
  const std::string path = kData + "oiiotool_channels_tiled_window.exr";
  const Image image = read_image(path, 5);
  ASSERT_EQ(image.width, 4);
  ASSERT_EQ(image.height, 3);
  for (int y = 0; y < 3; ++y)
    for (int x = 0; x < 4; ++x)
      for (int c = 0; c < 5; ++c)
        EXPECT_EQ(image.px(x, y)[c], checker<5>(x, y, {5, 4, 3, 1, 2}, {10, 9, 8, 6, 7})[c])
            << x << ", " << y << ", " << c;
}

TEST(ImageIo, Reads16BitPngScaledToUnit) {
  const std::string path = kData + "oiiotool_gray16.png";
  const ImageFileInfo info = read_image_info(path);
  EXPECT_EQ(info.pixel_type, "uint16");
  EXPECT_EQ(info.channels, 1);
  const Image image = read_image(path, 1);
  // oiiotool stored round(0.25 * 65535) = 16384 and round(0.75 * 65535) = 49151.
  for (int y = 0; y < 3; ++y)
    for (int x = 0; x < 5; ++x) EXPECT_FLOAT_EQ(image.px(x, y)[0], ((x + y) % 2 == 0 ? 16384 : 49151) / 65535.0f);
}

TEST(ImageIo, ReadsPngAlphaAsAssociated) {
  // Stored unassociated, as PNG defines: (204, 102, 51, 128) | (255, 255, 255, 0), no gamma chunk. Read
  // colour x alpha, rounded down in the file's integers: 204 x 128 / 255 = 102.4 -> 102, ...
  const std::string path = kData + "oiiotool_rgba_unassociated.png";
  const Image image = read_image(path, 4);
  const int stored[2][4] = {{204, 102, 51, 128}, {255, 255, 255, 0}};
  for (int y = 0; y < 3; ++y)
    for (int x = 0; x < 4; ++x) {
      const int* s = stored[(x + y) % 2];
      for (int c = 0; c < 4; ++c) {
        const int expected = c == 3 ? s[3] : s[c] * s[3] / 255;
        EXPECT_FLOAT_EQ(image.px(x, y)[c], expected / 255.0f) << x << ", " << y << ", " << c;
      }
    }
  // A scene's colour is its first three channels.
  EXPECT_EQ(read_image(path, 3).channels, 3);
}

// ---- Bad files and paths: a message naming the file and the problem ----

TEST(ImageIo, MissingAndUnreadableFilesAreNamed) {
  const std::string missing = "/nonexistent/bokeh.exr";
  expect_error([&] { read_image_info(missing); }, missing, "");
  expect_error([&] { read_image(missing, 3, "colour"); }, missing, "colour");
  const std::string not_an_image = std::string(BOKEH_TEST_DATA_DIR) + "/lens_missing_focus.json";
  expect_error([&] { read_image(not_an_image, 3); }, not_an_image, lean() ? "neither OpenEXR nor PNG" : "");
  expect_error([&] { read_image(kData, 3); }, kData, "");  // a directory
}

TEST(ImageIo, TruncatedFilesAreErrors) {
  for (const std::string name : {"oiio_written_f32.exr", "oiio_written_display.png"}) {
    std::ifstream in(kData + name, std::ios::binary);
    std::vector<char> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    for (std::size_t keep : {std::size_t{10}, bytes.size() / 2}) {
      const TempFile file(fs::path(name).extension().string());
      std::ofstream(file.path(), std::ios::binary).write(bytes.data(), static_cast<std::streamsize>(keep));
      expect_error([&] { read_image(file.path(), 3); }, file.path(), "");
    }
  }
}

TEST(ImageIo, DeepAndSubsampledExrAreRefused) {
  // Made with OpenEXR directly (make_fixtures.sh): OpenImageIO 2.4 crashed reading the deep one.
  const std::string deep = kData + "openexr_deep.exr";
  expect_error([&] { read_image(deep, 1, "depth"); }, deep, "deep (multi-sample) pixels");
  const std::string subsampled = kData + "openexr_luminance_chroma.exr";
  expect_error([&] { read_image(subsampled, 3, "colour"); }, subsampled, "ubsampled");
}

TEST(ImageIo, IntegerDepthIsRefusedWithItsType) {
  const std::string path = kData + "oiiotool_gray16.png";
  expect_error([&] { read_image(path, 1, "depth", /*float_only=*/true); }, path, "stores uint16 values, not floats");
  expect_error([&] { read_image(path, 3, "colour"); }, path, "has 1 channels, need 3");
}

TEST(ImageIo, UnwritablePathsAndShapesAreNamed) {
  const Image image = exr_image(3);
  for (const std::string path : {"/nonexistent/bokeh.exr", "/nonexistent/bokeh.png"})
    expect_error([&] { write_image(image, path); }, path, "");
  expect_error([&] { write_image(image, "/tmp/bokeh.tif"); }, "/tmp/bokeh.tif", "extension must be .exr");
  expect_error([&] { write_image(Image(), "/tmp/bokeh-empty.exr"); }, "/tmp/bokeh-empty.exr", "empty");
  const TempFile five(".png");
  expect_error([&] { write_display_image(Image(2, 2, 5, 0.5f), five.path()); }, five.path(), "1 to 4 channels, not 5");
  EXPECT_FALSE(fs::exists(five.path())) << "no empty file is left behind";
}

TEST(ImageIo, LeanBackendRefusesWhatItCannotWrite) {
  if (!lean()) GTEST_SKIP() << "OpenImageIO writes these";
  const TempFile alpha(".png"), jpeg(".jpg");
  expect_error([&] { write_display_image(Image(2, 2, 4, 0.5f), alpha.path()); }, alpha.path(), "PNG alpha");
  expect_error([&] { write_display_image(Image(2, 2, 3, 0.5f), jpeg.path()); }, jpeg.path(), "only as .png");
}

}  // namespace
}  // namespace bokeh
