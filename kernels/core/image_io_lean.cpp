// The lean back-end (BOKEH_IMAGE_IO=lean): OpenEXR 3 for .exr, libpng for .png, 23 Debian packages where
// OpenImageIO brings 246 (README, "Building for a machine with few packages"). It reads files as
// OpenImageIO 2.4 (Debian 12) does, to the same values: channel order, integer scaling, PNG alpha
// association (image_io.hpp, read_image). What it leaves out, each refused with a message naming the file:
// formats other than EXR and PNG, deep and subsampled EXR channels, and PNG writes with an alpha channel
// (OpenImageIO divides colour by alpha first; nothing here writes one). No text renderer: draw_text draws
// nothing and returns false, so contact sheets keep blank label strips (README).
#include <algorithm>
#include <bit>
#include <cerrno>
#include <cmath>
#include <csetjmp>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <memory>
#include <stdexcept>
#include <tuple>

#include <strings.h>

#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfInputPart.h>
#include <ImfMultiPartInputFile.h>
#include <ImfOutputFile.h>
#include <ImfPartType.h>
#include <ImfStringAttribute.h>
#include <OpenEXRConfig.h>
#include <fmt/format.h>
#include <png.h>

#include "image_backend.hpp"

namespace bokeh::image_backend {

namespace {

// OpenImageIO's limits on a file's size (ImageInput::check_open): a corrupt header fails clearly here
// rather than as an allocation of terabytes.
constexpr int kMaxSidePx = 1 << 20;
constexpr int kMaxChannels = 1 << 12;

enum class Format { exr, png };

// A read refused here, its message complete (naming the file); other exceptions get the file's name added.
struct ReadError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

[[noreturn]] void fail_read(const std::string& what, const std::string& path, const std::string& why) {
  throw ReadError(fmt::format("cannot read {} '{}': {}", what, path, why));
}

// By content, not extension, as OpenImageIO does when the extension does not fit.
Format detect_format(const std::string& path, const std::string& what) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) fail_read(what, path, "it is a directory");
  std::ifstream file(path, std::ios::binary);
  if (!file) fail_read(what, path, std::strerror(errno));
  unsigned char magic[8] = {};
  file.read(reinterpret_cast<char*>(magic), sizeof magic);
  const auto got = file.gcount();
  if (got >= 4 && magic[0] == 0x76 && magic[1] == 0x2f && magic[2] == 0x31 && magic[3] == 0x01) return Format::exr;
  if (got == 8 && png_sig_cmp(magic, 0, 8) == 0) return Format::png;
  fail_read(what, path,
            fmt::format("{} is neither OpenEXR nor PNG, the only formats this build reads (BOKEH_IMAGE_IO=lean; "
                        "configure with -DBOKEH_IMAGE_IO=oiio to read TIFF, JPEG, HDR and more through OpenImageIO)",
                        got == 0 ? "the file is empty, so it" : "it"));
}

void check_size(const std::string& what, const std::string& path, long long width, long long height,
                long long channels) {
  if (width < 1 || height < 1 || width > kMaxSidePx || height > kMaxSidePx || channels < 1 || channels > kMaxChannels)
    fail_read(what, path,
              fmt::format("{}x{} pixels of {} channels is outside what can be read (1 to {} a side, 1 to {} channels)",
                          width, height, channels, kMaxSidePx, kMaxChannels));
}

// ---- OpenEXR ----

// Channels in OpenImageIO's order (its exrinput.cpp, ChanNameHolder): by layer (the name up to its last
// dot, the dot included), then reserved names in a fixed order, then by name. A layer holding X and Y or
// Z (a position or normal) puts X, Y, Z after R, G, B.
struct ExrChannel {
  std::string name, layer, suffix;
  Imf::PixelType type;
  int special = 10000;
};

bool iequals(const std::string& a, const char* b) { return strcasecmp(a.c_str(), b) == 0; }

std::vector<ExrChannel> channels_in_read_order(const Imf::Header& header, const std::string& what,
                                               const std::string& path) {
  std::vector<ExrChannel> channels;
  for (auto it = header.channels().begin(); it != header.channels().end(); ++it) {
    const std::string name = it.name();
    const std::size_t dot = name.find_last_of('.');
    ExrChannel c{name, dot == std::string::npos ? "" : name.substr(0, dot + 1),
                 dot == std::string::npos ? name : name.substr(dot + 1), it.channel().type};
    if (it.channel().xSampling != 1 || it.channel().ySampling != 1)
      fail_read(what, path,
                fmt::format("channel '{}' is subsampled ({}x{}); only full-resolution channels can be read", name,
                            it.channel().xSampling, it.channel().ySampling));
    channels.push_back(c);
  }
  static const char* const kSpecial[] = {"R",     "Red", "G",  "Green", "B",  "Blue", "Y",  "real", "imag",  "A",
                                         "Alpha", "AR",  "RA", "AG",    "GA", "AB",   "BA", "Z",    "Depth", "Zback"};
  static const char* const kSpecialXyz[] = {"R",  "Red", "G",    "Green", "B",  "Blue",  "X",
                                            "Y",  "Z",   "real", "imag",  "A",  "Alpha", "AR",
                                            "RA", "AG",  "GA",   "AB",    "BA", "Depth", "Zback"};
  for (ExrChannel& c : channels) {
    auto in_layer = [&](const char* suffix) {
      return std::any_of(channels.begin(), channels.end(),
                         [&](const ExrChannel& o) { return o.layer == c.layer && iequals(o.suffix, suffix); });
    };
    const bool xyz = in_layer("X") && (in_layer("Y") || in_layer("Z"));
    const auto begin = xyz ? std::begin(kSpecialXyz) : std::begin(kSpecial);
    const auto end = xyz ? std::end(kSpecialXyz) : std::end(kSpecial);
    const auto found = std::find_if(begin, end, [&](const char* s) { return iequals(c.suffix, s); });
    if (found != end) c.special = static_cast<int>(found - begin);
  }
  std::sort(channels.begin(), channels.end(), [](const ExrChannel& a, const ExrChannel& b) {
    return std::tie(a.layer, a.special, a.suffix) < std::tie(b.layer, b.special, b.suffix);
  });
  return channels;
}

const char* type_name(Imf::PixelType type) {
  switch (type) {
    case Imf::UINT:
      return "uint";
    case Imf::HALF:
      return "half";
    case Imf::FLOAT:
      return "float";
    default:
      return "unknown";
  }
}

// One type for the file, as OpenImageIO's TypeDesc::basetype_merge gives it: the channels' own when they
// agree, else float (which holds half and, scaled, uint).
ImageFileInfo exr_info(const Imf::Header& header, const std::vector<ExrChannel>& channels) {
  const Imath::Box2i window = header.dataWindow();
  ImageFileInfo info;
  info.width = window.max.x - window.min.x + 1;
  info.height = window.max.y - window.min.y + 1;
  info.channels = static_cast<int>(channels.size());
  const bool one_type = std::all_of(channels.begin(), channels.end(),
                                    [&](const ExrChannel& c) { return c.type == channels.front().type; });
  const Imf::PixelType type = channels.empty() || !one_type ? Imf::FLOAT : channels.front().type;
  info.pixel_type = type_name(type);
  info.is_float = type != Imf::UINT;
  return info;
}

// OpenEXR reports problems as exceptions (Iex): each becomes one naming the file.
template <typename F>
auto with_exr_errors(const std::string& what, const std::string& path, F&& body) {
  try {
    return body();
  } catch (const ReadError&) {
    throw;
  } catch (const std::bad_alloc&) {
    throw;
  } catch (const std::exception& e) {
    fail_read(what, path, fmt::format("OpenEXR: {}", e.what()));
  }
}

void check_not_deep(const Imf::Header& header, const std::string& what, const std::string& path) {
  if (header.hasType() && Imf::isDeepData(header.type())) fail_read(what, path, kDeepPixels);
}

// The first part (OpenImageIO's subimage 0) of a single- or multi-part file; its first (full-resolution)
// level where it is tiled with mipmaps.
ImageFileInfo read_exr_info(const std::string& path) {
  return with_exr_errors("image", path, [&] {
    Imf::MultiPartInputFile file(path.c_str());
    const Imf::Header& header = file.header(0);
    check_not_deep(header, "image", path);
    const ImageFileInfo info = exr_info(header, channels_in_read_order(header, "image", path));
    check_size("image", path, info.width, info.height, info.channels);
    return info;
  });
}

Image read_exr(const std::string& path, const std::string& what) {
  return with_exr_errors(what, path, [&] {
    Imf::MultiPartInputFile file(path.c_str());
    const Imf::Header& header = file.header(0);
    check_not_deep(header, what, path);
    Imf::InputPart part(file, 0);
    const std::vector<ExrChannel> channels = channels_in_read_order(header, what, path);
    const ImageFileInfo info = exr_info(header, channels);
    check_size(what, path, info.width, info.height, info.channels);
    Image image(info.width, info.height, info.channels);
    const Imath::Box2i window = header.dataWindow();
    const std::size_t pixel_stride_b = sizeof(float) * image.channels;
    // uint channels are read as stored, then scaled to 0..1 as OpenImageIO scales them (in float, below).
    std::vector<std::vector<std::uint32_t>> uint_planes(channels.size());
    Imf::FrameBuffer frame;
    for (std::size_t k = 0; k < channels.size(); ++k) {
      if (channels[k].type == Imf::UINT) {
        uint_planes[k].resize(image.pixel_count());
        frame.insert(channels[k].name, Imf::Slice::Make(Imf::UINT, uint_planes[k].data(), window, sizeof(std::uint32_t),
                                                        sizeof(std::uint32_t) * image.width));
      } else {
        frame.insert(channels[k].name, Imf::Slice::Make(Imf::FLOAT, image.pixels.data() + k, window, pixel_stride_b,
                                                        pixel_stride_b * image.width));
      }
    }
    part.setFrameBuffer(frame);
    part.readPixels(window.min.y, window.max.y);
    for (std::size_t k = 0; k < channels.size(); ++k)
      for (std::size_t p = 0; p < uint_planes[k].size(); ++p)
        image.pixels[p * image.channels + k] = static_cast<float>(uint_planes[k][p]) * (1.0f / 4294967295.0f);
    return image;
  });
}

// ---- libpng ----
// libpng reports errors by longjmp: the functions holding a setjmp keep no C++ object whose state
// changes after it (everything they fill lives in the caller's PngRead), and error messages are copied
// into a fixed buffer.

struct PngError {
  char message[256] = {};
};

void on_png_error(png_structp png, png_const_charp message) {
  auto* error = static_cast<PngError*>(png_get_error_ptr(png));
  std::snprintf(error->message, sizeof error->message, "%s", message);
  png_longjmp(png, 1);
}
void on_png_warning(png_structp, png_const_charp) {}  // as OpenImageIO: warnings (e.g. a bad iCCP) pass

struct PngRead {
  // What the file holds once libpng has expanded palettes, low bit depths and tRNS (OpenImageIO's
  // png_set_expand): 1 to 4 channels of 8 or 16 bits.
  png_uint_32 width = 0, height = 0;
  int channels = 0, bit_depth = 0;
  bool srgb_chunk = false, gama_chunk = false;
  double file_gamma = 0.0;
  // The rows, held as 16-bit values (native-endian where bit_depth is 16; 8-bit ones are read as bytes).
  std::vector<std::uint16_t> storage;
  std::vector<png_bytep> rows;
};

// Returns false with error->message set on failure. Pixels only unless header_only.
bool png_read_file(std::FILE* file, bool header_only, PngRead* out, PngError* error) {
  png_structp png = png_create_read_struct(PNG_LIBPNG_VER_STRING, error, on_png_error, on_png_warning);
  if (!png) {
    std::snprintf(error->message, sizeof error->message, "libpng could not start");
    return false;
  }
  png_infop info = png_create_info_struct(png);
  if (!info) {
    std::snprintf(error->message, sizeof error->message, "libpng could not start");
    png_destroy_read_struct(&png, nullptr, nullptr);
    return false;
  }
  if (setjmp(png_jmpbuf(png))) {
    png_destroy_read_struct(&png, &info, nullptr);
    return false;
  }
  png_init_io(png, file);
  png_read_info(png, info);
  png_set_expand(png);
  if (std::endian::native == std::endian::little) png_set_swap(png);
  png_set_interlace_handling(png);
  png_read_update_info(png, info);
  out->width = png_get_image_width(png, info);
  out->height = png_get_image_height(png, info);
  out->channels = png_get_channels(png, info);
  out->bit_depth = png_get_bit_depth(png, info);
  int intent = 0;
  out->srgb_chunk = png_get_sRGB(png, info, &intent) != 0;
  out->gama_chunk = png_get_gAMA(png, info, &out->file_gamma) != 0;
  if (!header_only) {
    const std::size_t row_bytes = png_get_rowbytes(png, info);
    out->storage.resize((row_bytes * out->height + 1) / 2);
    out->rows.resize(out->height);
    for (png_uint_32 y = 0; y < out->height; ++y)
      out->rows[y] = reinterpret_cast<png_bytep>(out->storage.data()) + y * row_bytes;
    png_read_image(png, out->rows.data());
    png_read_end(png, nullptr);
  }
  png_destroy_read_struct(&png, &info, nullptr);
  return true;
}

PngRead read_png_file(const std::string& path, const std::string& what, bool header_only) {
  std::unique_ptr<std::FILE, int (*)(std::FILE*)> file(std::fopen(path.c_str(), "rb"), std::fclose);
  if (!file) fail_read(what, path, std::strerror(errno));
  PngRead png;
  PngError error;
  if (!png_read_file(file.get(), header_only, &png, &error))
    fail_read(what, path, fmt::format("PNG: {}", error.message));
  check_size(what, path, png.width, png.height, png.channels);
  return png;
}

// OpenImageIO 2.4's PNG reader multiplies colour by alpha in the file's integers (pnginput.cpp,
// png_associateAlpha): exactly, rounding down, unless a gAMA chunk without an sRGB chunk gives a gamma,
// which weights alpha as alpha^gamma and truncates.
template <typename T>
void associate_alpha(T* values, std::size_t pixels, int channels, float gamma) {
  constexpr T kMax = std::numeric_limits<T>::max();
  const int alpha = channels - 1;
  const float inv_max = static_cast<float>(1.0 / kMax);
  for (std::size_t p = 0; p < pixels; ++p, values += channels) {
    const float weight = gamma == 1.0f ? 0.0f : std::pow(values[alpha] * inv_max, gamma);
    for (int c = 0; c < alpha; ++c)
      values[c] = gamma == 1.0f ? static_cast<T>(static_cast<unsigned>(values[c]) * values[alpha] / kMax)
                                : static_cast<T>(values[c] * weight);
  }
}

Image read_png(const std::string& path, const std::string& what) {
  PngRead png = read_png_file(path, what, /*header_only=*/false);
  Image image(static_cast<int>(png.width), static_cast<int>(png.height), png.channels);
  const std::size_t count = image.pixels.size();
  const bool has_alpha = png.channels == 2 || png.channels == 4;
  // OpenImageIO's gamma: 1 / gAMA rounded to hundredths (2.2, not 2.19998), ignored beside an sRGB chunk.
  float gamma = 1.0f;
  if (!png.srgb_chunk && png.gama_chunk && png.file_gamma > 0.0)
    gamma = std::round(static_cast<float>(100.0 * static_cast<float>(1.0 / png.file_gamma))) / 100.0f;
  // Integers to floats as OpenImageIO converts them: n * (1 / max) in float.
  if (png.bit_depth == 16) {
    std::uint16_t* values = png.storage.data();
    if (has_alpha) associate_alpha(values, image.pixel_count(), png.channels, gamma);
    for (std::size_t i = 0; i < count; ++i) image.pixels[i] = values[i] * (1.0f / 65535.0f);
  } else {
    auto* values = reinterpret_cast<std::uint8_t*>(png.storage.data());
    if (has_alpha) associate_alpha(values, image.pixel_count(), png.channels, gamma);
    for (std::size_t i = 0; i < count; ++i) image.pixels[i] = values[i] * (1.0f / 255.0f);
  }
  return image;
}

bool png_write_file(std::FILE* file, const std::vector<png_bytep>& rows, png_uint_32 width, png_uint_32 height,
                    int color_type, bool srgb_tagged, PngError* error) {
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, error, on_png_error, on_png_warning);
  if (!png) {
    std::snprintf(error->message, sizeof error->message, "libpng could not start");
    return false;
  }
  png_infop info = png_create_info_struct(png);
  if (!info) {
    std::snprintf(error->message, sizeof error->message, "libpng could not start");
    png_destroy_write_struct(&png, nullptr);
    return false;
  }
  if (setjmp(png_jmpbuf(png))) {
    png_destroy_write_struct(&png, &info);
    return false;
  }
  png_init_io(png, file);
  png_set_IHDR(png, info, width, height, 8, color_type, PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT,
               PNG_FILTER_TYPE_DEFAULT);
  // The chunks OpenImageIO writes for an sRGB image: sRGB (absolute colorimetric), gAMA 1/2.2, cHRM.
  if (srgb_tagged) png_set_sRGB_gAMA_and_cHRM(png, info, PNG_sRGB_INTENT_ABSOLUTE);
  png_write_info(png, info);
  png_write_image(png, const_cast<png_bytepp>(rows.data()));
  png_write_end(png, nullptr);
  png_destroy_write_struct(&png, &info);
  return true;
}

// write_file_atomically names the target: the reason alone.
[[noreturn]] void fail_write(const std::string& why) { throw std::runtime_error(why); }

}  // namespace

ImageFileInfo read_info(const std::string& path) {
  if (detect_format(path, "image") == Format::exr) return read_exr_info(path);
  const PngRead png = read_png_file(path, "image", /*header_only=*/true);
  ImageFileInfo info;
  info.width = static_cast<int>(png.width);
  info.height = static_cast<int>(png.height);
  info.channels = png.channels;
  info.pixel_type = png.bit_depth == 16 ? "uint16" : "uint8";
  info.is_float = false;
  return info;
}

Image read(const std::string& path, const std::string& what) {
  return detect_format(path, what) == Format::exr ? read_exr(path, what) : read_png(path, what);
}

std::string read_exr_string_attribute(const std::string& path, const std::string& name) {
  if (detect_format(path, "image") != Format::exr) return {};
  try {
    Imf::MultiPartInputFile file(path.c_str());
    const auto* attribute = file.header(0).findTypedAttribute<Imf::StringAttribute>(name);
    return attribute ? attribute->value() : std::string();
  } catch (const std::bad_alloc&) {
    throw;
  } catch (const std::exception& e) {
    fail_read("image", path, fmt::format("OpenEXR: {}", e.what()));
  }
}

void write_exr_float(const Image& image, const std::string& file, const ExrAttributes& attributes) {
  static const char* const kRgba[] = {"R", "G", "B", "A"};
  try {
    Imf::Header header(image.width, image.height);
    header.compression() = Imf::ZIP_COMPRESSION;
    std::vector<std::string> names;
    for (int k = 0; k < image.channels; ++k)
      names.push_back(image.channels == 1 ? "Y" : k < 4 ? kRgba[k] : fmt::format("channel{}", k));
    for (const std::string& name : names) header.channels().insert(name, Imf::Channel(Imf::FLOAT));
    for (const auto& [name, value] : attributes) header.insert(name, Imf::StringAttribute(value));
    const std::size_t pixel_stride_b = sizeof(float) * image.channels;
    Imf::FrameBuffer frame;
    for (int k = 0; k < image.channels; ++k)
      frame.insert(names[k],
                   Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(const_cast<float*>(image.pixels.data() + k)),
                              pixel_stride_b, pixel_stride_b * image.width));
    Imf::OutputFile out(file.c_str(), header);
    out.setFrameBuffer(frame);
    out.writePixels(image.height);
  } catch (const std::bad_alloc&) {
    throw;
  } catch (const std::exception& e) {
    fail_write(fmt::format("OpenEXR: {}", e.what()));
  }
}

void write_8bit(const std::vector<std::uint8_t>& bytes, int width, int height, int channels, const std::string& file,
                const std::string& extension, bool srgb_tagged) {
  const std::string& ext = extension;
  if (ext != ".png")
    fail_write(fmt::format("this build writes 8-bit images only as .png, not '{}' (BOKEH_IMAGE_IO=lean; "
                                 "configure with -DBOKEH_IMAGE_IO=oiio for other formats)",
                                 ext.empty() ? "(none)" : ext));
  if (channels == 2 || channels == 4)
    fail_write(fmt::format("{} channels would make the last one PNG alpha, which this build does not write "
                                 "(BOKEH_IMAGE_IO=lean): write 1 or 3 channels, or .exr",
                                 channels));
  std::vector<png_bytep> rows(height);
  for (int y = 0; y < height; ++y)
    rows[y] = const_cast<png_bytep>(bytes.data()) + static_cast<std::size_t>(y) * width * channels;
  std::unique_ptr<std::FILE, int (*)(std::FILE*)> out(std::fopen(file.c_str(), "wb"), std::fclose);
  if (!out) fail_write(std::strerror(errno));
  PngError error;
  if (!png_write_file(out.get(), rows, width, height, channels == 1 ? PNG_COLOR_TYPE_GRAY : PNG_COLOR_TYPE_RGB,
                      srgb_tagged, &error))
    fail_write(fmt::format("PNG: {}", error.message));
  if (std::fclose(out.release()) != 0) fail_write(std::strerror(errno));
}

bool draw_text(Image&, int, int, const std::string&, int, const std::array<float, 3>&) {
  return false;  // no text renderer in this back-end (see the top of this file)
}

ImageIoBackend describe() {
  return {"lean", fmt::format("OpenEXR {}, libpng {}", OPENEXR_VERSION_STRING, png_get_libpng_ver(nullptr))};
}

}  // namespace bokeh::image_backend
