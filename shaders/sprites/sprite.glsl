// One bokeh sprite, as the detection pass appends it and the quad shaders draw it. Mirrors `Sprite`
// in kernels/sprites/sprites.hpp (std430: 32 bytes).
struct Sprite {
  ivec2 pixel_px;       // the source pixel; the sprite's disc is centred on its centre
  float radius_px;      // its CoC radius
  float pixel_count;    // pixels of its disc (integer offsets with dx^2 + dy^2 <= r^2)
  vec4 rgb_per_pixel;   // the source's colour / pixel_count: the disc's pixels sum to the colour
};

// The quad covering the disc: pixels [p - f, p + f] with f = floor(r), edges on pixel boundaries, so
// no pixel centre lies on an edge and the rasteriser's tie-breaking rule never applies.
int quad_half_px(float radius_px) { return int(radius_px); }
