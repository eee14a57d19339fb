#pragma once
// What every GPU filter shares: the scene uploaded once, the CoC pass writing the packed input,
// and the output buffer. A filter adds its own passes after the CoC pass.
#include <memory>
#include <string>

#include <nlohmann/json.hpp>

#include "coc.hpp"
#include "gather_pattern.hpp"
#include "image.hpp"
#include "lens.hpp"
#include "vk/compute_pipeline.hpp"
#include "vk/context.hpp"
#include "vk/memory.hpp"
#include "vk/timestamps.hpp"
#include "work.hpp"

namespace bokeh::gpu {

// Mirrors `Params` in shaders/common/common.glsl.
struct PassParams {
  std::int32_t width_px, height_px, half_n, spacing_px;
  float coc_scale_px, focus_m, max_radius_px;
  std::int32_t band_y0_px = 0, band_y1_px = 0;  // FLAG streamed: the rows of one band's dispatch
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
  vk::Buffer disc_area;  // int per disc index: the pattern's DiscAreaTable, read by the CoC pass
  vk::ComputePipeline coc_pass;

  std::uint32_t width() const { return static_cast<std::uint32_t>(params.width_px); }
  std::uint32_t height() const { return static_cast<std::uint32_t>(params.height_px); }
  Image read_output();  // RGB
  Image read_packed();  // RGBA as the CoC pass wrote it
};

// The engine-style gathers' input (shaders/common/signed_coc.comp, kernels/core/signed_coc.hpp):
// colour with the CoC radius in alpha, negative in front of the focus plane, in `buffer` (vec4 per
// pixel). Spiral and hexagon start from it.
class SignedCocPass {
 public:
  explicit SignedCocPass(GpuFrame& frame);
  void dispatch(VkCommandBuffer cmd) const;  // over the whole frame, after the CoC pass

  vk::Buffer buffer;

 private:
  GpuFrame& frame_;
  vk::ComputePipeline pipeline_;
};

// The pattern's DiscAreaTable in a storage buffer (int per disc index), as shaders that divide by
// the discrete disc area read it.
vk::Buffer make_disc_area_buffer(vk::Context& ctx, const GatherPattern& pattern);

class GpuFilter {
 public:
  virtual ~GpuFilter() = default;
  // Records the filter's passes after the CoC pass, stamping each with `timer.end_pass`.
  virtual void record(VkCommandBuffer cmd, vk::TimestampQueries& timer) = 0;
  // Bytes of intermediate storage the filter allocated (driver's sizes), beyond the shared buffers.
  virtual std::uint64_t intermediate_bytes() const = 0;
  // What the last frame found where it depends on the scene (e.g. sprite counts and overflow), read
  // back after the frames, outside the timed region: an object, empty when there is nothing to report.
  virtual nlohmann::json stats() { return nlohmann::json::object(); }
  // While a submission runs: the pass it is in, where the filter marks its progress in host memory
  // (method packages do; "" : unknown). Timestamp queries cannot say: lavapipe answers them only
  // once the submission ends, and a runaway one never does.
  virtual std::string running_pass() const { return ""; }
};

// Runs CoC + filter `frames` times in one timed submission (a batch long enough to swamp launch
// overhead and timer resolution on a fast GPU) and returns each pass's mean time per frame.
std::vector<vk::PassTime> run_frames(GpuFrame& frame, GpuFilter& filter, vk::TimestampQueries& timer, int frames = 1);

// The CoC pass's work: it reads colour and depth, looks the discrete disc area up, and writes the
// packed input.
PassWork coc_pass_work(const GatherPattern& pattern, int width_px, int height_px);

// Runs every pipeline once over a tiny region: lavapipe JIT-compiles a pipeline on first use.
void warm_up(GpuFrame& frame, GpuFilter& filter, vk::TimestampQueries& timer);

}  // namespace bokeh::gpu
