#pragma once
// FLAG for a non-disc aperture on the GPU (flag_shape_gpu.cpp): built on the disc's parts (flag_gpu.hpp:
// binning, streamed ring, checks), which know nothing of it.
#include <memory>

#include "aperture.hpp"
#include "flag_gpu.hpp"

namespace bokeh {

struct FlagConfig;
// FLAG for a non-disc aperture (flag_shape.hpp, flag_shape_gpu.cpp): passes shape_pack, horizontal
// (chord extents, or row sections with horizontal_bins = scan), vertical (or both as "streamed", or
// one "fused" with layer_buffer = registers), in the configurations Method::aperture_unsupported accepts
// (per-value precisions, scale 1, adaptive off) for options.aperture.
std::unique_ptr<gpu::GpuFilter> make_flag_shape_gpu(gpu::GpuFrame& frame, const FilterOptions& options);
// The horizontal pass's binning for a non-disc aperture of `layers` layers: `bins` as chosen; auto:
// indexed on GPUs, on software devices scan from 7 layers on where the device has the scan's subgroup
// operations, else indexed (flag_shape_gpu.cpp has the measurements).
FlagHorizontalBins flag_shape_binning(FlagHorizontalBins bins, const vk::DeviceInfo& device, int layers);
// The layer image of a non-disc aperture as make_flag_shape_gpu allocates it: the frame's rows, or
// (layer_buffer = streamed) the ring's B + 2 n k rows and the band B (band_rows 0: the full buffer).
FlagStreamRing flag_shape_layer_rows(const FlagConfig& config, int layers, int width_px, int height_px,
                                     bool software_device);

}  // namespace bokeh
