#pragma once
// The scan binning's order of additions on the CPU, shared by flag_horizontal_scan (the disc, flag.cpp)
// and flag_shape_horizontal_scan (other apertures, flag_shape.cpp), as the GPU's horizontal_scan.comp
// and horizontal_shape_scan.comp share scan_segment.glsl. A template, so that the per-sample interval
// test inlines into the loop it runs in (once per sample, layer and segment).
#include <algorithm>
#include <cstddef>
#include <vector>

#include "flag.hpp"
#include "gather_pattern.hpp"
#include "image.hpp"
#include "parallel.hpp"

namespace bokeh {

// `layers` layers of the packed input (rgb at .rgb) summed per row, lattice phase, segment of `segment`
// (>= 1) columns at stride k and layer z: each sample j (column x0 + j k) within n columns of the
// segment whose interval of output columns [j + first, j + last] is not empty adds itself at the
// interval's start (clamped to the segment) and subtracts itself past its end, in row order; a prefix
// sum along the segment gives the layer, rounded as `precision` stores it. row_intervals(y) returns the
// row's interval(x, z, first, last): false when the sample at column x reaches no column of layer z.
template <class RowIntervals>
FlagLayers flag_scan_layers(const Image& packed, const GatherPattern& p, int layers, LayerPrecision precision,
                            int segment, int threads, const RowIntervals& row_intervals) {
  const int n = p.half(), k = p.spacing_px, w = packed.width;
  FlagLayers out{w, packed.height, layers, {}, {}, {}};
  out.rgb.assign(static_cast<std::size_t>(w) * out.height * layers * 3, 0.0f);
  parallel_rows(packed.height, threads, [&](int y) {
    const auto interval = row_intervals(y);
    std::vector<float> diff(static_cast<std::size_t>(segment) * 3);
    for (int phase = 0; phase < k; ++phase)
      for (int c0 = 0; phase + c0 * k < w; c0 += segment) {
        const int x0 = phase + c0 * k;  // column t of the segment is x0 + t k
        const int j_lo = std::max(-n, -c0), j_hi = std::min(segment - 1 + n, (w - 1 - x0) / k);
        for (int z = 0; z < layers; ++z) {
          std::fill(diff.begin(), diff.end(), 0.0f);
          for (int j = j_lo; j <= j_hi; ++j) {
            int first = 0, last = 0;
            if (!interval(x0 + j * k, z, first, last) || j + last < 0 || j + first >= segment) continue;
            const float* s = packed.px(x0 + j * k, y);
            float* start = diff.data() + static_cast<std::size_t>(std::max(j + first, 0)) * 3;
            for (int c = 0; c < 3; ++c) start[c] += s[c];
            if (j + last + 1 < segment) {
              float* end = diff.data() + static_cast<std::size_t>(j + last + 1) * 3;
              for (int c = 0; c < 3; ++c) end[c] -= s[c];
            }
          }
          float running[3] = {0, 0, 0};
          for (int t = 0; t < segment && x0 + t * k < w; ++t)
            for (int c = 0; c < 3; ++c) {
              running[c] += diff[static_cast<std::size_t>(t) * 3 + c];
              out.at(x0 + t * k, y, z)[c] = round_layer_value(running[c], precision, c);
            }
        }
      }
  });
  return out;
}

}  // namespace bokeh
