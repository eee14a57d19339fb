// The rows of FLAG's layer buffer (included by layers.glsl and vertical.comp). Full buffer
// (LAYER_ROWS = 0): one row of layers per row of FLAG's grid. Streamed (the method's option
// layer_buffer = streamed, kernels/flag/flag_gpu.hpp): a ring of LAYER_ROWS rows, row y stored in
// row y mod LAYER_ROWS, filled band by band (params.band_y0_px .. band_y1_px) as the vertical pass
// moves down: LAYER_ROWS >= band + 2 n k, so every row a band's vertical pass reads is still there.
layout(constant_id = 7) const int LAYER_ROWS = 0;

// An if on a specialization constant, not a ?:, so that no % by 0 is ever evaluated; the driver
// drops the dead side when it specialises.
int layer_row(int y) {
  if (LAYER_ROWS > 0) return y % LAYER_ROWS;
  return y;
}

// Rows of the frame this dispatch covers: invocation row r is frame row band_y0_px + r; rows from
// band_y1_px on belong to the next band (streamed) or are past the frame (full: band_y1_px = height).
int band_row(int invocation_row) { return invocation_row + params.band_y0_px; }
bool outside_band(ivec2 p) { return p.x >= params.width_px || p.y >= params.band_y1_px; }
