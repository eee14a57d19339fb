#pragma once
// hexagon: the two-pass hexagonal bokeh of Need for Speed: The Run (White & Barre-Brisebois, SIGGRAPH
// 2011), as the blog write-up of it describes (references: hexagonal-separable-bokeh).
// Three one-sided 1D blurs at 120 degrees make three rhombi that tile a hexagon:
//   pass 1  out1 = B_up(I);  out2 = B_up(I) + B_downleft(I)               (two outputs)
//   pass 2  result = (B_downleft(out1) + B_downright(out2)) / 3           (three rhombi)
// A hexagon of circumradius r (its CoC radius): vertices straight up and down, vertical sides at
// x = +-r sqrt(3)/2. "B_d" spreads a pixel's light from it along d over its CoC; as a gather, pixel p
// reads the samples p + t g, t = 0..T (T = the largest CoC, whole pixels, unit steps), g = -d:
//   up (0, -1): g = (0, 1);  down-left (-sqrt3/2, 1/2): g = (sqrt3/2, -1/2);  down-right: g = (-sqrt3/2, -1/2)
// (image y points down). An off-axis sample is the four texels around p + t g, each with its bilinear
// weight (the write-up samples filtered textures) and each tested with its own CoC ("the CoCSize of
// that pixel"); samples beyond the image's outermost pixel centres add nothing (signed_coc.hpp).
//
// Per-pixel CoC (scatter-as-gather), as the write-up has it: a sample (texel) at t px from pixel p,
// with signed CoC s (near negative) against the pixel's own c, is "added in" with the coverage
//   w = clamp(|s| - t + 1, 0, 1)          "blend in the contribution as the CoC goes from t to t - 1 px"
//   x 0                                   if s is behind the focus plane and c in front of it,
//   x clamp(2c - s + 1, 0, 1)             if both are behind: "not too far behind" (CoC at most 2c);
// the sample at t = 0 (the pixel itself) has w = 1 - min(|CoC|, 1) / 2. Choices the write-up leaves
// open, and ours:
//   - the pixel itself counts half once its CoC reaches a pixel: the three rhombi share their edges
//     (the lines t = 0 of each blur), which would otherwise be lit twice; the Frostbite code the
//     write-up deciphers offsets its samples by half a texel for this ("this offset is important").
//   - normalisation: each sample adds w colour / extent(s), extent(s) = |s| + w_centre(s): a source
//     of CoC r spreads over t = 0..r, whose weights sum to exactly that, so every source's light sums
//     to its colour (as the FLAG paper's gather divides by the disc's area) and "each blur preserves
//     the total brightness", at any CoC. (Godot's hexagon mode divides by the fixed tap count and
//     gives non-contributing taps the centre colour instead: a point of CoC below the largest then
//     keeps a spike at its centre.)
//   - the CoC of the first pass's outputs, which the second pass tests and divides by: the mean of the
//     samples' CoCs weighted by w extent(s), towards large CoCs as the Frostbite slides weight by CoC
//     (and never zero, so it is continuous): a near light's streak over a sharp background keeps
//     ~its CoC and spreads into rhombi in the second pass; out2's is the same mean over both blurs.
//   - the "too far behind" cut gets the soft edge's one-pixel ramp: every weight is then continuous
//     in the CoCs, so CPU and GPU agree and nothing pops as a CoC changes by less than a pixel (the
//     reason the write-up softens the edge).
//   - what the rule hides is filled: a blur whose included samples fill a view v = sum w / extent < 1
//     while the rule hid a share h = sum (coverage - w) / extent is scaled by min(v + h, 1) / v, i.e.
//     the hidden share takes the mean colour of what is visible, up to a full view (as the harness's
//     depth-ordered reference fills a hidden surface's share). Without it a blurred foreground keeps a
//     dark rim inside its edges, where the background it hides would have added light; a sharp pixel
//     (v = 1) and any pixel the rule hides nothing from (h = 0) are unchanged.
// Rotation (the aperture blades6 at any rotation): the hexagon turned clockwise by the rotation modulo
// 60 degrees (a hexagon repeats every 60) is tiled by the same three rhombi with the three directions
// turned with it. Away from 0 the up blur leaves the pixel grid too, so all three sample bilinearly
// (at 0 the up blur reads whole texels, as the write-up's does). The directions are floats both sides
// use as they are, so CPU and GPU still run the same operations.
// For exactness at radius 0, out2 holds the mean (B_up + B_downleft) / 2 and the result is computed as
// R1 + (R2 - R1) 2/3 with R1 = B_downleft(out1), R2 = B_downright(out2): the same (R1 + 2 R2) / 3.
//
// Energy: each blur spreads every texel's light over its own extent with weights summing to one, so
// light is conserved away from the borders wherever the near/far rule lets every sample through (at a
// constant CoC, or all in front of the focus plane, or all behind it within a factor 2: tested). The
// rule drops light it deems hidden (the fill above puts some back, as the visible mean), and with
// mixed CoCs the second pass spreads a pixel of several contributions by their one mean CoC, which
// places (not loses) light approximately: a near object over a blurred background shows rim lines
// and, in its holes, triangular traces of the one-sided blurs (the write-up: "this isn't perfect").
#include <vector>

#include "image.hpp"
#include "parallel.hpp"

namespace bokeh {

// sqrt(3) / 2 and 2 / 3 as floats, as shaders/hexagon/hexagon.glsl spells them.
inline constexpr float kHexagonSin60 = 0.866025388240814208984375f;
inline constexpr float kHexagonTwoThirds = 0.666666686534881591796875f;

// The soft edge: how much of a sample (texel) of signed CoC s reaches t px (t >= 1).
float hexagon_coverage(float sample_coc, float distance_px);
// The near/far rule: how much of a sample of signed CoC s the pixel of signed CoC c lets in.
float hexagon_rule(float sample_coc, float centre_coc);
// The weight of the pixel itself (t = 0): 1 at CoC 0, 1/2 from a CoC of one pixel on.
float hexagon_centre_weight(float coc);
// What a pixel's weights along one direction sum to, its centre's included: |CoC| + centre weight.
float hexagon_extent(float coc);

// The three gather directions g = -d (unit vectors in image coordinates, y down) as floats: at rotation
// 0 exactly the write-up's (0, 1), (sqrt3/2, -1/2), (-sqrt3/2, -1/2), otherwise those turned clockwise
// by rotation_deg modulo 60 degrees.
struct HexagonDirections {
  float up[2], downleft[2], downright[2];
  bool up_on_axis = true;  // up is (0, 1): its taps are whole texels
};
HexagonDirections hexagon_directions(double rotation_deg);

struct HexagonPasses {
  Image up, up_downleft_mean;  // pass 1: out1 and out2 / 2 (RGBA: rgb, the weighted mean signed CoC)
  Image result;                // pass 2: RGB
};

// signed_coc: RGBA from signed_coc_image; taps: T, the largest CoC radius in whole pixels.
HexagonPasses hexagon_passes(const Image& signed_coc, int taps, int threads = default_cpu_threads(),
                             const HexagonDirections& directions = hexagon_directions(0.0));
Image hexagon_blur(const Image& signed_coc, int taps, int threads = default_cpu_threads(),
                   const HexagonDirections& directions = hexagon_directions(0.0));

}  // namespace bokeh
