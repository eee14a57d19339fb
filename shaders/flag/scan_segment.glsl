// The scan binning's workgroups, shared by horizontal_scan.comp (the disc) and horizontal_shape_scan.comp
// (other apertures) and matching the dispatches of flag_gpu.cpp and flag_shape_gpu.cpp: a workgroup of
// 8 invocations (lavapipe's SIMD width) is 8 layers of one row segment of SEGMENT columns of one
// lattice phase. Included after layer_rows.glsl (band_row) and common.glsl (params).
#extension GL_KHR_shader_subgroup_ballot : require
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

// The samples are loaded in batches of consecutive ones, one a lane, and those that reach the
// workgroup's layers are handed to all lanes in turn (lavapipe loads an address the lanes share lane by
// lane): x = the batch's size (the subgroup's lanes: 8 on lavapipe with AVX2, 4 without), y = this
// lane's place in it.
ivec2 sample_batch() {
  const uvec4 lanes = subgroupBallot(true);
  return ivec2(subgroupBallotBitCount(lanes), subgroupBallotExclusiveBitCount(lanes));
}

// The lowest lane of the ballot `reaching` (uniform), taken out of it.
uint take_lowest_lane(inout uvec4 reaching) {
  const uint lane = subgroupBallotFindLSB(reaching);
  reaching[lane / 32] &= ~(1u << (lane % 32));
  return lane;
}
