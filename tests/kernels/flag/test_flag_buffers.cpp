// FLAG's 3D buffer at reduced precision and reduced resolution: each format's rounding bound on real
// layer data, bracketing against the plain format of the same size, GPU against the CPU emulation
// for every precision and scale, reduced resolution against full resolution, and the memory figures.
// Every bound is stated next to its check; measured / bound ratios are printed ([ measured ]).
#include <gtest/gtest.h>
#include <Imath/half.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <random>
#include <string>
#include <vector>

#include "coc.hpp"
#include "flag.hpp"
#include "flag_memory.hpp"
#include "flag_reduced.hpp"
#include "flag_gpu.hpp"
#include "gpu_test_support.hpp"
#include "half_float.hpp"
#include "metrics.hpp"
#include "run.hpp"
#include "scene.hpp"
#include "vk/memory.hpp"

namespace bokeh {
namespace {

using test::context;

// FLAG's defaults (every option of its own present) at this pattern and precision, through its 3D
// buffer (layer_buffer = full), whose formats and reduced extents these tests measure.
FilterOptions flag_options(const GatherPattern& pattern, const std::string& precision) {
  FilterOptions o = find_method("flag").defaults(pattern);
  o.precision = precision;
  o.values["layer_buffer"] = static_cast<double>(FlagLayerBuffer::full);
  return o;
}

void report(const std::string& what, double measured, double bound) {
  std::printf("[ measured ] %-58s %.4g (bound %.4g, ratio %.3f)\n", what.c_str(), measured, bound,
              bound > 0 ? measured / bound : 0.0);
}

// Realistic layer data: the hoops scene (HDR highlights on a dim backdrop) with circles up to the
// pattern's largest, as the sweeps use it.
struct SceneLayers {
  Scene scene;
  Lens lens;
  GatherPattern pattern;
  CocInput coc;
};

SceneLayers scene_layers(const char* name, int w, int h, GatherPattern pattern) {
  SceneLayers s{make_scene(name, w, h), {}, pattern, {}};
  s.lens = with_max_coc_radius(s.scene.lens, s.scene.depth_m, pattern.max_radius_px());
  s.coc = cpu_coc_pass(s.scene.color, s.scene.depth_m, s.lens, pattern);
  return s;
}

// Largest |stored - exact| / bound over every layer value.
template <class BoundFn>
double worst_ratio(const FlagLayers& exact, const FlagLayers& stored, BoundFn bound) {
  double worst = 0;
  for (int z = 0; z < exact.layers; ++z)
    for (int y = 0; y < exact.height; ++y)
      for (int x = 0; x < exact.width; ++x)
        for (int c = 0; c < 3; ++c) {
          const double v = exact.at(x, y, z)[c], err = std::abs(stored.at(x, y, z)[c] - v);
          worst = std::max(worst, err / bound(v, y, z, c));
        }
  return worst;
}

struct LayerErrors {
  double rms = 0, max = 0;
};
LayerErrors layer_errors(const FlagLayers& exact, const FlagLayers& stored) {
  LayerErrors e;
  for (std::size_t i = 0; i < exact.rgb.size(); ++i) {
    const double d = std::abs(double(stored.rgb[i]) - exact.rgb[i]);
    e.rms += d * d;
    e.max = std::max(e.max, d);
  }
  e.rms = std::sqrt(e.rms / static_cast<double>(exact.rgb.size()));
  return e;
}

// ---------------------------------------------------------------------------------------------
// Names, registry, exact emulation of the 11/10-bit unsigned floats.

TEST(FlagPrecision, NamesRoundTripAndTheRegistryAcceptsEveryOne) {
  for (LayerPrecision p : all_layer_precisions()) {
    EXPECT_EQ(layer_precision_from_string(to_string(p)), p);
    for (int scale : {1, 2, 4}) {
      FilterOptions options = flag_options({9, 2}, to_string(p));
      options.buffer_scale = scale;
      EXPECT_NO_THROW(check_options(find_method("flag"), options));
    }
  }
  FilterOptions bad_scale = flag_options({9, 2}, "f16");
  bad_scale.buffer_scale = 3;
  EXPECT_THROW(check_options(find_method("flag"), bad_scale), std::invalid_argument);
  FilterOptions naive_half = find_method("naive").defaults({9, 2});
  naive_half.buffer_scale = 2;
  EXPECT_THROW(check_options(find_method("naive"), naive_half), std::invalid_argument);  // only FLAG has a 3D buffer
  EXPECT_EQ(bytes_per_texel(LayerPrecision::r11g11b10f), 4);
  EXPECT_EQ(bytes_per_texel(LayerPrecision::unorm10_bracketed), 4);
  EXPECT_EQ(bytes_per_texel(LayerPrecision::unorm16_bracketed), 8);
  EXPECT_THROW(layer_precision_from_string("unorm8"), std::invalid_argument);
}

// Every value of an unsigned float with 5 exponent bits and m mantissa bits, ascending.
std::vector<double> all_ufloat_values(int m) {
  std::vector<double> v;
  for (int e = 0; e < 31; ++e)
    for (int f = 0; f < (1 << m); ++f)
      v.push_back(e == 0 ? std::ldexp(f, -14 - m) : std::ldexp((1 << m) + f, e - 15 - m));
  return v;
}

// The CPU's f16 storage: the F16C path (compiled in or chosen at run time) gives Imath's software
// conversion bit for bit: every half, its float neighbours, every tie between two halves and the
// floats next to it, overflow, subnormals, signed zeros, infinities, and random floats.
TEST(FlagPrecision, HalfRoundingMatchesImathBitForBit) {
  auto from_bits = [](std::uint32_t bits) {
    Imath::half h;
    h.setBits(static_cast<std::uint16_t>(bits));
    return static_cast<float>(h);
  };
  std::vector<float> values;
  for (std::uint32_t h = 0; h < 0x10000; ++h) {
    if ((h & 0x7c00) == 0x7c00) continue;  // inf and NaN below
    const float f = from_bits(h);
    const float next = h == 0x7bff || h == 0xfbff ? std::copysign(65520.0f, f) : from_bits(h + 1);
    const float tie = f + (next - f) / 2;  // exact: halves have 11 significant bits
    for (float v : {f, tie, next}) values.insert(values.end(), {v, std::nextafter(v, -1e38f), std::nextafter(v, 1e38f)});
  }
  std::mt19937 rng(5);
  std::uniform_int_distribution<std::uint32_t> bits;
  for (int i = 0; i < 200000; ++i) {
    const std::uint32_t b = bits(rng);
    float f;
    std::memcpy(&f, &b, sizeof f);
    if (std::isfinite(f)) values.push_back(f);
  }
  values.insert(values.end(), {0.0f, -0.0f, 65504.0f, 65519.99f, 65520.0f, 1e10f, -1e10f, 1e-8f, 5.96e-8f, 2.98e-8f,
                               INFINITY, -INFINITY});
  std::vector<float> fast = values, software = values;
  round_to_half(fast.data(), fast.size());
  round_to_half_software(software.data(), software.size());
  std::printf("[ measured ] half conversion path: %s, %zu values\n", half_conversion().c_str(), values.size());
  for (std::size_t i = 0; i < values.size(); ++i)
    ASSERT_EQ(std::memcmp(&fast[i], &software[i], sizeof(float)), 0)
        << values[i] << " -> " << fast[i] << " (fast) vs " << software[i] << " (Imath)";
  EXPECT_TRUE(std::isnan(round_to_half(std::nanf(""))));
}

TEST(FlagPrecision, R11G11B10RoundingIsTheNearestRepresentableValueTiesToEven) {
  for (int m : {6, 5}) {
    const std::vector<double> table = all_ufloat_values(m);
    // Every representable value and every midpoint between neighbours (ties go to the even code).
    for (std::size_t i = 0; i + 1 < table.size(); ++i) {
      ASSERT_EQ(round_to_ufloat(static_cast<float>(table[i]), m), static_cast<float>(table[i]));
      const float mid = static_cast<float>((table[i] + table[i + 1]) / 2);
      ASSERT_EQ(round_to_ufloat(mid, m), static_cast<float>(table[i % 2 == 0 ? i : i + 1])) << "tie at " << mid;
      const float below = std::nextafter(mid, 0.0f), above = std::nextafter(mid, 1e30f);
      ASSERT_EQ(round_to_ufloat(below, m), static_cast<float>(table[i]));
      ASSERT_EQ(round_to_ufloat(above, m), static_cast<float>(table[i + 1]));
    }
    EXPECT_EQ(round_to_ufloat(-1.0f, m), 0.0f);
    EXPECT_EQ(round_to_ufloat(1e9f, m), static_cast<float>(table.back()));
  }
  EXPECT_EQ(round_layer_value(1.0f + 1.0f / 128, LayerPrecision::r11g11b10f, 0), 1.0f);  // tie, even
  EXPECT_EQ(round_layer_value(1.0f + 3.0f / 128, LayerPrecision::r11g11b10f, 0), 1.0f + 4.0f / 128);
  EXPECT_EQ(round_layer_value(1.0f + 1.0f / 64, LayerPrecision::r11g11b10f, 0), 1.0f + 1.0f / 64);  // R: exact
  EXPECT_EQ(round_layer_value(1.0f + 1.0f / 64, LayerPrecision::r11g11b10f, 2), 1.0f);  // B, 5 bits: tie, even
}

// ---------------------------------------------------------------------------------------------
// Round trip of real layer values through each format, against the format's bound.
//   f16 (10 stored mantissa bits + the implicit one): |v' - v| <= 2^-11 v for normal values, and
//       <= 2^-25 (half the subnormal spacing 2^-24) below 2^-14.
//   r11g11b10f: <= 2^-7 v (R, G: 6 bits) / 2^-6 v (B: 5 bits); below 2^-14 half the subnormal
//       spacing, 2^-21 / 2^-20.
//   unorm10_bracketed: |v' - v| <= scale / 1023 / 2 of the value's (row, layer, channel);
//   unorm16_bracketed: <= scale / 65535 / 2. Plus the float rounding of offset + scale * code / L:
//       a few ulps of offset + scale, bounded here by 2^-21 (offset + scale).
// (Toward-zero rounding, which Vulkan allows a GPU, doubles the float bounds and makes the unorm
// ones one full code; the GPU test below uses those.)
double cpu_format_bound(LayerPrecision p, const FlagLayers& stored, double v, int y, int z, int c) {
  switch (p) {
    case LayerPrecision::f16: return std::ldexp(v, -11) + std::ldexp(1.0, -25);
    case LayerPrecision::r11g11b10f: {
      const int m = c == 2 ? 5 : 6;
      return std::ldexp(v, -(m + 1)) + std::ldexp(1.0, -15 - m);
    }
    default: {
      const double offset = stored.bracket_offset[stored.bracket_index(y, z, c)];
      const double scale = stored.bracket_scale[stored.bracket_index(y, z, c)];
      return scale / bracket_levels(p) / 2 + std::ldexp(offset + scale, -21) + 1e-30;
    }
  }
}

class LayerRoundTrip : public ::testing::TestWithParam<LayerPrecision> {};

TEST_P(LayerRoundTrip, EveryStoredValueWithinItsFormatBound) {
  const LayerPrecision p = GetParam();
  const SceneLayers s = scene_layers("hoops", 192, 128, {21, 2});
  const FlagLayers exact = flag_horizontal(s.coc.packed, s.pattern, LayerPrecision::f32, 2);
  const FlagLayers stored = flag_horizontal(s.coc.packed, s.pattern, p, 2);
  const double ratio = worst_ratio(exact, stored, [&](double v, int y, int z, int c) {
    return cpu_format_bound(p, stored, v, y, z, c);
  });
  report(std::string("layer round trip, worst error / bound, ") + to_string(p), ratio, 1.0);
  EXPECT_LE(ratio, 1.0);
  EXPECT_GT(ratio, 0.25) << "the bound is far from tight: is the format really being emulated?";
}

INSTANTIATE_TEST_SUITE_P(Formats, LayerRoundTrip,
                         ::testing::Values(LayerPrecision::f16, LayerPrecision::r11g11b10f,
                                           LayerPrecision::unorm10_bracketed, LayerPrecision::unorm16_bracketed),
                         [](const auto& info) { return std::string(to_string(info.param)); });

TEST(FlagPrecision, BracketOffsetsAndScalesSpanEachRowLayerAndChannel) {
  const SceneLayers s = scene_layers("pillars", 64, 48, {9, 2});
  const FlagLayers exact = flag_horizontal(s.coc.packed, s.pattern, LayerPrecision::f32, 2);
  const FlagLayers stored = flag_horizontal(s.coc.packed, s.pattern, LayerPrecision::unorm10_bracketed, 2);
  ASSERT_EQ(stored.bracket_offset.size(), static_cast<std::size_t>(48 * 5 * 3));
  for (int y = 0; y < 48; ++y)
    for (int z = 0; z < 5; ++z)
      for (int c = 0; c < 3; ++c) {
        float lo = 1e30f, hi = -1e30f;
        for (int x = 0; x < 64; ++x) lo = std::min(lo, exact.at(x, y, z)[c]), hi = std::max(hi, exact.at(x, y, z)[c]);
        ASSERT_EQ(stored.bracket_offset[stored.bracket_index(y, z, c)], lo);
        ASSERT_EQ(stored.bracket_scale[stored.bracket_index(y, z, c)], hi - lo);
      }
}

// Bracketing against the plain format of the same texel size, on the same realistic layer data:
// unorm10_bracketed vs r11g11b10f (4 B), unorm16_bracketed vs f16 (8 B). Both the layer values'
// RMS and max error, and the final image's RMSE against f32 FLAG.
TEST(FlagPrecision, BracketedBeatsThePlainFormatOfTheSameSize) {
  for (const char* name : {"hoops", "pillars"}) {
    const SceneLayers s = scene_layers(name, 192, 128, {21, 2});
    const FlagLayers exact = flag_horizontal(s.coc.packed, s.pattern, LayerPrecision::f32, 2);
    const Image exact_out = flag_vertical(exact, s.pattern, 2);
    struct Pair {
      LayerPrecision bracketed, plain;
    };
    for (const Pair pair : {Pair{LayerPrecision::unorm10_bracketed, LayerPrecision::r11g11b10f},
                            Pair{LayerPrecision::unorm16_bracketed, LayerPrecision::f16}}) {
      const FlagLayers b = flag_horizontal(s.coc.packed, s.pattern, pair.bracketed, 2);
      const FlagLayers f = flag_horizontal(s.coc.packed, s.pattern, pair.plain, 2);
      const LayerErrors eb = layer_errors(exact, b), ef = layer_errors(exact, f);
      const double rb = compare_images(flag_vertical(b, s.pattern, 2), exact_out).rmse;
      const double rf = compare_images(flag_vertical(f, s.pattern, 2), exact_out).rmse;
      const std::string tag = std::string(name) + ", " + to_string(pair.bracketed) + " / " + to_string(pair.plain);
      report("layer RMS error ratio, " + tag, eb.rms / ef.rms, 1.0);
      report("layer max error ratio, " + tag, eb.max / ef.max, 1.0);
      report("output RMSE ratio, " + tag, rb / rf, 1.0);
      EXPECT_LT(eb.rms, ef.rms) << tag;
      EXPECT_LT(eb.max, ef.max) << tag;
      EXPECT_LT(rb, rf) << tag;
    }
  }
}

TEST(FlagPrecision, UnsignedPrecisionsRejectNegativeColours) {
  Scene s = make_scene("hoops", 32, 24);
  s.color.px(5, 7)[1] = -0.25f;
  const FilterOptions f16 = flag_options({5, 2}, "f16");
  EXPECT_NO_THROW(run_cpu(find_method("flag"), s.color, s.depth_m, s.lens, f16, 1));  // signed formats: fine
  for (const char* p : {"r11g11b10f", "unorm10_bracketed", "unorm16_bracketed"})
    for (int scale : {1, 2}) {
      FilterOptions o = flag_options({5, 2}, p);
      o.buffer_scale = scale;
      for (bool gpu : {false, true}) {
        try {
          gpu ? run_gpu(context(), find_method("flag"), s.color, s.depth_m, s.lens, o)
              : run_cpu(find_method("flag"), s.color, s.depth_m, s.lens, o, 1);
          ADD_FAILURE() << p << " scale " << scale << (gpu ? " GPU" : " CPU") << " accepted a negative colour";
        } catch (const std::invalid_argument& e) {
          EXPECT_NE(std::string(e.what()).find("pixel (5, 7)"), std::string::npos) << e.what();
          EXPECT_NE(std::string(e.what()).find("colours must be >= 0"), std::string::npos) << e.what();
        }
      }
    }
}

// ---------------------------------------------------------------------------------------------
// GPU against the CPU emulation, every precision at every scale (hoops, 96x64, N = 13, k = 2).
// Per output value, with v_j the 2n+1 layer values the vertical pass adds (all >= 0):
//   f32: 1e-5 of the image's largest value (f32 summation in another order; as test_gpu).
//   f16 / r11g11b10f: each stored value may differ by one ulp, 2^-m v_j (m = 10 half, 6 R/G, 5 B),
//       as Vulkan lets the GPU round toward zero where the CPU rounds to nearest; summed:
//       2^-m sum_j v_j = 2^-m * (f32 output), plus (2n+1) subnormal spacings.
//   bracketed: each stored value may differ by one code, scale_j / L: sum_j scale_j / L over the
//       rows and layers the pixel reads (the CPU's brackets; the GPU's own min/max are the same f32
//       values up to rounding), plus 2^-20 of sum_j (offset_j + scale_j) for float rounding.
// At scale s > 1 the same per low-res pixel, then the upsample mixes four low-res values with
// weights summing to one: bound = the largest of the four low-res bounds, plus 2^-20 relative.
struct GpuCase {
  LayerPrecision precision;
  int scale;
};

class GpuMatchesEmulation : public ::testing::TestWithParam<GpuCase> {};

Image low_res_bound(LayerPrecision p, const ReducedFlag& emu, const Image& exact_low) {
  const GatherPattern& pat = emu.pattern;
  const int n = pat.half(), k = pat.spacing_px;
  Image bound(exact_low.width, exact_low.height, 3);
  for (int y = 0; y < bound.height; ++y)
    for (int x = 0; x < bound.width; ++x)
      for (int c = 0; c < 3; ++c) {
        const double out = exact_low.px(x, y)[c];
        double b = 0;
        if (p == LayerPrecision::f32) {
          b = 0;  // set globally below
        } else if (!is_bracketed(p)) {
          const int m = p == LayerPrecision::f16 ? 10 : (c == 2 ? 5 : 6);
          const double subnormal = std::ldexp(1.0, p == LayerPrecision::f16 ? -24 : -14 - m);
          b = std::ldexp(out, -m) * (1 + 1e-3) + (2 * n + 1) * subnormal;
        } else {
          double scales = 0, magnitude = 0;
          for (int j = -n; j <= n; ++j) {
            const int sy = y + j * k;
            if (sy < 0 || sy >= bound.height) continue;
            const std::size_t i = emu.layers.bracket_index(sy, std::abs(j), c);
            scales += emu.layers.bracket_scale[i];
            magnitude += emu.layers.bracket_offset[i] + emu.layers.bracket_scale[i];
          }
          b = scales / bracket_levels(p) + std::ldexp(magnitude, -20);
        }
        bound.px(x, y)[c] = static_cast<float>(b);
      }
  return bound;
}

TEST_P(GpuMatchesEmulation, WithinTheFormatsRoundingFreedom) {
  const GpuCase gc = GetParam();
  const SceneLayers s = scene_layers("hoops", 96, 64, {13, 2});
  FilterOptions options = flag_options(s.pattern, to_string(gc.precision));
  options.buffer_scale = gc.scale;
  std::vector<vk::PassTime> passes;
  const Image gpu = run_gpu(context(), find_method("flag"), s.scene.color, s.scene.depth_m, s.lens, options, &passes);
  const ReducedFlag emu = flag_reduced(s.scene.color, s.coc.radius_px, s.pattern, gc.scale, gc.precision, 2);
  const ReducedFlag exact = flag_reduced(s.scene.color, s.coc.radius_px, s.pattern, gc.scale, LayerPrecision::f32, 2);
  const Image low = low_res_bound(gc.precision, emu, exact.blurred);

  double max_ref = 0;
  for (float v : exact.output.pixels) max_ref = std::max(max_ref, double(std::abs(v)));
  const int lw = low.width, lh = low.height, sc = gc.scale;
  double worst = 0, worst_abs = 0;
  for (int y = 0; y < gpu.height; ++y)
    for (int x = 0; x < gpu.width; ++x) {
      // The low-res pixels the upsample reads for (x, y) (itself at scale 1).
      int xs[2] = {x, x}, ys[2] = {y, y};
      if (sc > 1) {
        const float u = (x + 0.5f) / sc - 0.5f, v = (y + 0.5f) / sc - 0.5f;
        const int fu = static_cast<int>(std::floor(u)), fv = static_cast<int>(std::floor(v));
        xs[0] = std::clamp(fu, 0, lw - 1), xs[1] = std::clamp(fu + 1, 0, lw - 1);
        ys[0] = std::clamp(fv, 0, lh - 1), ys[1] = std::clamp(fv + 1, 0, lh - 1);
      }
      for (int c = 0; c < 3; ++c) {
        double b = 0;
        for (int yy : ys)
          for (int xx : xs) b = std::max(b, double(low.px(xx, yy)[c]));
        const double ref = emu.output.px(x, y)[c];
        b += gc.precision == LayerPrecision::f32 ? 1e-5 * max_ref : std::ldexp(std::abs(ref), -20) + 1e-7;
        const double err = std::abs(gpu.px(x, y)[c] - ref);
        worst = std::max(worst, err / b);
        worst_abs = std::max(worst_abs, err);
        ASSERT_LE(err, b) << "pixel (" << x << ", " << y << ") channel " << c << ": GPU " << gpu.px(x, y)[c]
                          << " CPU emulation " << ref;
      }
    }
  report(std::string("GPU vs CPU emulation, worst error / bound, ") + to_string(gc.precision) + " 1/" +
             std::to_string(gc.scale),
         worst, 1.0);
  // Every pass is timed under its own name.
  std::vector<std::string> names;
  for (const auto& pt : passes) names.push_back(pt.pass);
  std::vector<std::string> expected = {"coc"};
  if (gc.scale > 1) expected.push_back("downsample");
  if (is_bracketed(gc.precision)) expected.push_back("bracket");
  expected.insert(expected.end(), {"horizontal", "vertical"});
  if (gc.scale > 1) expected.push_back("upsample");
  EXPECT_EQ(names, expected);
}

std::vector<GpuCase> all_gpu_cases() {
  std::vector<GpuCase> cases;
  for (LayerPrecision p : all_layer_precisions())
    for (int scale : flag_buffer_scales()) cases.push_back({p, scale});
  return cases;
}

INSTANTIATE_TEST_SUITE_P(EveryPrecisionAndScale, GpuMatchesEmulation, ::testing::ValuesIn(all_gpu_cases()),
                         [](const auto& info) {
                           return std::string(to_string(info.param.precision)) + "_scale" +
                                  std::to_string(info.param.scale);
                         });

// ---------------------------------------------------------------------------------------------
// Reduced resolution.

TEST(FlagReduced, PatternKeepsTheLargestCircle) {
  const GatherPattern p41{41, 2};
  EXPECT_EQ(reduced_pattern(p41, 1).size_n, 41);
  EXPECT_EQ(reduced_pattern(p41, 2).size_n, 21);  // L' = ceil(21 / 2) = 11
  EXPECT_EQ(reduced_pattern(p41, 4).size_n, 11);  // L' = 6
  for (int s : {2, 4}) {
    EXPECT_EQ(reduced_pattern(p41, s).max_radius_px() * s, p41.max_radius_px());  // 40 px in full-res px
    const auto e = flag_buffer_extent(1920, 1080, p41, s);
    EXPECT_EQ(e.layers, reduced_pattern(p41, s).layers());
  }
  EXPECT_EQ(reduced_pattern({21, 2}, 4).max_radius_px() * 4, 16.0f);  // 21 at s = 4: 16 of 20 px
  EXPECT_THROW(reduced_pattern(p41, 3), std::invalid_argument);
}

// With every radius 0 nothing goes to the low-res buffer (w = 0): the output is the input, bit for
// bit on the CPU (sharp = 1, B = 0, any precision: an all-zero layer has scale 0 and is exact), and on
// the GPU (the same operations). Full-res f32 FLAG is the identity at radius 0 as well.
TEST(FlagReduced, ZeroRadiiGiveTheInputExactly) {
  Scene s = make_scene("hoops", 61, 43);  // odd sizes: partial blocks at the right and bottom edges
  std::fill(s.depth_m.pixels.begin(), s.depth_m.pixels.end(), static_cast<float>(s.lens.focus_distance_m));
  for (const char* precision : {"f32", "unorm10_bracketed"})
    for (int scale : flag_buffer_scales()) {
      // Full-res bracketed layers hold the colours themselves, quantised: exact only through f32.
      if (scale == 1 && std::string(precision) != "f32") continue;
      FilterOptions o = flag_options({13, 2}, precision);
      o.buffer_scale = scale;
      const Image cpu = run_cpu(find_method("flag"), s.color, s.depth_m, s.lens, o, 2);
      const Image gpu = run_gpu(context(), find_method("flag"), s.color, s.depth_m, s.lens, o);
      for (std::size_t p = 0; p < s.color.pixel_count(); ++p)
        for (int c = 0; c < 3; ++c) {
          ASSERT_EQ(cpu.pixels[p * 3 + c], s.color.pixels[p * 3 + c]) << precision << " 1/" << scale << " CPU";
          ASSERT_EQ(gpu.pixels[p * 3 + c], s.color.pixels[p * 3 + c]) << precision << " 1/" << scale << " GPU";
        }
    }
}

// Constant large CoC: full-res FLAG averages a disc of radius R sampled every k px; the reduced
// pipelines average the same disc sampled every s k px of an s x s box-filtered image, then
// interpolate bilinearly. Their difference is the sampling error of that disc mean, which shrinks
// as the disc holds more samples (~R / (s k) per axis): it must fall as R grows and stay a small
// fraction of what the blur itself changes (RMSE of input vs full-res result). The bounds are the
// errors measured here (hoops and pillars, 96x64, N = 41, k = 2) with ~1.5x margin:
//   relative RMSE (RMSE / RMS of the full-res result) at R = 36: <= 0.15 (s = 2), 0.18 (s = 4);
//   RMSE <= 0.12 of RMSE(input, full-res result).
TEST(FlagReduced, ConstantLargeCocApproachesFullResolution) {
  const GatherPattern pattern{41, 2};
  for (const char* name : {"hoops", "pillars"}) {
    const Scene s = make_scene(name, 96, 64);
    for (int scale : {2, 4}) {
      double previous = 1e30;
      for (float radius : {12.0f, 24.0f, 36.0f}) {
        const Image r(96, 64, 1, radius);
        const Image full = flag_blur(pack_gather_input(s.color, r, pattern), pattern, LayerPrecision::f32, 2);
        const Image reduced = flag_reduced_blur(s.color, r, pattern, scale, LayerPrecision::f32, 2);
        double rms = 0;
        for (float v : full.pixels) rms += double(v) * v;
        rms = std::sqrt(rms / full.pixels.size());
        const double rmse = compare_images(reduced, full).rmse, blur = compare_images(s.color, full).rmse;
        const std::string tag = std::string(name) + " 1/" + std::to_string(scale) + " R " + std::to_string(int(radius));
        report("relative RMSE vs full res, " + tag, rmse / rms, radius == 36.0f ? (scale == 2 ? 0.15 : 0.18) : 1.0);
        report("RMSE / RMSE(input vs full res), " + tag, rmse / blur, 0.12);
        EXPECT_LT(rmse, previous) << tag << ": error should fall as the circles grow";
        EXPECT_LE(rmse / blur, 0.12) << tag;
        if (radius == 36.0f) {
          EXPECT_LE(rmse / rms, scale == 2 ? 0.15 : 0.18) << tag;
        }
        previous = rmse;
      }
    }
  }
}

// ---------------------------------------------------------------------------------------------
// Memory: the paper's printed figures (f16) and the driver's sizes for every format.

TEST(FlagBufferMemory, PaperFiguresAndDriverSizesForEveryPrecision) {
  const GatherPattern k41{41, 2};
  // 332 / 42 / 5.2 "MB" (MiB) at 1080p, 41x41, RGBA16F; the other formats scale by bytes per texel.
  // The paper prints them to the last digit shown: 332.2 -> 332, 41.5 -> 42, 5.19 -> 5.2.
  const double printed[] = {332.0, 42.0, 5.2}, digit[] = {0.5, 0.5, 0.05};
  for (int i = 0; i < 3; ++i) {
    const int scale = 1 << i;
    EXPECT_NEAR(flag_paper_bytes(1920, 1080, k41, LayerPrecision::f16, scale) / kMiB, printed[i], digit[i]);
    for (LayerPrecision p : all_layer_precisions()) {
      EXPECT_DOUBLE_EQ(flag_paper_bytes(1920, 1080, k41, p, scale),
                       flag_paper_bytes(1920, 1080, k41, LayerPrecision::f16, scale) * bytes_per_texel(p) / 8.0);
      const auto e = flag_buffer_extent(1920, 1080, k41, scale);
      const auto driver = vk::image_3d_requirement_bytes(context(), layer_format(p), e.width, e.height, e.layers);
      const auto texels = flag_texel_bytes(1920, 1080, k41, p, scale);
      EXPECT_GE(driver, texels) << to_string(p) << " 1/" << scale;
      EXPECT_LT(driver, texels + texels / 8) << to_string(p) << " 1/" << scale << ": padding over 12.5%";
      if (scale == 1)
        std::printf("[ measured ] %-18s 1080p N=41 full: paper convention %.2f MiB, driver %.2f MiB\n", to_string(p),
                    flag_paper_bytes(1920, 1080, k41, p, 1) / kMiB, driver / kMiB);
    }
  }
  // An aligned extent has no padding: the driver's bytes per texel are the format's.
  for (LayerPrecision p : all_layer_precisions())
    EXPECT_EQ(vk::image_3d_requirement_bytes(context(), layer_format(p), 64, 64, 8),
              64ull * 64 * 8 * bytes_per_texel(p))
        << to_string(p);
}

}  // namespace
}  // namespace bokeh
