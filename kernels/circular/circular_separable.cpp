#include "circular_separable.hpp"

#include <algorithm>
#include <cmath>
#include <complex>
#include <climits>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <stdexcept>
#include <type_traits>

#include <Imath/half.h>

namespace bokeh {

namespace {

constexpr float kUnorm10Max = 1023.0f;
// Below this blurred far alpha the far colour rgb_b / a_b is mostly ringing: keep the sharp pixel.
constexpr float kMinFarAlpha = 1e-4f;

float round_half(float v) { return static_cast<float>(Imath::half(v)); }

}  // namespace

BracketedKernel bracket_kernel(const std::vector<float>& g) {
  BracketedKernel b;
  b.offset = *std::min_element(g.begin(), g.end());
  double s = 0.0;
  for (float v : g) s += v - b.offset;
  b.scale = static_cast<float>(s);
  for (float v : g) b.taps.push_back(static_cast<float>((v - b.offset) / s));
  return b;
}

namespace {

// The horizontal pass output as the vertical pass reads it: real and imaginary parts in separate
// planes, [(c * height + y) * width * channels + x * channels + ch], already in the form the vertical
// pass uses (f32; f16-rounded; bracketed10: I = S (code / 1023 M) + O (sum(J) / M) M, decoded once
// per stored value instead of once per tap reading it: the same float operations, so the same value).
struct Intermediate {
  int width = 0, height = 0, channels = 0, components = 0;
  std::vector<float> re, im;

  std::size_t row(int c, int y) const {
    return (static_cast<std::size_t>(c) * height + y) * width * channels;
  }
};

// Why the passes below are fast and still give the CPU reference's order of summation: each output
// value sums its taps in ascending order, product then sum, exactly as a per-pixel loop would, but
// a block of adjacent values of a row (x * channels + ch) sits in SIMD registers while the taps run
// (horizontal: all taps of one row; vertical: the taps of 4 output rows, so every intermediate row
// loaded serves 4 outputs). Borders clamp through a padded copy of the row (horizontal) or clamped
// row pointers (vertical). tests/kernels/circular/test_circular.cpp checks the bits against plain loops.

// Float vectors of one SIMD register (GCC/Clang vector extension: 4 floats with SSE, 8 when the
// build enables AVX, e.g. -march=native): element-wise IEEE operations, so a sum over vectors keeps
// each element's order of summation.
#ifdef __AVX__
using FloatVec = float __attribute__((vector_size(32)));
#else
using FloatVec = float __attribute__((vector_size(16)));
#endif
constexpr std::size_t kVecFloats = sizeof(FloatVec) / sizeof(float);

template <class V>
V load_values(const float* p) {
  V v;
  std::memcpy(&v, p, sizeof v);
  return v;
}
template <class V>
void store_values(float* p, V v) {
  std::memcpy(p, &v, sizeof v);
}

// Values of a row the horizontal pass sums at once, in registers over all taps.
constexpr std::size_t kBlock = 4 * kVecFloats;

// out_re[u] = sum_i tap_re[i] src[i * stride + u] (ascending i, product then sum), likewise im, for
// u < kBlock.
void accumulate_block(const float* src, int stride, const float* tap_re, const float* tap_im, int taps, float* out_re,
                      float* out_im) {
  constexpr std::size_t w = kVecFloats;
  FloatVec re0{}, re1{}, re2{}, re3{}, im0{}, im1{}, im2{}, im3{};
  for (int i = 0; i < taps; ++i) {
    const float* s = src + static_cast<std::size_t>(i) * stride;
    const FloatVec s0 = load_values<FloatVec>(s), s1 = load_values<FloatVec>(s + w),
                   s2 = load_values<FloatVec>(s + 2 * w), s3 = load_values<FloatVec>(s + 3 * w);
    const float tr = tap_re[i], ti = tap_im[i];
    re0 += tr * s0, re1 += tr * s1, re2 += tr * s2, re3 += tr * s3;
    im0 += ti * s0, im1 += ti * s1, im2 += ti * s2, im3 += ti * s3;
  }
  store_values(out_re, re0), store_values(out_re + w, re1), store_values(out_re + 2 * w, re2);
  store_values(out_re + 3 * w, re3);
  store_values(out_im, im0), store_values(out_im + w, im1), store_values(out_im + 2 * w, im2);
  store_values(out_im + 3 * w, im3);
}

// The same for one value.
void accumulate_one(const float* src, int stride, const float* tap_re, const float* tap_im, int taps, float* out_re,
                    float* out_im) {
  float re = 0.0f, im = 0.0f;
  for (int i = 0; i < taps; ++i) {
    const float s = src[static_cast<std::size_t>(i) * stride];
    re += tap_re[i] * s, im += tap_im[i] * s;
  }
  *out_re = re, *out_im = im;
}

Intermediate horizontal_pass(const Image& img, const CircularKernel& k, IntermediatePrecision precision,
                             int threads, const std::vector<float>* given_max) {
  Intermediate out;
  out.width = img.width, out.height = img.height, out.channels = img.channels, out.components = k.components;
  out.re.assign(static_cast<std::size_t>(k.components) * img.pixels.size(), 0.0f);
  out.im.assign(out.re.size(), 0.0f);
  const bool bracketed = precision == IntermediatePrecision::bracketed10;
  std::vector<float> channel_max, inv_max;
  std::vector<BracketedKernel> real, imag;  // per component, bracketed10 only
  if (bracketed) {
    channel_max.assign(img.channels, 0.0f);
    for (std::size_t i = 0; i < img.pixels.size(); ++i) {
      const float v = img.pixels[i];
      if (!(v >= 0.0f)) throw std::invalid_argument("bracketed10 intermediates need non-negative, finite input");
      float& m = channel_max[i % img.channels];
      m = std::max(m, v);
    }
    if (given_max) {
      if (given_max->size() != static_cast<std::size_t>(img.channels))
        throw std::invalid_argument("bracketed10: one channel maximum per channel expected");
      for (int ch = 0; ch < img.channels; ++ch)
        if (!((*given_max)[ch] >= channel_max[ch]))
          throw std::invalid_argument("bracketed10: a given channel maximum lies below the image's");
      channel_max = *given_max;
    }
    for (float m : channel_max) inv_max.push_back(m > 0.0f ? 1.0f / m : 0.0f);
    for (const auto& taps : k.taps) {
      std::vector<float> re, im;
      for (std::complex<float> t : taps) re.push_back(t.real()), im.push_back(t.imag());
      real.push_back(bracket_kernel(re));
      imag.push_back(bracket_kernel(im));
    }
  }
  const int r = k.radius_px, n = k.tap_count(), ch_count = img.channels;
  const std::size_t row_values = static_cast<std::size_t>(img.width) * ch_count;
  parallel_rows(img.height, threads, [&](int y) {
    // padded[(x + r) * channels + ch] = J(clamp(x), y): tap i of output x reads padded + i * channels.
    std::vector<float> padded((static_cast<std::size_t>(img.width) + 2 * r) * ch_count);
    for (int x = -r; x < img.width + r; ++x) {
      const float* j = img.px(std::clamp(x, 0, img.width - 1), y);
      std::copy(j, j + ch_count, &padded[static_cast<std::size_t>(x + r) * ch_count]);
    }
    std::vector<float> acc_re(row_values), acc_im(row_values), box, tap_re(n), tap_im(n);
    if (bracketed) {
      // The box sum over the same window, per channel, as f16 of sum(J) / M, then times M again.
      box.assign(row_values, 0.0f);
      for (int i = 0; i < n; ++i) {
        const float* src = &padded[static_cast<std::size_t>(i) * ch_count];
        for (std::size_t v = 0; v < row_values; ++v) box[v] += src[v];
      }
      for (std::size_t v = 0; v < row_values; ++v) {
        const std::size_t ch = v % ch_count;
        box[v] = round_half(box[v] * inv_max[ch]) * channel_max[ch];
      }
    }
    for (int c = 0; c < k.components; ++c) {
      // Bracketed: accumulate with G' (real and imaginary kernels separately), as a GPU would.
      for (int i = 0; i < n; ++i) {
        tap_re[i] = bracketed ? real[c].taps[i] : k.taps[c][i].real();
        tap_im[i] = bracketed ? imag[c].taps[i] : k.taps[c][i].imag();
      }
      // kBlock values at a time, their sums held in registers over all taps.
      for (std::size_t v0 = 0; v0 < row_values; v0 += kBlock) {
        const std::size_t count = std::min(kBlock, row_values - v0);
        if (count == kBlock)
          accumulate_block(&padded[v0], ch_count, tap_re.data(), tap_im.data(), n, &acc_re[v0], &acc_im[v0]);
        else
          for (std::size_t v = v0; v < v0 + count; ++v)
            accumulate_one(&padded[v], ch_count, tap_re.data(), tap_im.data(), n, &acc_re[v], &acc_im[v]);
      }
      float* dst_re = &out.re[out.row(c, y)];
      float* dst_im = &out.im[out.row(c, y)];
      for (std::size_t v = 0; v < row_values; ++v) {
        if (precision == IntermediatePrecision::f32) {
          dst_re[v] = acc_re[v], dst_im[v] = acc_im[v];
        } else if (precision == IntermediatePrecision::f16) {
          dst_re[v] = round_half(acc_re[v]), dst_im[v] = round_half(acc_im[v]);
        } else {
          // The 10-bit code of I' / M (round half to even), read back as I = S I' + O sum(J).
          const std::size_t ch = v % ch_count;
          const float m = channel_max[ch];
          const auto code = [&](float value) {
            return std::nearbyint(std::clamp(value * inv_max[ch], 0.0f, 1.0f) * kUnorm10Max);
          };
          dst_re[v] = real[c].scale * (code(acc_re[v]) / kUnorm10Max * m) + real[c].offset * box[v];
          dst_im[v] = imag[c].scale * (code(acc_im[v]) / kUnorm10Max * m) + imag[c].offset * box[v];
        }
      }
    }
  });
  return out;
}

// Output rows per block: every intermediate value a block loads serves up to this many output rows.
constexpr int kVerticalRowsPerBlock = 4;

// For the kVerticalRowsPerBlock output rows of a block, at value v of a row (V = float: one value,
// FloatVec: kVecFloats): acc[row] = sum_j tap_j * H(row + j), complex, ascending j, the product formed as
// std::complex<float> forms it for finite values, then added. src_re/im[s]: intermediate row s of the
// block (s = row + j); acc_re[row * row_stride].
template <class V>
void vertical_block(const float* const* src_re, const float* const* src_im, std::size_t v,
                    const std::vector<std::complex<float>>& taps, float* acc_re, float* acc_im, std::size_t row_stride) {
  constexpr int rows = kVerticalRowsPerBlock;
  V re[rows] = {}, im[rows] = {};
  const int n = static_cast<int>(taps.size());
  for (int s = 0; s < n + rows - 1; ++s) {
    const V h_re = load_values<V>(src_re[s] + v), h_im = load_values<V>(src_im[s] + v);
    for (int row = 0; row < rows; ++row) {
      const int j = s - row;
      if (j < 0 || j >= n) continue;
      const float tr = taps[j].real(), ti = taps[j].imag();
      re[row] += tr * h_re - ti * h_im;
      im[row] += tr * h_im + ti * h_re;
    }
  }
  for (int row = 0; row < rows; ++row) {
    store_values(acc_re + row * row_stride, re[row]);
    store_values(acc_im + row * row_stride, im[row]);
  }
}

Image vertical_pass(const Intermediate& in, const CircularKernel& k, int threads) {
  Image out(in.width, in.height, in.channels);
  const int r = k.radius_px, n = k.tap_count(), ch_count = in.channels, rows = kVerticalRowsPerBlock;
  const std::size_t row_values = static_cast<std::size_t>(in.width) * ch_count;
  const int blocks = (in.height + rows - 1) / rows;
  parallel_rows(blocks, threads, [&](int block) {
    const int y0 = block * rows;
    // acc_re[(c * rows + row) * row_values + v]: output row y0 + row, component c.
    const std::size_t acc_size = static_cast<std::size_t>(rows) * k.components * row_values;
    std::vector<float> acc_re(acc_size, 0.0f), acc_im(acc_size, 0.0f);
    std::vector<const float*> src_re(n + rows - 1), src_im(n + rows - 1);
    for (int c = 0; c < k.components; ++c) {
      // Intermediate row y0 + s - r serves tap j = s - row of output row y0 + row.
      for (int s = 0; s < n + rows - 1; ++s) {
        const int sy = std::clamp(y0 + s - r, 0, in.height - 1);
        src_re[s] = &in.re[in.row(c, sy)], src_im[s] = &in.im[in.row(c, sy)];
      }
      float* a_re = &acc_re[static_cast<std::size_t>(c) * rows * row_values];
      float* a_im = &acc_im[static_cast<std::size_t>(c) * rows * row_values];
      std::size_t v = 0;
      for (; v + kVecFloats <= row_values; v += kVecFloats)
        vertical_block<FloatVec>(src_re.data(), src_im.data(), v, k.taps[c], a_re + v, a_im + v, row_values);
      for (; v < row_values; ++v)
        vertical_block<float>(src_re.data(), src_im.data(), v, k.taps[c], a_re + v, a_im + v, row_values);
    }
    for (int row = 0; row < rows && y0 + row < in.height; ++row) {
      float* o = out.px(0, y0 + row);
      for (std::size_t v = 0; v < row_values; ++v) {
        float sum = 0.0f;
        for (int c = 0; c < k.components; ++c) {
          const std::size_t a = (static_cast<std::size_t>(c) * rows + row) * row_values + v;
          sum += k.weight_real[c] * acc_re[a] + k.weight_imag[c] * acc_im[a];
        }
        o[v] = sum;
      }
    }
  });
  return out;
}

void check_same_size(const Image& a, const Image& b, const char* what) {
  if (a.width != b.width || a.height != b.height || b.channels != 1)
    throw std::invalid_argument(std::string(what) + " must be a one-channel image the size of the colour image");
}

}  // namespace

const char* to_string(IntermediatePrecision precision) {
  switch (precision) {
    case IntermediatePrecision::f32: return "f32";
    case IntermediatePrecision::f16: return "f16";
    case IntermediatePrecision::bracketed10: return "bracketed10";
  }
  throw std::invalid_argument("unknown intermediate precision");
}

IntermediatePrecision intermediate_precision_from_string(const std::string& name) {
  if (name == "f32") return IntermediatePrecision::f32;
  if (name == "f16") return IntermediatePrecision::f16;
  if (name == "bracketed10") return IntermediatePrecision::bracketed10;
  throw std::invalid_argument("unknown intermediate precision '" + name + "' (expected f32, f16 or bracketed10)");
}

Image circular_convolve(const Image& image, const CircularKernel& kernel, IntermediatePrecision precision,
                        int threads, const std::vector<float>* channel_max) {
  if (image.channels < 1 || image.width < 1 || image.height < 1)
    throw std::invalid_argument("circular_convolve needs a non-empty image");
  return vertical_pass(horizontal_pass(image, kernel, precision, threads, channel_max), kernel, threads);
}

CircularBuckets circular_buckets(double max_radius_px) {
  if (!(max_radius_px >= 1.0) || !std::isfinite(max_radius_px))
    throw std::invalid_argument("circular buckets need a finite max radius >= 1 px, got " +
                                std::to_string(max_radius_px));
  std::vector<double> radii;
  for (double spacing = kBucketSpacingPx; radii.empty() || static_cast<int>(radii.size()) > kMaxBuckets;
       spacing *= 1.1) {
    radii = {kMinBucketRadiusPx};
    while (radii.back() < max_radius_px - 1e-9)
      radii.push_back(std::min(radii.back() * kBucketRatio, radii.back() + spacing));
    // The max radius nearer the one before the last than the last: drop the last, stretch the rest.
    if (radii.size() > 1 && max_radius_px - radii[radii.size() - 2] < radii.back() - max_radius_px) radii.pop_back();
    const double stretch = max_radius_px / radii.back();
    for (double& rho : radii) rho *= stretch;
  }
  const double gain = 1.0 / kBucketBlend;
  CircularBuckets b;
  double previous = kIdentityRadiusPx;
  for (double rho : radii) {
    const double span = rho - previous;
    b.disc_radius_px.push_back(static_cast<float>(rho));
    b.ramp_scale.push_back(static_cast<float>(gain / span));
    b.ramp_offset.push_back(static_cast<float>(gain * previous / span + (gain - 1) / 2));
    previous = rho;
  }
  return b;
}

float bucket_coordinate(const CircularBuckets& b, float r) {
  float s = 0.0f;
  for (int k = 0; k < b.count(); ++k) s += std::clamp(r * b.ramp_scale[k] - b.ramp_offset[k], 0.0f, 1.0f);
  return s;
}

Image circular_blur_adaptive(const Image& color, const Image& radius_px, const Image& depth_m,
                             double focus_distance_m, const CircularFilterConfig& config, int threads,
                             AdaptiveWork* work) {
  if (color.channels < 3) throw std::invalid_argument("colour needs at least three channels");
  check_same_size(color, radius_px, "the CoC radius image");
  check_same_size(color, depth_m, "the depth image");
  if (config.max_radius_px < 1)
    throw std::invalid_argument("circular blur max radius must be >= 1 px, got " +
                                std::to_string(config.max_radius_px));
  const CircularBuckets buckets = circular_buckets(config.max_radius_px);
  const int w = color.width, h = color.height, count = buckets.count();
  const float focus = static_cast<float>(focus_distance_m);
  // Layers (rgb, s); per row, the buckets each field touches (bit k: some hat_k > 0).
  Image layers[2] = {Image(w, h, 4, 0.0f), Image(w, h, 4, 0.0f)};  // far, near
  std::vector<std::uint32_t> row_masks[2] = {std::vector<std::uint32_t>(h, 0u), std::vector<std::uint32_t>(h, 0u)};
  std::vector<std::vector<float>> row_max[2] = {std::vector<std::vector<float>>(h, std::vector<float>(4, 0.0f)),
                                                std::vector<std::vector<float>>(h, std::vector<float>(4, 0.0f))};
  parallel_rows(h, threads, [&](int y) {
    for (int x = 0; x < w; ++x) {
      const float* rgb = color.px(x, y);
      const float s = bucket_coordinate(buckets, *radius_px.px(x, y));
      const int field = *depth_m.px(x, y) < focus ? 1 : 0;
      for (int f = 0; f < 2; ++f) {
        float* l = layers[f].px(x, y);
        l[3] = kNoBucket;
        if (f != field || !(s > 0.0f)) continue;
        std::copy(rgb, rgb + 3, l);
        l[3] = s;
        const int lower = static_cast<int>(std::floor(s));
        row_masks[f][y] |= (1u << lower) | (1u << static_cast<int>(std::ceil(s)));
        for (int c = 0; c < 3; ++c) row_max[f][y][c] = std::max(row_max[f][y][c], rgb[c]);
        row_max[f][y][3] = 1.0f;
      }
    }
  });
  // Per field and bucket, the box holding its pixels (x0, y0, x1, y1; empty when x0 > x1).
  struct Box {
    int x0 = INT_MAX, y0 = INT_MAX, x1 = -1, y1 = -1;
    void add(int x, int y) { x0 = std::min(x0, x), y0 = std::min(y0, y), x1 = std::max(x1, x), y1 = std::max(y1, y); }
  };
  std::vector<Box> boxes[2] = {std::vector<Box>(count + 1), std::vector<Box>(count + 1)};
  for (int f = 0; f < 2; ++f)
    for (int y = 0; y < h; ++y) {
      if (!row_masks[f][y]) continue;
      for (int x = 0; x < w; ++x) {
        const float s = layers[f].px(x, y)[3];
        if (!(s > 0.0f)) continue;
        boxes[f][static_cast<int>(std::floor(s))].add(x, y);
        boxes[f][static_cast<int>(std::ceil(s))].add(x, y);
      }
    }
  Image sums[2] = {Image(w, h, 4, 0.0f), Image(w, h, 4, 0.0f)};
  for (int f = 0; f < 2; ++f) {
    std::uint32_t mask = 0;
    std::vector<float> field_max(4, 0.0f);
    for (int y = 0; y < h; ++y) {
      mask |= row_masks[f][y];
      for (int c = 0; c < 4; ++c) field_max[c] = std::max(field_max[c], row_max[f][y][c]);
    }
    const int components = f == 0 ? config.far_components : config.near_components;
    for (int k = 1; k <= count; ++k) {
      if (!(mask & (1u << k))) continue;
      const CircularKernel kernel = make_circular_kernel_for_disc(components, buckets.disc_radius_px[k - 1]);
      // Outside its box dilated by the kernel radius, the bucket's response is exactly 0 (as on the
      // GPU, which skips those tiles): convolve that window only. Inside, the window's borders are
      // zeros (beyond the box) or the image's own (clamped alike), so the values are the same bits.
      const Box& b = boxes[f][k];
      const int r = kernel.radius_px, x0 = std::max(0, b.x0 - r), y0 = std::max(0, b.y0 - r);
      const int x1 = std::min(w - 1, b.x1 + r), y1 = std::min(h - 1, b.y1 + r);
      Image bucket(x1 - x0 + 1, y1 - y0 + 1, 4);
      const float kf = static_cast<float>(k);
      parallel_rows(bucket.height, threads, [&](int y) {
        for (int x = 0; x < bucket.width; ++x) {
          const float* l = layers[f].px(x0 + x, y0 + y);
          const float hat = std::max(0.0f, 1.0f - std::abs(l[3] - kf));
          float* d = bucket.px(x, y);
          for (int c = 0; c < 3; ++c) d[c] = l[c] * hat;
          d[3] = hat;
        }
      });
      const Image blurred = circular_convolve(bucket, kernel, config.precision, threads, &field_max);
      parallel_rows(bucket.height, threads, [&](int y) {
        float* sum = sums[f].px(x0, y0 + y);
        const float* add = blurred.px(0, y);
        for (int v = 0; v < bucket.width * 4; ++v) sum[v] += add[v];
      });
    }
  }
  if (work) {
    const int components[2] = {config.far_components, config.near_components};
    std::vector<int> radii[2];
    for (int f = 0; f < 2; ++f)
      for (float disc : buckets.disc_radius_px)
        radii[f].push_back(make_circular_kernel_for_disc(components[f], disc).radius_px);
    *work = adaptive_tiles(layers[0], layers[1], buckets, radii, components);
  }
  Image out(w, h, 3);
  parallel_rows(h, threads, [&](int y) {
    for (int x = 0; x < w; ++x) {
      float field_sum[2][4];
      for (int f = 0; f < 2; ++f) {
        const float* l = layers[f].px(x, y);
        const float hat = std::max(0.0f, 1.0f - std::abs(l[3]));  // the identity bucket
        const float* sum = sums[f].px(x, y);
        for (int c = 0; c < 3; ++c) field_sum[f][c] = sum[c] + l[c] * hat;
        field_sum[f][3] = sum[3] + hat;
      }
      const bool far = layers[0].px(x, y)[3] > 0.0f, near = layers[1].px(x, y)[3] > 0.0f;
      const float* sharp = color.px(x, y);
      const float* far_sum = field_sum[0];
      const float* near_sum = field_sum[1];
      const float alpha = std::min(near_sum[3], 1.0f);
      float o[3];
      if (near) {
        const float cover = std::max(std::max(far_sum[3], 1.0f - alpha), kMinFarAlpha);
        for (int c = 0; c < 3; ++c) o[c] = far_sum[c] / cover;
      } else if (far && far_sum[3] > kMinFarAlpha) {
        for (int c = 0; c < 3; ++c) o[c] = far_sum[c] / far_sum[3];
      } else {
        std::copy(sharp, sharp + 3, o);
      }
      for (int c = 0; c < 3; ++c)
        o[c] = near_sum[3] < 1.0f ? (1.0f - alpha) * o[c] + near_sum[c] : near_sum[c] / near_sum[3];
      std::copy(o, o + 3, out.px(x, y));
    }
  });
  return out;
}

Image circular_blur(const Image& color, const Image& radius_px, const Image& depth_m, double focus_distance_m,
                    const CircularFilterConfig& config, int threads) {
  if (config.adaptive) return circular_blur_adaptive(color, radius_px, depth_m, focus_distance_m, config, threads);
  if (color.channels < 3) throw std::invalid_argument("colour needs at least three channels");
  check_same_size(color, radius_px, "the CoC radius image");
  check_same_size(color, depth_m, "the depth image");
  if (config.max_radius_px < 1)
    throw std::invalid_argument("circular blur max radius must be >= 1 px, got " + std::to_string(config.max_radius_px));

  const int w = color.width, h = color.height;
  Image out(w, h, 3), near_layer(w, h, 4), far_layer(w, h, 4);
  // Per row: whether it has near (bit 1) or far (bit 2) pixels.
  std::vector<unsigned char> row_fields(h, 0);
  const float focus = static_cast<float>(focus_distance_m), max_radius = static_cast<float>(config.max_radius_px);
  parallel_rows(h, threads, [&](int y) {
    for (int x = 0; x < w; ++x) {
      const float* rgb = color.px(x, y);
      std::copy(rgb, rgb + 3, out.px(x, y));
      const float alpha = std::clamp(*radius_px.px(x, y) / max_radius, 0.0f, 1.0f);
      if (!(alpha > 0.0f)) continue;
      const bool near = *depth_m.px(x, y) < focus;
      row_fields[y] |= near ? 1 : 2;
      float* layer = (near ? near_layer : far_layer).px(x, y);
      for (int c = 0; c < 3; ++c) layer[c] = rgb[c] * alpha;
      layer[3] = alpha;
    }
  });
  const bool any_near = std::any_of(row_fields.begin(), row_fields.end(), [](unsigned char f) { return f & 1; });
  const bool any_far = std::any_of(row_fields.begin(), row_fields.end(), [](unsigned char f) { return f & 2; });

  if (any_far) {
    const Image blurred = circular_convolve(
        far_layer, make_circular_kernel_for_disc(config.far_components, max_radius), config.precision, threads);
    parallel_rows(h, threads, [&](int y) {
      for (int x = 0; x < w; ++x) {
        const float alpha = far_layer.px(x, y)[3], blurred_alpha = blurred.px(x, y)[3];
        if (!(alpha > 0.0f) || !(blurred_alpha > kMinFarAlpha)) continue;
        float* o = out.px(x, y);
        for (int c = 0; c < 3; ++c) o[c] = (1.0f - alpha) * o[c] + alpha * blurred.px(x, y)[c] / blurred_alpha;
      }
    });
  }
  if (any_near) {
    const Image blurred = circular_convolve(
        near_layer, make_circular_kernel_for_disc(config.near_components, max_radius), config.precision, threads);
    parallel_rows(h, threads, [&](int y) {
      for (int x = 0; x < w; ++x) {
        const float blurred_alpha = blurred.px(x, y)[3];
        // Ringing can push the blurred alpha outside [0, 1]: composite with the clamped alpha.
        const float alpha = std::clamp(blurred_alpha, 0.0f, 1.0f);
        if (!(alpha > 0.0f)) continue;
        float* o = out.px(x, y);
        for (int c = 0; c < 3; ++c) o[c] = (1.0f - alpha) * o[c] + blurred.px(x, y)[c] * (alpha / blurred_alpha);
      }
    });
  }
  return out;
}

AdaptiveWork adaptive_tiles(const Image& far_layer, const Image& near_layer, const CircularBuckets& buckets,
                            const std::vector<int> (&tap_radius_px)[2], const int (&components)[2]) {
  const int w = far_layer.width, h = far_layer.height, count = buckets.count();
  const int columns = (w + kTilePx - 1) / kTilePx, rows = (h + kTilePx - 1) / kTilePx;
  AdaptiveWork work;
  work.tiles = columns * rows;
  const auto tile_pixels = [&](int t) {
    return static_cast<double>(std::min(kTilePx, w - (t % columns) * kTilePx)) *
           std::min(kTilePx, h - (t / columns) * kTilePx);
  };
  const Image* layers[2] = {&far_layer, &near_layer};
  for (int f = 0; f < 2; ++f) {
    // Bits floor(s) and ceil(s) of every pixel, per tile (layers.comp), then each bucket's bits
    // spread along the tile row by its reach (tiles.comp, STEP 0).
    std::vector<std::uint32_t> raw(work.tiles, 0u), row(work.tiles, 0u);
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        const float s = layers[f]->px(x, y)[3];
        if (!(s > 0.0f)) continue;
        const std::uint32_t bits = (1u << static_cast<int>(std::floor(s))) | (1u << static_cast<int>(std::ceil(s)));
        raw[(y / kTilePx) * columns + x / kTilePx] |= bits;
        work.bucket_mask[f] |= bits;
      }
    const auto reach = [&](int k) { return (tap_radius_px[f][k - 1] + kTilePx - 1) / kTilePx; };
    for (int ty = 0; ty < rows; ++ty)
      for (int tx = 0; tx < columns; ++tx)
        for (int k = 1; k <= count; ++k)
          for (int x = std::max(tx - reach(k), 0); x <= std::min(tx + reach(k), columns - 1); ++x)
            row[ty * columns + tx] |= raw[ty * columns + x] & (1u << k);
    work.horizontal_tiles[f].assign(count, 0);
    work.zero_tiles[f].assign(count, 0);
    work.vertical_tiles[f].assign(count, 0);
    for (int k = 1; k <= count; ++k) {
      const std::uint32_t bit = 1u << k;
      const double taps = components[f] * (2.0 * tap_radius_px[f][k - 1] + 1);
      for (int ty = 0; ty < rows; ++ty)
        for (int tx = 0; tx < columns; ++tx) {
          bool vertical = false, read = false;
          for (int y = std::max(ty - 2 * reach(k), 0); y <= std::min(ty + 2 * reach(k), rows - 1); ++y) {
            const bool in_row = (row[y * columns + tx] & bit) != 0;
            read = read || in_row;
            vertical = vertical || (in_row && std::abs(y - ty) <= reach(k));
          }
          const int t = ty * columns + tx;
          const bool own = (row[t] & bit) != 0;
          if (read && own) ++work.horizontal_tiles[f][k - 1], work.taps[f] += tile_pixels(t) * taps;
          if (read && !own) ++work.zero_tiles[f][k - 1];
          if (vertical) ++work.vertical_tiles[f][k - 1], work.taps[f] += tile_pixels(t) * taps;
        }
    }
  }
  return work;
}

nlohmann::json bucket_stats(const CircularBuckets& buckets, const AdaptiveWork& work) {
  nlohmann::json stats = {{"bucket_radii_px", buckets.disc_radius_px}, {"tiles", work.tiles}};
  for (int f = 0; f < 2; ++f) {
    std::vector<float> radii;
    std::vector<int> horizontal, zero, vertical;
    for (int k = 1; k <= buckets.count(); ++k) {
      if (!(work.bucket_mask[f] & (1u << k))) continue;
      radii.push_back(buckets.disc_radius_px[k - 1]);
      horizontal.push_back(work.horizontal_tiles[f][k - 1]);
      zero.push_back(work.zero_tiles[f][k - 1]);
      vertical.push_back(work.vertical_tiles[f][k - 1]);
    }
    const std::string field = f == 0 ? "far_" : "near_";
    stats[field + "buckets_run"] = radii.size();
    stats[field + "bucket_radii_px"] = radii;
    stats[field + "horizontal_tiles"] = horizontal;
    stats[field + "zero_tiles"] = zero;
    stats[field + "vertical_tiles"] = vertical;
    stats[field + "taps"] = work.taps[f];
  }
  return stats;
}

CircularCost circular_cost(int components, int radius_px, IntermediatePrecision precision, int channels) {
  circular_components(components);  // validates the count
  if (radius_px < 1 || channels < 1) throw std::invalid_argument("circular_cost needs radius >= 1 px and >= 1 channel");
  const long values_per_component = 2L * channels;  // real and imaginary part per channel
  long bytes = 0;
  switch (precision) {
    case IntermediatePrecision::f32: bytes = components * values_per_component * 4; break;
    case IntermediatePrecision::f16: bytes = components * values_per_component * 2; break;
    case IntermediatePrecision::bracketed10:
      bytes = components * 4L * ((values_per_component + 2) / 3) + 8L * ((channels + 3) / 4);
      break;
  }
  return {2, 2L * components * (2L * radius_px + 1), bytes};
}

double propagate_storage_error(const CircularKernel& k, const std::vector<double>& err_re,
                               const std::vector<double>& err_im) {
  double bound = 0.0;
  for (int c = 0; c < k.components; ++c)
    for (std::complex<float> f : k.taps[c]) {
      const double wr = k.weight_real[c], wi = k.weight_imag[c];
      bound += err_re[c] * std::abs(wr * f.real() + wi * f.imag()) + err_im[c] * std::abs(wi * f.real() - wr * f.imag());
    }
  return bound;
}

double circular_storage_bound(const CircularKernel& k, IntermediatePrecision precision, double units) {
  if (precision == IntermediatePrecision::f32) return 0.0;
  const double half_ulp = std::ldexp(1.0, -11);
  std::vector<double> err_re, err_im;
  for (int c = 0; c < k.components; ++c)
    for (int part = 0; part < 2; ++part) {
      double sum_abs = 0.0, o = 1e30, s = 0.0;
      for (std::complex<float> t : k.taps[c]) {
        const double g = part ? t.imag() : t.real();
        sum_abs += std::abs(g), o = std::min(o, g);
      }
      for (std::complex<float> t : k.taps[c]) s += (part ? t.imag() : t.real()) - o;
      const double e = precision == IntermediatePrecision::f16
                           ? sum_abs * half_ulp
                           : s / kUnorm10Max / 2.0 + std::abs(o) * k.tap_count() * half_ulp;
      (part ? err_im : err_re).push_back(units * e);
    }
  return propagate_storage_error(k, err_re, err_im);
}

}  // namespace bokeh
