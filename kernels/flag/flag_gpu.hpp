#pragma once
// FLAG on the GPU (flag_gpu.cpp): passes downsample (scale > 1), tile_max, tile_reach, tile_layers
// (adaptive = on), bracket (bracketed precisions), horizontal, vertical, upsample (scale > 1).
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "flag.hpp"
#include "flag_memory.hpp"
#include "method.hpp"

namespace bokeh {

// Pixels per invocation of the horizontal pass, at stride k (OUTPUTS in shaders/flag/layers.glsl),
// the method's option "horizontal_block": each loaded row sample serves up to that many pixels, whose
// layers stay bit for bit the same. "auto" picks 4 on CPU devices (lavapipe: a buffer load costs a
// scalar load per lane; 2 or 1 where 4 x layers would pass what lavapipe computes correctly, see
// flag_gpu.cpp) and 1 on GPUs, where 4 pixels' bins (4 x ceil(N/2) x 3 floats) would spill registers
// and the L1 cache already shares the loads.
const std::vector<std::string>& flag_horizontal_blocks();  // "auto", "1", "2", "4", "8"
// The block the pass runs: `requested` (FlagConfig::horizontal_block), or auto's choice when empty.
int flag_horizontal_block(std::optional<int> requested, const vk::DeviceInfo& device, int layers);

// How the horizontal pass bins a row sample into the layer its disc reaches, the method's option
// "horizontal_bins". "indexed" and "masked" (MASKED_BINS in shaders/flag/layers.glsl) add the same
// samples in the same order, so their layers are the same bit for bit. "indexed": bins[z] += sample,
// one add per sample (the paper's O(N + n) per pixel). "masked": every bin tests its own integer range
// of the sample's disc index and adds the sample or -0.0: O(N n) adds but no dynamically indexed
// array, which lavapipe turns into a scalar load and store per lane. "scan"
// (shaders/flag/horizontal_scan.comp): per layer, interval sums from a difference array and a prefix
// sum along a row segment of kFlagScanSegment columns: O(N) per pixel with each sample loaded once
// per 8 layers by one lane and handed to the others; the same samples per layer in another order of
// additions (flag_horizontal_scan() mirrors it bit for bit; bracketed precisions quantise its values
// with the bracket pass's ranges, which sum in the bins' order: within one code). "auto": on CPU
// devices (lavapipe) masked up to 12 layers (N = 23), scan beyond (indexed without the scan's subgroup
// operations); on GPUs indexed. flag_gpu.cpp has the measurements. Non-disc apertures
// choose their own (flag_shape_binning, flag_shape_gpu.hpp).
const std::vector<std::string>& flag_horizontal_bins();  // "auto", "indexed", "masked", "scan"
// The option's value; the enumerators in the order of flag_horizontal_bins().
enum class FlagHorizontalBins { automatic, indexed, masked, scan };
// The scan's lanes load consecutive samples and hand them to each other (subgroupBallot, subgroupShuffle):
// a device without these runs the other binnings (auto) or refuses scan.
constexpr VkSubgroupFeatureFlags kFlagScanSubgroupOperations =
    VK_SUBGROUP_FEATURE_BASIC_BIT | VK_SUBGROUP_FEATURE_BALLOT_BIT | VK_SUBGROUP_FEATURE_SHUFFLE_BIT;
// The binning the pass runs: `bins` as chosen, auto's choice by device and layers.
FlagHorizontalBins flag_horizontal_binning(FlagHorizontalBins bins, const vk::DeviceInfo& device, int layers);
// Invocations along a row of the horizontal pass (the disc's and other apertures'), `bins` resolved:
// scan, k phases x ceil(ceil(W / k) / kFlagScanSegment) segments x ceil(layers / 8) workgroups of 8
// (shaders/flag/scan_segment.glsl); else ceil(W / (block k)) k, a block of pixels at stride k each.
std::uint32_t flag_horizontal_invocations_x(FlagHorizontalBins bins, int width_px, int spacing_px, int layers,
                                            int block);

// The order the vertical pass's workgroups take their tiles, the method's option "vertical_order".
// A layer row is read twice, by output rows y - j k and y + j k; in "rows" (row-major tiles, as
// drivers launch workgroups) the rows between those two reads are k n (n + 1) rows of the frame's
// width, 75 MB of f16 layers at 800x600, N = 153: past the caches, so the second read goes to memory.
// "columns" walks 8-px column strips top to bottom (tile i = (i / tiles_y, i % tiles_y)), keeping that
// window at 8 px wide (~750 KB there). Same sums in the same order: the same image bit for bit.
// "auto": columns on CPU devices (lavapipe, measured in flag_gpu.cpp), rows on GPUs (not measured
// there: their tiled images and L2 may favour either).
const std::vector<std::string>& flag_vertical_orders();  // "auto", "rows", "columns"
enum class FlagVerticalOrder { automatic, rows, columns };
FlagVerticalOrder flag_vertical_ordering(FlagVerticalOrder order, const vk::DeviceInfo& device);

// Where the horizontal pass leaves the layers for the vertical pass, the method's option
// "layer_buffer". "full" (the reference): the paper's 3D buffer, one row of layers per row of FLAG's
// grid. "streamed": a ring of rows. The vertical pass at row y reads only rows y - n k .. y + n k, so
// the frame is cut into bands of B output rows; for each band the horizontal pass writes the rows not
// yet written up to the band's last row + n k, then the vertical pass sums the band, each a dispatch
// in the same command buffer with a barrier between. Row y of layers lives in row y mod (B + 2 n k) of
// the ring, which never overwrites a row a later band still reads. The same layer values in the same
// order of additions: the full buffer's image bit for bit (every precision), in W x min(H, B + 2 n k)
// x ceil(N/2) texels instead of W x H x ceil(N/2). "registers" (shaders/flag/fused.comp): no buffer;
// both passes fused, as the CPU reference runs them, each invocation walking down one column with its
// row's layers and the 2 n + 1 output rows in flight in registers, each layer rounded to f32 or f16
// (to nearest): the CPU reference's image bit for bit, and the full buffer's with indexed bins (f16: up
// to its store's rounding, toward zero on lavapipe, which Vulkan allows). lavapipe stores and loads a
// texel lane by lane, which is most of the full buffer's frame; a GPU has too few such invocations
// (k^2 W / 8 k workgroups of 8) and too few registers for them. Full resolution, f32 or f16, adaptive off, and a
// device with the scan's subgroup operations (kFlagScanSubgroupOperations); any aperture (polygons:
// flag_shape_gpu.cpp, chords as horizontal_shape.comp). "auto" (the default): registers where it can
// run on a CPU device (lavapipe), any aperture, else full.
const std::vector<std::string>& flag_layer_buffers();  // "auto", "full", "streamed", "registers"
enum class FlagLayerBuffer { automatic, full, streamed, registers };
// layer_buffer = registers bins masked (the option horizontal_bins = masked, or auto up to 24 layers,
// N = 47, measured in flag_gpu.cpp) or else indexed (scan runs as indexed there).
bool flag_registers_masked(FlagHorizontalBins bins, int layers);
// Why layer_buffer = registers cannot run these options (empty: it can), device aside.
std::string flag_registers_unsupported(const FilterOptions& options);
// The layer buffer `device` runs: `options`' choice, or auto's (device null: full, the reference the
// models describe where no device is named).
FlagLayerBuffer flag_layer_buffering(const FilterOptions& options, const vk::DeviceInfo* device);
// Whether `device` runs layer_buffer = registers for these options (the GPU filters of every aperture
// ask this once); throws std::invalid_argument with flag_registers_unsupported's reason where registers
// is asked for and cannot run.
bool flag_runs_registers(const FilterOptions& options, const vk::DeviceInfo& device);
// Invocations along a row of the fused pass (shaders/flag/fused.comp), the disc's and other apertures':
// k phases x ceil(ceil(W / k) / 8) workgroups of 8 columns.
std::uint32_t flag_fused_invocations_x(int width_px, int spacing_px);
// The tile-max CoC map's tile side in px for the disc's fused pass, which loads of a row only the
// samples of the tiles that can reach its columns: a tile of 16 px is one batch of 8 columns at k = 2.
inline constexpr int kFlagFusedTilePx = 16;
// Whether the fused pass of a pattern of `layers` = (N + 1) / 2 layers reads the map (its pass tile_max
// runs): the disc's from 13 layers (N = 25) on, a polygon's (a map of areas) from 15 (N = 29). Below,
// the map's pass costs more than the loads it saves on lavapipe (800x600 hoops, f16: the disc 1.23x /
// 1.09x the frame at N = 9 / 13, the same at 21, 0.94 at 33; blades5 1.023-1.026x at N = 25, 0.976 at
// 29; results/README.md).
bool flag_fused_reads_tile_map(int layers, bool shape = false);
// Output rows per band as run: `requested` (> 0, the option band_rows), or auto's (0): the largest
// band whose ring fits kFlagStreamBudgetBytes of the device kind, and at least kFlagStreamMinBand
// rows. `reach_rows` = n k of FLAG's grid, `row_bytes` = one row of layers (width x layers x texel).
int flag_stream_band_rows(int requested, bool software_device, int reach_rows, std::uint64_t row_bytes);
// Rows of the ring: B + 2 n k, at most the grid's height (then it is the full buffer's extent).
int flag_stream_ring_rows(int band_rows, int reach_rows, int height);
// The streamed ring of a layer buffer whose whole extent is `full`, on a grid of `spacing_px`: its band
// and its extent (the full width and layers, the ring's rows), as the GPU driver allocates it.
struct FlagStreamRing {
  int band_rows = 0;
  FlagBufferExtent extent;
};
FlagStreamRing flag_stream_ring(const FlagBufferExtent& full, int spacing_px, LayerPrecision precision,
                                int requested_band_rows, bool software_device);

// Bins (horizontal block x layers) a horizontal pass holds per invocation that lavapipe computes
// correctly (flag_gpu.cpp has the measurements); beyond, it returns zero layers without an error.
constexpr int kFlagSoftwareMaxBlockLayers = 324;

// Parses `options` once (flag_config) and makes the filter for the disc aperture (any other
// aperture: make_flag_shape_gpu, flag_shape_gpu.hpp, which builds on this file's parts).
std::unique_ptr<gpu::GpuFilter> make_flag_gpu(gpu::GpuFrame& frame, const FilterOptions& options);

// The unsigned formats cannot hold negative layer values: checks the uploaded colour once, with the
// CPU reference's message (check_layer_input).
void check_frame_colour(gpu::GpuFrame& frame, LayerPrecision precision);
// Throws std::invalid_argument on lavapipe for a horizontal block of more bins (block x layers) than it
// computes correctly, or bracketed layers beyond what its bracket pass does; nothing on other devices.
void check_software_bounds(const vk::DeviceInfo& device, int block, int layers, bool bracketed);

VkFormat layer_format(LayerPrecision precision);  // FLAG's 3D buffer format
// Bytes of the bracketed precisions' min/max buffer: 2 x rows x layers uvec4.
std::uint64_t flag_bracket_buffer_bytes(std::uint32_t rows, std::uint32_t layers);

}  // namespace bokeh
