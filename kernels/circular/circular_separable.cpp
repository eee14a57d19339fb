#include "circular_separable.hpp"

#include <algorithm>
#include <cmath>
#include <complex>
#include <stdexcept>

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

// The horizontal pass output in the form the vertical pass reads it back.
struct Intermediate {
  int width = 0, height = 0, channels = 0, components = 0;
  IntermediatePrecision precision = IntermediatePrecision::f32;
  // [(((c * height + y) * width + x) * channels + ch) * 2 + {0: real, 1: imaginary}]:
  // the value (f32, f16-rounded) or, for bracketed10, the 10-bit unorm code of I' / M.
  std::vector<float> stored;
  // bracketed10 only.
  std::vector<float> box_over_max;  // f16-rounded sum(J) / M, [(y * width + x) * channels + ch]
  std::vector<float> channel_max;   // M per channel
  std::vector<BracketedKernel> real, imag;  // per component

  std::size_t at(int c, int x, int y, int ch) const {
    return ((((static_cast<std::size_t>(c) * height + y) * width + x) * channels) + ch) * 2;
  }

  std::complex<float> load(int c, int x, int y, int ch) const {
    const std::size_t i = at(c, x, y, ch);
    if (precision != IntermediatePrecision::bracketed10) return {stored[i], stored[i + 1]};
    // I = S I' + O sum(J), with I' = code / 1023 * M and sum(J) = box * M.
    const float m = channel_max[ch];
    const float box = box_over_max[(static_cast<std::size_t>(y) * width + x) * channels + ch] * m;
    return {real[c].scale * (stored[i] / kUnorm10Max * m) + real[c].offset * box,
            imag[c].scale * (stored[i + 1] / kUnorm10Max * m) + imag[c].offset * box};
  }
};

Intermediate horizontal_pass(const Image& img, const CircularKernel& k, IntermediatePrecision precision,
                             int threads) {
  Intermediate out;
  out.width = img.width, out.height = img.height, out.channels = img.channels, out.components = k.components;
  out.precision = precision;
  out.stored.assign(static_cast<std::size_t>(k.components) * img.pixels.size() * 2, 0.0f);
  const bool bracketed = precision == IntermediatePrecision::bracketed10;
  if (bracketed) {
    out.channel_max.assign(img.channels, 0.0f);
    for (std::size_t i = 0; i < img.pixels.size(); ++i) {
      const float v = img.pixels[i];
      if (!(v >= 0.0f)) throw std::invalid_argument("bracketed10 intermediates need non-negative, finite input");
      float& m = out.channel_max[i % img.channels];
      m = std::max(m, v);
    }
    for (const auto& taps : k.taps) {
      std::vector<float> re, im;
      for (std::complex<float> t : taps) re.push_back(t.real()), im.push_back(t.imag());
      out.real.push_back(bracket_kernel(re));
      out.imag.push_back(bracket_kernel(im));
    }
    out.box_over_max.assign(img.pixels.size(), 0.0f);
  }
  const int r = k.radius_px, n = k.tap_count(), ch_count = img.channels;
  parallel_rows(img.height, threads, [&](int y) {
    std::vector<std::complex<float>> acc(ch_count);
    std::vector<float> box(ch_count);
    for (int x = 0; x < img.width; ++x) {
      for (int c = 0; c < k.components; ++c) {
        std::fill(acc.begin(), acc.end(), std::complex<float>());
        for (int i = 0; i < n; ++i) {
          const float* j = img.px(std::clamp(x + i - r, 0, img.width - 1), y);
          // Bracketed: accumulate with G' (real and imaginary kernels separately), as a GPU would.
          const std::complex<float> tap = bracketed ? std::complex<float>(out.real[c].taps[i], out.imag[c].taps[i])
                                                    : k.taps[c][i];
          for (int ch = 0; ch < ch_count; ++ch) acc[ch] += tap * j[ch];
        }
        for (int ch = 0; ch < ch_count; ++ch) {
          float* dst = &out.stored[out.at(c, x, y, ch)];
          if (precision == IntermediatePrecision::f32) {
            dst[0] = acc[ch].real(), dst[1] = acc[ch].imag();
          } else if (precision == IntermediatePrecision::f16) {
            dst[0] = round_half(acc[ch].real()), dst[1] = round_half(acc[ch].imag());
          } else {
            const float inv_max = out.channel_max[ch] > 0.0f ? 1.0f / out.channel_max[ch] : 0.0f;
            const auto unorm10 = [&](float v) { return std::nearbyint(std::clamp(v * inv_max, 0.0f, 1.0f) * kUnorm10Max); };
            dst[0] = unorm10(acc[ch].real()), dst[1] = unorm10(acc[ch].imag());
          }
        }
      }
      if (bracketed) {
        std::fill(box.begin(), box.end(), 0.0f);
        for (int i = 0; i < n; ++i) {
          const float* j = img.px(std::clamp(x + i - r, 0, img.width - 1), y);
          for (int ch = 0; ch < ch_count; ++ch) box[ch] += j[ch];
        }
        for (int ch = 0; ch < ch_count; ++ch) {
          const float inv_max = out.channel_max[ch] > 0.0f ? 1.0f / out.channel_max[ch] : 0.0f;
          out.box_over_max[(static_cast<std::size_t>(y) * img.width + x) * ch_count + ch] = round_half(box[ch] * inv_max);
        }
      }
    }
  });
  return out;
}

Image vertical_pass(const Intermediate& in, const CircularKernel& k, int threads) {
  Image out(in.width, in.height, in.channels);
  const int r = k.radius_px, n = k.tap_count(), ch_count = in.channels;
  parallel_rows(in.height, threads, [&](int y) {
    // Row-at-a-time so the intermediate is read along rows: acc[(x * C + c) * channels + ch].
    std::vector<std::complex<float>> acc(static_cast<std::size_t>(in.width) * k.components * ch_count);
    for (int j = 0; j < n; ++j) {
      const int sy = std::clamp(y + j - r, 0, in.height - 1);
      for (int c = 0; c < k.components; ++c) {
        const std::complex<float> tap = k.taps[c][j];
        for (int x = 0; x < in.width; ++x)
          for (int ch = 0; ch < ch_count; ++ch)
            acc[(static_cast<std::size_t>(x) * k.components + c) * ch_count + ch] += tap * in.load(c, x, sy, ch);
      }
    }
    for (int x = 0; x < in.width; ++x) {
      float* o = out.px(x, y);
      for (int ch = 0; ch < ch_count; ++ch) {
        float sum = 0.0f;
        for (int c = 0; c < k.components; ++c) {
          const std::complex<float> v = acc[(static_cast<std::size_t>(x) * k.components + c) * ch_count + ch];
          sum += k.weight_real[c] * v.real() + k.weight_imag[c] * v.imag();
        }
        o[ch] = sum;
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
                        int threads) {
  if (image.channels < 1 || image.width < 1 || image.height < 1)
    throw std::invalid_argument("circular_convolve needs a non-empty image");
  return vertical_pass(horizontal_pass(image, kernel, precision, threads), kernel, threads);
}

Image circular_blur(const Image& color, const Image& radius_px, const Image& depth_m, double focus_distance_m,
                    const CircularFilterConfig& config, int threads) {
  if (color.channels < 3) throw std::invalid_argument("colour needs at least three channels");
  check_same_size(color, radius_px, "the CoC radius image");
  check_same_size(color, depth_m, "the depth image");
  if (config.max_radius_px < 1)
    throw std::invalid_argument("circular blur max radius must be >= 1 px, got " + std::to_string(config.max_radius_px));

  const int w = color.width, h = color.height;
  Image out(w, h, 3), near_layer(w, h, 4), far_layer(w, h, 4);
  bool any_near = false, any_far = false;
  const float focus = static_cast<float>(focus_distance_m), max_radius = static_cast<float>(config.max_radius_px);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const float* rgb = color.px(x, y);
      std::copy(rgb, rgb + 3, out.px(x, y));
      const float alpha = std::clamp(*radius_px.px(x, y) / max_radius, 0.0f, 1.0f);
      if (!(alpha > 0.0f)) continue;
      const bool near = *depth_m.px(x, y) < focus;
      (near ? any_near : any_far) = true;
      float* layer = (near ? near_layer : far_layer).px(x, y);
      for (int c = 0; c < 3; ++c) layer[c] = rgb[c] * alpha;
      layer[3] = alpha;
    }

  if (any_far) {
    const Image blurred = circular_convolve(
        far_layer, make_circular_kernel_for_disc(config.far_components, max_radius), config.precision, threads);
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        const float alpha = far_layer.px(x, y)[3], blurred_alpha = blurred.px(x, y)[3];
        if (!(alpha > 0.0f) || !(blurred_alpha > kMinFarAlpha)) continue;
        float* o = out.px(x, y);
        for (int c = 0; c < 3; ++c) o[c] = (1.0f - alpha) * o[c] + alpha * blurred.px(x, y)[c] / blurred_alpha;
      }
  }
  if (any_near) {
    const Image blurred = circular_convolve(
        near_layer, make_circular_kernel_for_disc(config.near_components, max_radius), config.precision, threads);
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        const float blurred_alpha = blurred.px(x, y)[3];
        // Ringing can push the blurred alpha outside [0, 1]: composite with the clamped alpha.
        const float alpha = std::clamp(blurred_alpha, 0.0f, 1.0f);
        if (!(alpha > 0.0f)) continue;
        float* o = out.px(x, y);
        for (int c = 0; c < 3; ++c) o[c] = (1.0f - alpha) * o[c] + blurred.px(x, y)[c] * (alpha / blurred_alpha);
      }
  }
  return out;
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
