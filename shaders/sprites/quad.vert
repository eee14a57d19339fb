#version 450
// Sprite quads without vertex buffers (de Rousiers & Pettineo, pass 4, with the geometry shader's
// point-to-quad expansion done here): instance = sprite, vertices 0..5 = two triangles of its quad.
#extension GL_GOOGLE_include_directive : require
#include "sprite.glsl"

layout(std430, binding = 0) readonly buffer Sprites { Sprite sprites[]; };
layout(push_constant) uniform Target {
  int width_px;
  int height_px;
  int shape_half_px;  // the fragment shader's (non-disc apertures)
} target;

layout(location = 0) flat out vec3 rgb_per_pixel;
layout(location = 1) flat out ivec2 centre_px;
layout(location = 2) flat out float radius_px;

void main() {
  const Sprite s = sprites[gl_InstanceIndex];
  const int f = quad_half_px(s.radius_px);
  // Corners (0,0) (1,0) (0,1) | (0,1) (1,0) (1,1).
  const int v = gl_VertexIndex;
  const ivec2 corner = ivec2(v == 1 || v == 4 || v == 5 ? 1 : 0, v == 2 || v == 3 || v == 5 ? 1 : 0);
  // Pixel-boundary coordinates: the quad spans pixel columns p.x - f .. p.x + f, i.e. x in [p.x - f, p.x + f + 1].
  const vec2 edge_px = vec2(s.pixel_px - f + corner * (2 * f + 1));
  gl_Position = vec4(edge_px / vec2(target.width_px, target.height_px) * 2.0 - 1.0, 0.0, 1.0);
  rgb_per_pixel = s.rgb_per_pixel.rgb;
  centre_px = s.pixel_px;
  radius_px = s.radius_px;
}
