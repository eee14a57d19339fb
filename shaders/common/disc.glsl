// The disc test every pass shares, compute or graphics. Mirrors kernels/core/gather_pattern.hpp: disc
// membership is float(dx^2 + dy^2) <= r^2 with integer offsets, so GPU and CPU agree bit for bit.

bool in_disc(float radius_sq, int dx_px, int dy_px) {
  return float(dx_px * dx_px + dy_px * dy_px) <= radius_sq;
}

// The disc as an integer (kernels/core/gather_pattern.hpp has the reasoning and the CPU twins, which
// the tests check against in_disc): in_disc(radius_sq, dx, dy) <=> dx^2 + dy^2 <= disc_threshold,
// the largest integer whose float is <= radius_sq. Written with selects, no branches: cheap per lane.
int disc_threshold(float radius_sq) {
  const uint bits = floatBitsToUint(radius_sq);
  const int half_ulp = 1 << clamp(int((bits >> 23) & 0xffu) - 127 - 24, 0, 28);
  const int above = int(min(radius_sq, 1073741824.0)) + half_ulp - int(bits & 1u);  // radius_sq >= 2^24
  const int t = radius_sq < 16777216.0 ? int(radius_sq) : above;
  return radius_sq >= 0.0 ? t : -1;  // NaN: no sample is inside
}

// floor(sqrt(d)) for 0 <= d < 2^24: one correction each way absorbs the device's sqrt rounding.
int isqrt(int d) {
  int z = int(sqrt(float(d)));
  z += int((z + 1) * (z + 1) <= d);
  z -= int(z * z > d);
  return z;
}

// On a pattern of spacing k: in_disc(radius_sq, i k, j k) <=> i^2 + j^2 <= disc_index, capped at
// `cap` (2 n^2: every sample inside). -1: none. Pass k as a specialisation constant where it runs per
// lane, so the division becomes a multiply.
int disc_index(float radius_sq, int spacing_px, int cap) {
  const int t = disc_threshold(radius_sq);
  return t < 0 ? -1 : min(t / (spacing_px * spacing_px), cap);
}

// floor(sqrt(d)) for 0 <= d < 2^18, a disc index's range (2 n^2 <= 20000 for N <= 201), with no
// correction: sqrt(d + 0.5) lies more than 0.25 / (m + 1) from both m = floor(sqrt(d)) and m + 1, more
// than 4 ULP of the sqrt there (Vulkan allows 3).
int isqrt_index(int d) {
  return int(sqrt(float(d) + 0.5));
}

// Largest layer z <= max_layer with i^2 + z^2 <= index, or -1 if column i is outside the disc.
int reach_layer(int index, int i, int max_layer) {
  const int d = index - i * i;
  return d < 0 ? -1 : min(isqrt_index(max(d, 0)), max_layer);
}

// Largest layer z the disc reaches from horizontal offset dx, or -1 if it misses the column.
int disc_reach_layer(float radius_sq, int dx_px, int spacing_px, int max_layer) {
  const int t = disc_threshold(radius_sq) - dx_px * dx_px;
  return t < 0 ? -1 : min(isqrt(min(t / (spacing_px * spacing_px), max_layer * max_layer)), max_layer);
}
