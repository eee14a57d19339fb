#include "hexagon.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "signed_coc.hpp"

namespace bokeh {

namespace {

// The float operations of hexagon.glsl, in its order.
float clamp01(float v) { return std::clamp(v, 0.0f, 1.0f); }

// One blur's sums: rgb = sum w s.rgb / extent(s.a) with w = coverage x rule; the CoC mean's
// numerator and denominator; the view the included samples fill, sum w / extent, and the share the
// rule hid, sum (coverage - w) / extent.
struct BlurSums {
  float rgb[3];
  float coc_weighted, weight;  // sum w extent(s.a) s.a, sum w extent(s.a)
  float view, hidden;

  void add(const float* s, float coverage, float rule) {
    const float extent = hexagon_extent(s[3]);
    const float w = coverage * rule;
    const float colour_weight = w / extent, coc_weight = w * extent;
    for (int ch = 0; ch < 3; ++ch) rgb[ch] = rgb[ch] + s[ch] * colour_weight;
    coc_weighted = coc_weighted + s[3] * coc_weight;
    weight = weight + coc_weight;
    view = view + colour_weight;
    hidden = hidden + (coverage - w) / extent;
  }
  // The blurred colour, its hidden share filled with the mean of what is visible (up to a full view).
  float fill() const { return view < 1.0f ? std::min(view + hidden, 1.0f) / view : 1.0f; }
};

// A gather direction g = -d in image coordinates (y down).
struct Direction {
  float x, y;
};
// The write-up's directions (rotation 0): up (0, 1), down-left, down-right.
constexpr Direction kUp{0.0f, 1.0f}, kDownLeft{kHexagonSin60, -0.5f}, kDownRight{-kHexagonSin60, -0.5f};

// One-sided scatter-as-gather blur of `src` at (x, y) along d = -g with taps 0..T (kOnAxis: g is
// (0, 1), whole texels); centre_coc is the pixel's own signed CoC. An off-axis sample is the four
// texels around it, each tested with its own CoC ("the CoCSize of that pixel") and weighted by its
// bilinear weight; samples off the image add 0.
template <bool kOnAxis>
BlurSums blur(const Image& src, int x, int y, Direction g, int taps, float centre_coc) {
  BlurSums b{{0.0f, 0.0f, 0.0f}, 0.0f, 0.0f, 0.0f, 0.0f};
  const float* centre = src.px(x, y);
  b.add(centre, hexagon_centre_weight(centre[3]), 1.0f);  // t = 0: the pixel itself
  for (int t = 1; t <= taps; ++t) {
    const float ft = static_cast<float>(t);
    if constexpr (kOnAxis) {
      const float* s = src.px(x, std::min(y + t, src.height - 1));
      b.add(s, y + t <= src.height - 1 ? hexagon_coverage(s[3], ft) : 0.0f, hexagon_rule(s[3], centre_coc));
    } else {
      const SubpixelOffset o = split_offset(ft * g.x, ft * g.y);
      const float* texel[4];
      bilinear_texels(src, x, y, o, texel);
      float beta[4];
      bilinear_weights(o, beta);
      const bool inside = sample_inside(src, x, y, o);
      for (int k = 0; k < 4; ++k)
        b.add(texel[k], inside ? beta[k] * hexagon_coverage(texel[k][3], ft) : 0.0f,
              hexagon_rule(texel[k][3], centre_coc));
    }
  }
  return b;
}

// Both passes. kRotated = false: the write-up's directions as compile-time constants, which the
// compiler folds into each tap's offset (read at run time instead, CI's paired check measured the
// CPU reference 10-12% slower at rotation 0); true: the directions given.
template <bool kRotated>
HexagonPasses passes(const Image& signed_coc, int taps, int threads, const HexagonDirections& dirs) {
  const Direction up = kRotated ? Direction{dirs.up[0], dirs.up[1]} : kUp;
  const Direction downleft = kRotated ? Direction{dirs.downleft[0], dirs.downleft[1]} : kDownLeft;
  const Direction downright = kRotated ? Direction{dirs.downright[0], dirs.downright[1]} : kDownRight;
  const int w = signed_coc.width, h = signed_coc.height;
  HexagonPasses p{Image(w, h, 4), Image(w, h, 4), Image(w, h, 3)};
  parallel_rows(h, threads, [&](int y) {
    for (int x = 0; x < w; ++x) {
      const float c = signed_coc.px(x, y)[3];
      const BlurSums b_up = blur<!kRotated>(signed_coc, x, y, up, taps, c);
      const BlurSums b_downleft = blur<false>(signed_coc, x, y, downleft, taps, c);
      float* o1 = p.up.px(x, y);
      float* o2 = p.up_downleft_mean.px(x, y);
      const float up_fill = b_up.fill(), downleft_fill = b_downleft.fill();
      for (int ch = 0; ch < 3; ++ch) {
        o1[ch] = b_up.rgb[ch] * up_fill;
        o2[ch] = (o1[ch] + b_downleft.rgb[ch] * downleft_fill) * 0.5f;
      }
      o1[3] = b_up.coc_weighted / b_up.weight;
      o2[3] = (b_up.coc_weighted + b_downleft.coc_weighted) / (b_up.weight + b_downleft.weight);
    }
  });
  parallel_rows(h, threads, [&](int y) {
    for (int x = 0; x < w; ++x) {
      const float c = signed_coc.px(x, y)[3];
      const BlurSums r1 = blur<false>(p.up, x, y, downleft, taps, c);
      const BlurSums r2 = blur<false>(p.up_downleft_mean, x, y, downright, taps, c);
      float* o = p.result.px(x, y);
      const float fill1 = r1.fill(), fill2 = r2.fill();
      for (int ch = 0; ch < 3; ++ch) {
        const float a = r1.rgb[ch] * fill1, b = r2.rgb[ch] * fill2;
        o[ch] = a + (b - a) * kHexagonTwoThirds;
      }
    }
  });
  return p;
}

}  // namespace

HexagonDirections hexagon_directions(double rotation_deg) {
  HexagonDirections d{{0.0f, 1.0f}, {kHexagonSin60, -0.5f}, {-kHexagonSin60, -0.5f}, true};
  const double turn = rotation_deg - 60.0 * std::floor(rotation_deg / 60.0);  // in [0, 60)
  if (turn == 0.0) return d;
  // Clockwise on the image (y down): (x, y) -> (x cos a - y sin a, x sin a + y cos a), as Aperture
  // turns its vertices (aperture.hpp).
  const double a = turn * 3.14159265358979323846 / 180.0, c = std::cos(a), s = std::sin(a), h = std::sqrt(3.0) / 2;
  const auto turned = [&](double x, double y, float* out) {
    out[0] = static_cast<float>(x * c - y * s);
    out[1] = static_cast<float>(x * s + y * c);
  };
  turned(0.0, 1.0, d.up);
  turned(h, -0.5, d.downleft);
  turned(-h, -0.5, d.downright);
  d.up_on_axis = false;
  return d;
}

float hexagon_centre_weight(float s) { return 1.0f - std::min(std::abs(s), 1.0f) * 0.5f; }

float hexagon_extent(float s) {
  const float a = std::abs(s);
  return a + 1.0f - std::min(a, 1.0f) * 0.5f;
}

float hexagon_coverage(float s, float t) { return clamp01(std::abs(s) - t + 1.0f); }

float hexagon_rule(float s, float c) {
  if (s < 0.0f) return 1.0f;
  return c < 0.0f ? 0.0f : clamp01(2.0f * c - s + 1.0f);
}

HexagonPasses hexagon_passes(const Image& signed_coc, int taps, int threads, const HexagonDirections& dirs) {
  if (signed_coc.channels != 4) throw std::invalid_argument("hexagon: input must be RGBA (rgb, signed CoC)");
  if (taps < 0) throw std::invalid_argument("hexagon: taps must be >= 0");
  return dirs.up_on_axis ? passes<false>(signed_coc, taps, threads, dirs) : passes<true>(signed_coc, taps, threads, dirs);
}

Image hexagon_blur(const Image& signed_coc, int taps, int threads, const HexagonDirections& directions) {
  return std::move(hexagon_passes(signed_coc, taps, threads, directions).result);
}

}  // namespace bokeh
