// The disc test every pass shares, compute or graphics. Mirrors kernels/core/gather_pattern.hpp: disc
// membership is float(dx^2 + dy^2) <= r^2 with integer offsets, so GPU and CPU agree bit for bit.

bool in_disc(float radius_sq, int dx_px, int dy_px) {
  return float(dx_px * dx_px + dy_px * dy_px) <= radius_sq;
}

// Largest layer z the disc reaches from horizontal offset dx, or -1 if it misses the column.
int disc_reach_layer(float radius_sq, int dx_px, int spacing_px, int max_layer) {
  if (!in_disc(radius_sq, dx_px, 0)) return -1;
  int z = int(sqrt(max(radius_sq - float(dx_px * dx_px), 0.0)) / float(spacing_px));
  z = min(z, max_layer);
  while (z < max_layer && in_disc(radius_sq, dx_px, (z + 1) * spacing_px)) ++z;
  while (z > 0 && !in_disc(radius_sq, dx_px, z * spacing_px)) --z;
  return z;
}
