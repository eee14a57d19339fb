// Shared by every bokeh compute pass: workgroup size, the frame's parameters, the disc test
// (disc.glsl, which graphics shaders include on their own), pixel indexing.
layout(local_size_x_id = 100, local_size_y_id = 101) in;

layout(push_constant) uniform Params {
  int width_px;
  int height_px;
  int half_n;         // (N - 1) / 2
  int spacing_px;     // k
  float coc_scale_px; // r = coc_scale_px * |D - P| / D, see kernels/core/lens.hpp
  float focus_m;
  float max_radius_px;
  // FLAG streamed (kernels/flag/flag_gpu.hpp): the rows [band_y0_px, band_y1_px) one dispatch of a
  // band covers; its invocation rows count from band_y0_px. Other passes leave them 0 and ignore them.
  int band_y0_px;
  int band_y1_px;
} params;

#include "disc.glsl"

bool outside(ivec2 p) { return p.x >= params.width_px || p.y >= params.height_px; }
uint index_of(ivec2 p) { return uint(p.y * params.width_px + p.x); }
