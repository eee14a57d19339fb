#include "flag.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <utility>

#include <Imath/half.h>
#include <fmt/format.h>

#include "flag_scan.hpp"
#include "half_float.hpp"
#include "scratch.hpp"
#include "simd.hpp"

namespace bokeh {

namespace {

struct PrecisionName {
  LayerPrecision precision;
  const char* name;
};
constexpr PrecisionName kNames[] = {{LayerPrecision::f32, "f32"},
                                    {LayerPrecision::f16, "f16"},
                                    {LayerPrecision::r11g11b10f, "r11g11b10f"},
                                    {LayerPrecision::unorm10_bracketed, "unorm10_bracketed"},
                                    {LayerPrecision::unorm16_bracketed, "unorm16_bracketed"}};

}  // namespace

const char* to_string(LayerPrecision precision) {
  for (const auto& n : kNames)
    if (n.precision == precision) return n.name;
  return "unknown";
}

LayerPrecision layer_precision_from_string(const std::string& name) {
  std::string known;
  for (const auto& n : kNames) {
    if (name == n.name) return n.precision;
    known += (known.empty() ? "" : ", ") + std::string(n.name);
  }
  throw std::invalid_argument("unknown layer precision '" + name + "' (expected one of " + known + ")");
}

const std::vector<LayerPrecision>& all_layer_precisions() {
  static const std::vector<LayerPrecision> all = {LayerPrecision::f32, LayerPrecision::f16, LayerPrecision::r11g11b10f,
                                                  LayerPrecision::unorm10_bracketed,
                                                  LayerPrecision::unorm16_bracketed};
  return all;
}

int bytes_per_texel(LayerPrecision precision) {
  switch (precision) {
    case LayerPrecision::f32: return 16;
    case LayerPrecision::f16: return 8;
    case LayerPrecision::r11g11b10f: return 4;
    case LayerPrecision::unorm10_bracketed: return 4;
    case LayerPrecision::unorm16_bracketed: return 8;
  }
  throw std::invalid_argument("bytes_per_texel: unknown layer precision");
}

bool is_bracketed(LayerPrecision precision) {
  return precision == LayerPrecision::unorm10_bracketed || precision == LayerPrecision::unorm16_bracketed;
}

bool is_unsigned(LayerPrecision precision) { return precision == LayerPrecision::r11g11b10f || is_bracketed(precision); }

int bracket_levels(LayerPrecision precision) {
  return precision == LayerPrecision::unorm10_bracketed ? 1023 : precision == LayerPrecision::unorm16_bracketed ? 65535 : 0;
}

float round_to_ufloat(float value, int mantissa_bits) {
  if (!(value > 0.0f)) return 0.0f;  // unsigned format: negatives (and NaN) have no code
  const float max_finite = std::ldexp(2.0f - std::ldexp(1.0f, -mantissa_bits), 15);
  if (value >= max_finite) return max_finite;
  int e = 0;
  std::frexp(value, &e);                     // value in [2^(e-1), 2^e)
  const int exponent = std::max(e - 1, -14);  // below 2^-14: subnormal, fixed spacing
  const float quantum = std::ldexp(1.0f, exponent - mantissa_bits);
  return std::nearbyint(value / quantum) * quantum;  // exact division by a power of two; ties to even
}

float round_layer_value(float value, LayerPrecision precision, int channel) {
  switch (precision) {
    case LayerPrecision::f32: return value;
    case LayerPrecision::f16: return static_cast<float>(Imath::half(value));
    case LayerPrecision::r11g11b10f: return round_to_ufloat(value, channel == 2 ? 5 : 6);
    default: throw std::invalid_argument(std::string("round_layer_value: ") + to_string(precision) + " is bracketed");
  }
}

float bracket_round_trip(float value, float offset, float scale, int levels) {
  if (!(scale > 0.0f)) return offset;
  const float q = std::clamp((value - offset) / scale, 0.0f, 1.0f);
  const float code = std::nearbyint(q * static_cast<float>(levels));
  return offset + scale * (code / static_cast<float>(levels));
}

void check_layer_input(const Image& packed, LayerPrecision precision) {
  if (!is_unsigned(precision)) return;
  for (int y = 0; y < packed.height; ++y)
    for (int x = 0; x < packed.width; ++x)
      for (int c = 0; c < 3; ++c) {
        const float v = packed.px(x, y)[c];
        if (!(v >= 0.0f))
          throw std::invalid_argument(fmt::format(
              "FLAG layer precision {} stores only non-negative values, but the colour at pixel ({}, {}) has channel "
              "{} = {}: colours must be >= 0 (use f16 or f32 layers for negative colours)",
              to_string(precision), x, y, c, v));
      }
}

FlagLayers flag_horizontal(const Image& packed, const GatherPattern& p, LayerPrecision precision, int threads) {
  check_layer_input(packed, precision);
  const int n = p.half(), k = p.spacing_px;
  const bool bracketed = is_bracketed(precision);
  FlagLayers out{packed.width, packed.height, p.layers(), {}, {}, {}};
  out.rgb.assign(static_cast<std::size_t>(out.width) * out.height * out.layers * 3, 0.0f);
  if (bracketed) {
    out.bracket_offset.assign(static_cast<std::size_t>(out.height) * out.layers * 3, 0.0f);
    out.bracket_scale.assign(out.bracket_offset.size(), 0.0f);
  }
  parallel_rows(packed.height, threads, [&](int y) {
    std::vector<float> reach(static_cast<std::size_t>(out.layers) * 3);
    for (int x = 0; x < packed.width; ++x) {
      // Gather: each row sample lands in the slot of the last layer its disc reaches in column x...
      std::fill(reach.begin(), reach.end(), 0.0f);
      for (int i = -n; i <= n; ++i) {
        const int sx = x + i * k;
        if (sx < 0 || sx >= packed.width) continue;
        const float* s = packed.px(sx, y);
        const int z = disc_reach_layer(s[3] * s[3], i * k, k, n);
        if (z < 0) continue;
        for (int c = 0; c < 3; ++c) reach[z * 3 + c] += s[c];
      }
      // ...then accumulate from the outermost layer inwards: layer z holds every disc reaching >= z.
      float running[3] = {0, 0, 0};
      for (int z = n; z >= 0; --z) {
        float* dst = out.at(x, y, z);
        for (int c = 0; c < 3; ++c) {
          running[c] += reach[z * 3 + c];
          dst[c] = bracketed ? running[c] : round_layer_value(running[c], precision, c);
        }
      }
    }
    if (!bracketed) return;
    // Bracketing: the row's f32 values of each layer and channel span [offset, offset + scale]
    // (what the GPU's bracket pass records with atomicMin/atomicMax), then each is quantised.
    const int levels = bracket_levels(precision);
    for (int z = 0; z <= n; ++z)
      for (int c = 0; c < 3; ++c) {
        float lo = out.at(0, y, z)[c], hi = lo;
        for (int x = 1; x < out.width; ++x) lo = std::min(lo, out.at(x, y, z)[c]), hi = std::max(hi, out.at(x, y, z)[c]);
        const float scale = hi - lo;
        out.bracket_offset[out.bracket_index(y, z, c)] = lo;
        out.bracket_scale[out.bracket_index(y, z, c)] = scale;
        for (int x = 0; x < out.width; ++x) {
          float& v = out.at(x, y, z)[c];
          v = bracket_round_trip(v, lo, scale, levels);
        }
      }
  });
  return out;
}

FlagLayers flag_horizontal_scan(const Image& packed, const GatherPattern& p, LayerPrecision precision, int segment,
                                int threads) {
  if (is_bracketed(precision))
    throw std::invalid_argument(std::string("flag_horizontal_scan: ") + to_string(precision) +
                                " is bracketed; the scan binning stores per-value precisions only");
  if (segment < 1) throw std::invalid_argument("flag_horizontal_scan: segment must be >= 1 column");
  check_layer_input(packed, precision);
  const int n = p.half(), k = p.spacing_px, w = packed.width, max_index = 2 * n * n;
  return flag_scan_layers(packed, p, p.layers(), precision, segment, threads, [&](int y) {
    // Each sample's disc index once a row; layer z: the columns within isqrt(index - z^2) of it, up to n.
    std::vector<int> index(static_cast<std::size_t>(w));
    for (int x = 0; x < w; ++x) {
      const float r = packed.px(x, y)[3];
      index[static_cast<std::size_t>(x)] = disc_index(r * r, k, max_index);
    }
    return [index = std::move(index), n](int x, int z, int& first, int& last) {
      const int d = index[static_cast<std::size_t>(x)] - z * z;
      if (d < 0) return false;
      last = static_cast<int>(std::min<std::int64_t>(isqrt(d), n)), first = -last;
      return true;
    };
  });
}

Image flag_vertical(const FlagLayers& layers, const GatherPattern& p, int threads, bool both_halves) {
  const int n = p.half(), k = p.spacing_px;
  Image out(layers.width, layers.height, 3);
  parallel_rows(layers.height, threads, [&](int y) {
    for (int x = 0; x < layers.width; ++x) {
      float sum[3] = {0, 0, 0};
      for (int j = -n; j <= n; ++j) {
        const int sy = y + j * k;
        if (sy < 0 || sy >= layers.height) continue;
        const float* v = layers.at(x, sy, both_halves ? n - j : std::abs(j));
        for (int c = 0; c < 3; ++c) sum[c] += v[c];
      }
      float* o = out.px(x, y);
      for (int c = 0; c < 3; ++c) o[c] = sum[c];
    }
  });
  return out;
}

Image flag_blur_reference(const Image& packed, const GatherPattern& p, LayerPrecision precision, int threads) {
  return flag_vertical(flag_horizontal(packed, p, precision, threads), p, threads);
}

namespace {

// Columns rounded up to whole vectors: rows the vertical pass loads a vector at a time, past the last column.
int whole_vectors(int columns) { return (columns + simd::kWidth - 1) / simd::kWidth * simd::kWidth; }

// Rows of layers or sums in flight while `band_rows` output rows are summed: the band and the reach
// on either side (flag_blur: bands of one row), at most the frame.
int ring_rows_of(int height_px, const GatherPattern& p, int band_rows) {
  return static_cast<int>(std::min<std::int64_t>(height_px, static_cast<std::int64_t>(band_rows) + 2 * p.half() * p.spacing_px));
}

// flag_blur's strips. A thread's scratch (one source row's layers and the output rows in flight,
// ceil(N/2) + min(H, 2 n k + 1) rows of rgb f32 per column) stays within about 256 KiB, so it stays in a
// core's L2 at every N and the frame time does not depend on how much L3 the machine lends; strips are
// at most 64 columns (wider: less per-row overhead at small N). Their number is a multiple of the
// workers' and their widths nearly equal (whole vectors), so that each worker (strip s: worker s %
// workers) gets the same number of columns.
struct Strips {
  int count = 1, workers = 1, max_columns = 0, width = 0;
  int start(int s) const { return s >= count ? width : static_cast<int>(static_cast<std::int64_t>(s) * width / count) / simd::kWidth * simd::kWidth; }
};
Strips plan_strips(const GatherPattern& p, int width_px, int height_px, int threads) {
  const auto rows = static_cast<std::size_t>(p.layers() + ring_rows_of(height_px, p, 1));
  const int fit = std::clamp(static_cast<int>((256u << 10) / (rows * 3 * sizeof(float))) / simd::kWidth * simd::kWidth,
                             simd::kWidth, 64);
  const int vectors = whole_vectors(width_px) / simd::kWidth;
  Strips st;
  st.width = width_px;
  st.workers = std::clamp(threads, 1, vectors);
  st.count = std::min(vectors, ((width_px + fit - 1) / fit + st.workers - 1) / st.workers * st.workers);
  for (int s = 0; s < st.count; ++s) st.max_columns = std::max(st.max_columns, st.start(s + 1) - st.start(s));
  st.max_columns = whole_vectors(st.max_columns);
  return st;
}

// reach_of[d] = min(isqrt(d), n): a column's reach is reach_of[index - i^2] (reach_layer).
std::vector<std::int16_t> reach_table(int n, int max_index) {
  std::vector<std::int16_t> reach_of(static_cast<std::size_t>(max_index) + 1);
  for (int d = 0; d <= max_index; ++d) reach_of[static_cast<std::size_t>(d)] = static_cast<std::int16_t>(reach_layer(d, 0, n));
  return reach_of;
}

// The horizontal pass for row y, columns [x0, x1), into row_of(z, c)[x - x0], rounded as the precision
// stores it: each sample's reach from its disc index (disc_row: the row's indices, computed once per
// pixel, not per tap, and equal to disc_reach_layer), bins in sample order, accumulated outermost
// first (f16 rounded in bulk: half_float.hpp). `bins`: (n + 1) x 3 floats of scratch.
template <class RowOf>
inline void flag_row_layers(const Image& packed, const std::int32_t* disc_row, const std::int16_t* reach_of, int y,
                            int x0, int x1, int n, int k, LayerPrecision precision, float* bins, RowOf&& row_of) {
  const int w = packed.width;
  for (int x = x0; x < x1; ++x) {
    std::fill(bins, bins + static_cast<std::size_t>(n + 1) * 3, 0.0f);
    const int i_lo = std::max(-n, -(x / k)), i_hi = std::min(n, (w - 1 - x) / k);
    for (int i = i_lo; i <= i_hi; ++i) {
      const int sx = x + i * k, d = disc_row[sx] - i * i;
      if (d < 0) continue;
      const float* src = packed.px(sx, y);
      float* bin = bins + static_cast<std::size_t>(reach_of[static_cast<std::size_t>(d)]) * 3;
      bin[0] += src[0], bin[1] += src[1], bin[2] += src[2];
    }
    float running[3] = {0, 0, 0};
    for (int z = n; z >= 0; --z)
      for (int c = 0; c < 3; ++c) row_of(z, c)[x - x0] = running[c] += bins[static_cast<std::size_t>(z) * 3 + c];
  }
  const auto row_values = static_cast<std::size_t>(x1 - x0);
  if (precision == LayerPrecision::f16) {
    for (int z = 0; z <= n; ++z)
      for (int c = 0; c < 3; ++c) round_to_half(row_of(z, c), row_values);
  } else if (precision != LayerPrecision::f32) {
    for (int z = 0; z <= n; ++z)
      for (int c = 0; c < 3; ++c)
        for (std::size_t x = 0; x < row_values; ++x) row_of(z, c)[x] = round_layer_value(row_of(z, c)[x], precision, c);
  }
}

// The vertical pass for row y, columns [x0, x1), kWidth columns at a time: layer |j| of rows y + j k,
// j = -n .. n, from row_of(z, c, sy) (column x0 first). Its rows must hold a whole number of vectors
// past x0: lanes past x1 read whatever is there and are dropped.
template <class RowOf>
inline void flag_vertical_row(Image& out, int y, int x0, int x1, int n, int k, RowOf&& row_of) {
  const int h = out.height;
  for (int x = x0; x < x1; x += simd::kWidth) {
    simd::f32v sum[3] = {};
    for (int j = -n; j <= n; ++j) {
      const int sy = y + j * k;
      if (sy < 0 || sy >= h) continue;
      for (int c = 0; c < 3; ++c) sum[c] += simd::load(row_of(j < 0 ? -j : j, c, sy) + (x - x0));
    }
    for (int l = 0; l < simd::kWidth && x + l < x1; ++l) {
      float* o = out.px(x + l, y);
      o[0] = sum[0][l], o[1] = sum[1][l], o[2] = sum[2][l];
    }
  }
}

}  // namespace

// flag_horizontal + flag_vertical, strip by strip and fused: the horizontal pass writes a column's
// layers from that row's input alone and the vertical pass reads only that column's layers, so a strip
// of columns is computed whole (no halo). Each source row's layers are made once (flag_row_layers) and
// added at once to the two output rows that read them (layer z of row sy: output rows sy -+ z k), which
// receive them in ascending sy, the order flag_vertical sums them in; so per pixel the same float
// operations in the same order as the reference, and no layer ever leaves the strip's scratch.
Image flag_blur(const Image& packed, const GatherPattern& p, LayerPrecision precision, int threads) {
  if (is_bracketed(precision)) return flag_blur_reference(packed, p, precision, threads);  // brackets span rows
  check_layer_input(packed, precision);
  const int w = packed.width, h = packed.height, n = p.half(), k = p.spacing_px, layers = p.layers();
  const int max_index = 2 * n * n, reach_rows = n * k;
  const std::vector<std::int16_t> reach_of = reach_table(n, max_index);
  Scratch<std::int32_t> index_scratch(packed.pixel_count());
  std::int32_t* const disc = index_scratch.data();
  parallel_rows(h, threads, [&](int y) {
    for (int x = 0; x < w; ++x) {
      const float r = packed.px(x, y)[3];
      disc[static_cast<std::size_t>(y) * w + x] = disc_index(r * r, k, max_index);
    }
  });

  const Strips strips = plan_strips(p, w, h, threads);
  const int strip = strips.max_columns;  // the scratch's row stride
  // Output rows in flight: those sy - n k .. sy + n k, each in slot y mod ring_rows.
  const int ring_rows = ring_rows_of(h, p, 1);
  Image out(w, h, 3);
  parallel_rows(strips.workers, strips.workers, [&](int worker) {
    // layer_row[(z * 3 + c) * strip + x - x0]: the current source row's layers.
    std::vector<float> layer_row(static_cast<std::size_t>(layers) * 3 * strip);
    // sums[(slot * 3 + c) * strip + x - x0]: the vertical pass's running sums of the rows in flight.
    std::vector<float> sums(static_cast<std::size_t>(ring_rows) * 3 * strip);
    std::vector<float> bins(static_cast<std::size_t>(layers) * 3);
    auto sum_row = [&](int y, int c) { return sums.data() + (static_cast<std::size_t>(y % ring_rows) * 3 + c) * strip; };
    auto add_layer = [&](int z, int y, int width) {
      for (int c = 0; c < 3; ++c) {
        const float* src = layer_row.data() + (static_cast<std::size_t>(z) * 3 + c) * strip;
        float* dst = sum_row(y, c);
        for (int x = 0; x < width; x += simd::kWidth) simd::store(dst + x, simd::load(dst + x) + simd::load(src + x));
      }
    };
    auto emit = [&](int y, int x0, int x1) {
      for (int x = x0; x < x1; ++x) {
        float* o = out.px(x, y);
        for (int c = 0; c < 3; ++c) o[c] = sum_row(y, c)[x - x0];
      }
    };
    for (int s = worker; s < strips.count; s += strips.workers) {
      const int x0 = strips.start(s), x1 = strips.start(s + 1);
      const int width = whole_vectors(x1 - x0);  // lanes past x1 are dropped
      std::fill(sums.begin(), sums.end(), 0.0f);
      for (int sy = 0; sy < h; ++sy) {
        // Output row sy + n k gets its first layer now (the rows below it have been zeroed above).
        if (sy > 0 && sy + reach_rows < h)
          for (int c = 0; c < 3; ++c) std::fill_n(sum_row(sy + reach_rows, c), strip, 0.0f);
        flag_row_layers(packed, disc + static_cast<std::size_t>(sy) * w, reach_of.data(), sy, x0, x1, n, k, precision,
                        bins.data(), [&](int z, int c) { return layer_row.data() + (static_cast<std::size_t>(z) * 3 + c) * strip; });
        for (int z = 0; z <= n; ++z) {
          if (sy - z * k >= 0) add_layer(z, sy - z * k, width);
          if (z > 0 && sy + z * k < h) add_layer(z, sy + z * k, width);
        }
        // Output row y is whole once sy reaches min(y + n k, h - 1).
        if (sy < h - 1) {
          if (sy - reach_rows >= 0) emit(sy - reach_rows, x0, x1);
        } else {
          for (int y = std::max(0, sy - reach_rows); y < h; ++y) emit(y, x0, x1);
        }
      }
    }
  });
  return out;
}

std::uint64_t flag_blur_cpu_bytes(int width_px, int height_px, const GatherPattern& p, int threads) {
  const Strips strips = plan_strips(p, width_px, height_px, threads);
  const int strip = strips.max_columns;
  const auto layer_row = static_cast<std::uint64_t>(p.layers()) * 3 * strip;
  const auto sums = static_cast<std::uint64_t>(ring_rows_of(height_px, p, 1)) * 3 * strip;
  const auto per_thread = (layer_row + sums + p.layers() * 3ull) * sizeof(float);
  return static_cast<std::uint64_t>(width_px) * height_px * sizeof(std::int32_t) + strips.workers * per_thread;
}

std::uint64_t flag_streamed_cpu_bytes(int width_px, int height_px, const GatherPattern& p, int band_rows,
                                      int threads) {
  const auto ring = static_cast<std::uint64_t>(ring_rows_of(height_px, p, std::max(band_rows, 1))) * p.layers() * 3 *
                    whole_vectors(width_px) * sizeof(float);
  // Per worker: the bins (ceil(N/2) x 3 floats) and a row of disc indices.
  const auto scratch = static_cast<std::uint64_t>(std::max(threads, 1)) * (p.layers() * 12ull + width_px * 4ull);
  return ring + scratch;
}

// The streamed order (flag_gpu.hpp, layer_buffer = streamed): bands of `band_rows` output rows, the
// horizontal pass filling a ring of B + 2 n k rows up to each band's last row + n k, then the
// vertical pass over the band. Per pixel the operations of flag_blur (the same helpers), so the
// same result bit for bit; rows run in parallel within each pass of a band.
Image flag_blur_streamed(const Image& packed, const GatherPattern& p, LayerPrecision precision, int band_rows,
                         int threads) {
  if (is_bracketed(precision))
    throw std::invalid_argument(std::string("flag_blur_streamed: ") + to_string(precision) +
                                " is bracketed; the CPU streams the per-value precisions (f32, f16, r11g11b10f)");
  if (band_rows < 1)
    throw std::invalid_argument(fmt::format("flag_blur_streamed: band_rows {} must be >= 1", band_rows));
  check_layer_input(packed, precision);
  const int w = packed.width, h = packed.height, n = p.half(), k = p.spacing_px, layers = p.layers();
  const int max_index = 2 * n * n, reach_rows = n * k;
  const int ring_rows = ring_rows_of(h, p, band_rows), stride = whole_vectors(w);
  const std::vector<std::int16_t> reach_of = reach_table(n, max_index);
  Scratch<float> ring_scratch(static_cast<std::size_t>(ring_rows) * layers * 3 * stride);
  float* const ring = ring_scratch.data();
  // ring[((row mod ring_rows) * layers + z) * 3 + c) * stride + x]: row y of layers in ring row y mod R.
  auto at = [&](int z, int c, int y) {
    return ring + ((static_cast<std::size_t>(y % ring_rows) * layers + z) * 3 + c) * stride;
  };
  const int workers = std::max(1, threads);
  std::vector<std::vector<float>> bins(static_cast<std::size_t>(workers), std::vector<float>(static_cast<std::size_t>(layers) * 3));
  std::vector<std::vector<std::int32_t>> disc(static_cast<std::size_t>(workers), std::vector<std::int32_t>(static_cast<std::size_t>(w)));
  Image out(w, h, 3);
  int written = 0;  // rows of layers in the ring so far
  for (int y0 = 0; y0 < h; y0 += band_rows) {
    const int y1 = std::min(h, y0 + band_rows), needed = std::min(h, y1 + reach_rows), first = written;
    // Each worker takes every workers-th row; its scratch is its own.
    parallel_rows(workers, workers, [&](int worker) {
      std::int32_t* const disc_row = disc[static_cast<std::size_t>(worker)].data();
      for (int y = first + worker; y < needed; y += workers) {
        for (int x = 0; x < w; ++x) {
          const float r = packed.px(x, y)[3];
          disc_row[x] = disc_index(r * r, k, max_index);
        }
        flag_row_layers(packed, disc_row, reach_of.data(), y, 0, w, n, k, precision,
                        bins[static_cast<std::size_t>(worker)].data(), [&](int z, int c) { return at(z, c, y); });
      }
    });
    written = std::max(written, needed);
    parallel_rows(y1 - y0, workers, [&](int i) { flag_vertical_row(out, y0 + i, 0, w, n, k, at); });
  }
  return out;
}

}  // namespace bokeh
