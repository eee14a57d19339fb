#pragma once
// Each pass against the machine's limits, measured in the same run: the copy probe's bandwidth and
// the FMA probe's arithmetic rate (calibration.hpp). A pass's work is what its method declares
// (work.passes: taps, bytes read and written), so the distance to a limit is the declared work's.
#include <nlohmann/json.hpp>

namespace bokeh {

// A tap adds one weighted RGBA sample: at least one vec4 multiply-add, 8 FLOPs. The FMA probe's
// FLOP rate / kTapFlops bounds the taps a second a pass can reach (FLAG's horizontal taps only add,
// so for it this is a loose ceiling).
inline constexpr double kTapFlops = 8;

// Adds to each pass's throughput of each point (point.throughput.<pass>: taps_per_s, gb_per_s) its
// fraction_of_copy_bandwidth, fraction_of_fma_taps and taps_per_byte, against limits
// (measurement.limits: <backend>_copy_gb_per_s, <backend>_fma_gflop_per_s); for a fused pass also
// fraction_of_copy_unfused, its speed counted as the unfused passes' bytes (unfused_gb_per_s).
void add_roofline(nlohmann::json& points, const nlohmann::json& limits);

// The summary's table: per method, variant, backend, precision and pass, the range over the run's
// points of its bandwidth and taps a second and their fractions of the limits, the pass furthest
// from its nearer limit first.
void print_roofline(const nlohmann::json& doc);

}  // namespace bokeh
