// Samples handed from lane to lane (included by scan_segment.glsl and fused.comp): lavapipe loads an
// address the lanes share lane by lane, so the lanes load consecutive samples, one each, and those a
// workgroup needs go to every lane in turn by subgroupShuffle (registers on lavapipe).
#extension GL_KHR_shader_subgroup_ballot : require
#extension GL_KHR_shader_subgroup_shuffle : require

// The samples are loaded in batches of consecutive ones, one a lane, and those that reach the
// workgroup's layers are handed to all lanes in turn (lavapipe loads an address the lanes share lane by
// lane): x = the batch's size (the subgroup's lanes: 8 on lavapipe with AVX2, 4 without), y = this
// lane's place in it.
ivec2 sample_batch() {
  const uvec4 lanes = subgroupBallot(true);
  return ivec2(subgroupBallotBitCount(lanes), subgroupBallotExclusiveBitCount(lanes));
}

// The lowest lane of the ballot `reaching` (uniform), taken out of it; 0 from an empty ballot, which
// stays empty.
uint take_lowest_lane(inout uvec4 reaching) {
  const uint lane = reaching == uvec4(0) ? 0u : subgroupBallotFindLSB(reaching);
  reaching[lane / 32] &= ~(1u << (lane % 32));
  return lane;
}
