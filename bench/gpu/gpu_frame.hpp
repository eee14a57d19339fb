#pragma once
// What every GPU filter shares: the scene uploaded once, the CoC pass writing the packed input,
// and the output buffer. A filter adds its own passes after the CoC pass.
#include <memory>
#include <string>

#include "coc.hpp"
#include "flag.hpp"
#include "gather_pattern.hpp"
#include "image.hpp"
#include "lens.hpp"
#include "vk/compute_pipeline.hpp"
#include "vk/context.hpp"
#include "vk/memory.hpp"
#include "vk/timestamps.hpp"

namespace bokeh::gpu {

// Mirrors `Params` in shaders/common.glsl.
struct PassParams {
  std::int32_t width_px, height_px, half_n, spacing_px;
  float coc_scale_px, focus_m, max_radius_px;
};

struct FilterOptions {
  GatherPattern pattern;
  // Storage of the method's intermediates (FLAG: its 3D buffer); each registered filter lists the
  // names it accepts, see FilterRegistration::precisions.
  std::string precision = "f16";
  int near_components = 0;  // circular filters: near-field component count (0: the method's own)
  int buffer_scale = 1;     // FLAG only: 3D buffer at 1/scale resolution, 1 full, 2 half, 4 quarter (kernels/flag_reduced.hpp)
};

class GpuFrame {
 public:
  GpuFrame(vk::Context& ctx, const Image& color, const Image& depth_m, const Lens& lens, const GatherPattern& pattern);

  vk::Context& ctx;
  PassParams params;
  vk::Buffer color;   // vec4 per pixel (rgb, 1)
  vk::Buffer depth;   // float per pixel, metres
  vk::Buffer packed;  // vec4 (rgb / discrete disc area, radius px), written by the CoC pass
  vk::Buffer output;  // vec4 (rgb, 1), written by the filter's last pass
  vk::ComputePipeline coc_pass;

  std::uint32_t width() const { return static_cast<std::uint32_t>(params.width_px); }
  std::uint32_t height() const { return static_cast<std::uint32_t>(params.height_px); }
  Image read_output();  // RGB
  Image read_packed();  // RGBA as the CoC pass wrote it
};

class GpuFilter {
 public:
  virtual ~GpuFilter() = default;
  // Records the filter's passes after the CoC pass, stamping each with `timer.end_pass`.
  virtual void record(VkCommandBuffer cmd, vk::TimestampQueries& timer) = 0;
  // Bytes of intermediate storage the filter allocated (driver's sizes), beyond the shared buffers.
  virtual std::uint64_t intermediate_bytes() const = 0;
};

// Runs CoC + filter as one timed submission and returns the per-pass times.
std::vector<vk::PassTime> run_frame(GpuFrame& frame, GpuFilter& filter, vk::TimestampQueries& timer);

// Runs every pipeline once over a tiny region: lavapipe JIT-compiles a pipeline on first use.
void warm_up(GpuFrame& frame, GpuFilter& filter, vk::TimestampQueries& timer);

}  // namespace bokeh::gpu
