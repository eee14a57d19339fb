// Shared by the hexagon's two passes (kernels/hexagon/hexagon.hpp): the sample weight of the write-up's
// scatter-as-gather rule, with the same float operations as hexagon_weight() on the CPU.
const float HEX_SIN60 = 0.866025388240814208984375;   // sqrt(3) / 2 as a float
const float HEX_TWO_THIRDS = 0.666666686534881591796875;
const int HEX_UP = 0, HEX_DOWNLEFT = 1, HEX_DOWNRIGHT = 2;
// The gather directions g (HexagonDirections in kernels/hexagon/hexagon.hpp): the write-up's at
// rotation 0, turned with the aperture otherwise, where up leaves the grid too (HEX_UP_ON_AXIS 0).
// Specialisation constants 1..7, after TAPS; floats travel as their bits.
layout(constant_id = 1) const float HEX_UP_X = 0.0;
layout(constant_id = 2) const float HEX_UP_Y = 1.0;
layout(constant_id = 3) const float HEX_DOWNLEFT_X = 0.866025388240814208984375;
layout(constant_id = 4) const float HEX_DOWNLEFT_Y = -0.5;
layout(constant_id = 5) const float HEX_DOWNRIGHT_X = -0.866025388240814208984375;
layout(constant_id = 6) const float HEX_DOWNRIGHT_Y = -0.5;
layout(constant_id = 7) const int HEX_UP_ON_AXIS = 1;
vec2 hex_direction(const int direction) {
  return direction == HEX_UP ? vec2(HEX_UP_X, HEX_UP_Y)
                             : direction == HEX_DOWNLEFT ? vec2(HEX_DOWNLEFT_X, HEX_DOWNLEFT_Y)
                                                         : vec2(HEX_DOWNRIGHT_X, HEX_DOWNRIGHT_Y);
}
const int OUTPUTS = 4;  // adjacent pixels per invocation; kernels/hexagon/hexagon_gpu.cpp dispatches for it

// hexagon_coverage() and hexagon_rule() of hexagon.cpp: the soft edge (full at |s| >= t, none at
// |s| <= t - 1); a sample behind the focus plane only into a pixel behind it too, and fading out over
// one pixel of CoC past twice the pixel's ("not too far behind").
float hexagon_coverage(float s, float t) {
  precise const float w = clamp(abs(s) - t + 1.0, 0.0, 1.0);
  return w;
}
float hexagon_rule(float s, float c) {
  if (s < 0.0) return 1.0;
  precise const float r = c < 0.0 ? 0.0 : clamp(2.0 * c - s + 1.0, 0.0, 1.0);
  return r;
}

// hexagon_centre_weight() and hexagon_extent() of hexagon.cpp.
float hexagon_centre_weight(float s) {
  precise const float w = 1.0 - min(abs(s), 1.0) * 0.5;
  return w;
}
float hexagon_extent(float s) {
  precise const float e = abs(s) + 1.0 - min(abs(s), 1.0) * 0.5;
  return e;
}

// One blur's sums (BlurSums of hexagon.cpp): rgb = sum w s.rgb / extent(s.a) with w = coverage x
// rule; the CoC mean's numerator and denominator, sum w extent(s.a) s.a and sum w extent(s.a); the
// view the included samples fill, sum w / extent, and the share the rule hid.
struct BlurSums {
  vec3 rgb;
  float coc_weighted, weight, view, hidden;
};

BlurSums blur_start() { return BlurSums(vec3(0.0), 0.0, 0.0, 0.0, 0.0); }

void blur_add(inout BlurSums b, vec4 s, float coverage, float rule) {
  const float extent = hexagon_extent(s.a);
  precise const float w = coverage * rule;
  precise const float colour_weight = w / extent, coc_weight = w * extent;
  precise const vec3 rgb = b.rgb + s.rgb * colour_weight;
  precise const float coc_weighted = b.coc_weighted + s.a * coc_weight;
  precise const float weight = b.weight + coc_weight;
  precise const float view = b.view + colour_weight;
  precise const float hidden = b.hidden + (coverage - w) / extent;
  b.rgb = rgb;
  b.coc_weighted = coc_weighted;
  b.weight = weight;
  b.view = view;
  b.hidden = hidden;
}

// The blurred colour with its hidden share filled by the mean of what is visible, up to a full view.
vec3 blur_result(BlurSums b) {
  precise const float fill = b.view < 1.0 ? min(b.view + b.hidden, 1.0) / b.view : 1.0;
  precise const vec3 r = b.rgb * fill;
  return r;
}
