// The scan binning's workgroups, shared by horizontal_scan.comp (the disc) and horizontal_shape_scan.comp
// (other apertures) and matching the dispatches of flag_gpu.cpp and flag_shape_gpu.cpp: a workgroup of
// 8 invocations (lavapipe's SIMD width) is 8 layers of one row segment of SEGMENT columns of one
// lattice phase. Included after layer_rows.glsl (band_row) and common.glsl (params).
layout(constant_id = 6) const int SEGMENT = 256;  // output columns per workgroup, at stride k

// Workgroup (g + G s, r), G = ceil(layer_count / 8): layers z_first = 8 g .. 8 g + 7 of frame row y =
// band_row(r), phase s % k, lattice columns c0 .. c0 + SEGMENT - 1 of it, c0 = (s / k) SEGMENT;
// column t of the segment is x0 + t k, and `columns` of them lie in the frame (none where x0 is past
// it): events past them change no output, so they are dropped and only these slots are cleared
// (lavapipe clears a slot lane by lane).
struct ScanSegment {
  int y, z_first, c0, x0, columns;
};
ScanSegment scan_segment(int layer_count, int k) {
  const int groups = (layer_count + 7) / 8, s = int(gl_WorkGroupID.x) / groups;
  ScanSegment segment;
  segment.y = band_row(int(gl_WorkGroupID.y));
  segment.z_first = (int(gl_WorkGroupID.x) % groups) * 8;
  segment.c0 = (s / k) * SEGMENT;
  segment.x0 = s % k + segment.c0 * k;
  segment.columns = min(SEGMENT, (params.width_px - 1 - segment.x0) / k + 1);
  return segment;
}

#include "lane_batch.glsl"  // sample_batch, take_lowest_lane
