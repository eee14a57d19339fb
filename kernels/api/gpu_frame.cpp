#include "gpu_frame.hpp"

#include <algorithm>

#include <cstdint>
#include <stdexcept>

#include <fmt/format.h>

#include "vk/spirv.hpp"

namespace bokeh::gpu {

namespace {
constexpr VkDescriptorType kBuffer = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER;

std::vector<float> to_rgba(const Image& color) {
  std::vector<float> rgba(color.pixel_count() * 4, 1.0f);
  for (std::size_t i = 0; i < color.pixel_count(); ++i)
    for (int c = 0; c < 3; ++c) rgba[i * 4 + c] = color.pixels[i * color.channels + c];
  return rgba;
}
}  // namespace

GpuFrame::GpuFrame(vk::Context& context, const Image& color_image, const Image& depth_m, const Lens& lens,
                   const GatherPattern& pattern)
    : ctx(context),
      params{color_image.width, color_image.height, pattern.half(), pattern.spacing_px,
             static_cast<float>(coc_scale_px(lens, color_image.width)), static_cast<float>(lens.focus_distance_m),
             pattern.max_radius_px()},
      // Texel usage: methods may read the colour through a TexelView (lavapipe's fast load path).
      color(vk::make_storage_buffer(ctx, color_image.pixel_count() * 16, "colour buffer",
                                    VK_BUFFER_USAGE_UNIFORM_TEXEL_BUFFER_BIT)),
      depth(vk::make_storage_buffer(ctx, depth_m.pixel_count() * 4, "depth buffer")),
      packed(vk::make_storage_buffer(ctx, color_image.pixel_count() * 16, "packed CoC buffer")),
      output(vk::make_storage_buffer(ctx, color_image.pixel_count() * 16, "output buffer")),
      disc_area(make_disc_area_buffer(ctx, pattern)),
      coc_pass(ctx, vk::spirv("common/coc"), {kBuffer, kBuffer, kBuffer, kBuffer}, sizeof(PassParams),
               {pattern.spacing_px}) {
  validate(lens);
  validate(pattern);
  const auto rgba = to_rgba(color_image);
  vk::upload(ctx, color, rgba.data(), rgba.size() * sizeof(float));
  vk::upload(ctx, depth, depth_m.pixels.data(), depth_m.pixels.size() * sizeof(float));
  coc_pass.bind(0, color);
  coc_pass.bind(1, depth);
  coc_pass.bind(2, packed);
  coc_pass.bind(3, disc_area);
}

SignedCocPass::SignedCocPass(GpuFrame& frame)
    : buffer(vk::make_storage_buffer(frame.ctx, static_cast<VkDeviceSize>(frame.width()) * frame.height() * 16,
                                     "signed-CoC buffer")),
      frame_(frame),
      pipeline_(frame.ctx, vk::spirv("common/signed_coc"), {kBuffer, kBuffer, kBuffer, kBuffer}, sizeof(PassParams)) {
  pipeline_.bind(0, frame.color);
  pipeline_.bind(1, frame.depth);
  pipeline_.bind(2, frame.packed);
  pipeline_.bind(3, buffer);
}

void SignedCocPass::dispatch(VkCommandBuffer cmd) const {
  pipeline_.dispatch(cmd, &frame_.params, frame_.width(), frame_.height());
}

vk::Buffer make_disc_area_buffer(vk::Context& ctx, const GatherPattern& pattern) {
  validate(pattern);
  const DiscAreaTable table(pattern);
  const auto& areas = table.by_index();
  vk::Buffer buffer = vk::make_storage_buffer(ctx, areas.size() * sizeof(areas[0]), "disc area table");
  vk::upload(ctx, buffer, areas.data(), areas.size() * sizeof(areas[0]));
  return buffer;
}

Image GpuFrame::read_output() {
  std::vector<float> rgba(static_cast<std::size_t>(width()) * height() * 4);
  vk::download(ctx, output, rgba.data(), rgba.size() * sizeof(float));
  Image out(params.width_px, params.height_px, 3);
  for (std::size_t i = 0; i < out.pixel_count(); ++i)
    for (int c = 0; c < 3; ++c) out.pixels[i * 3 + c] = rgba[i * 4 + c];
  return out;
}

Image GpuFrame::read_packed() {
  Image out(params.width_px, params.height_px, 4);
  vk::download(ctx, packed, out.pixels.data(), out.pixels.size() * sizeof(float));
  return out;
}

std::vector<vk::PassTime> run_frames(GpuFrame& frame, GpuFilter& filter, vk::TimestampQueries& timer, int frames) {
  try {
    frame.ctx.submit_and_wait([&](VkCommandBuffer cmd) {
      timer.begin_frame(cmd);
      for (int f = 0; f < frames; ++f) {
        frame.coc_pass.dispatch(cmd, &frame.params, frame.width(), frame.height());
        timer.end_pass(cmd, "coc");
        filter.record(cmd, timer);
      }
      timer.end_frame(cmd);
    });
  } catch (const vk::RunawaySubmission& e) {
    const std::string pass = filter.running_pass();
    throw std::runtime_error(fmt::format("{} of {} frame{} at {}x{} {}; the device still runs it, so no GPU work "
                                         "after it can run in this process",
                                         pass.empty() ? "a pass" : "pass '" + pass + "'", frames, frames == 1 ? "" : "s",
                                         frame.params.width_px, frame.params.height_px, e.what()));
  }
  return vk::mean_per_frame(timer.read(), frames);
}

PassWork coc_pass_work(const GatherPattern& /*pattern: the area lookup costs the same for every N*/, int width_px,
                       int height_px) {
  // One area-table entry per pixel (counted as its tap), colour (16 B), depth (4 B) and entry (4 B) read.
  const double pixels = static_cast<double>(width_px) * height_px;
  return {"coc", pixels, pixels * 24, pixels * 16};
}

void warm_up(GpuFrame& frame, GpuFilter& filter, vk::TimestampQueries& timer) {
  const PassParams full = frame.params;
  frame.params.width_px = std::min(full.width_px, 16);
  frame.params.height_px = std::min(full.height_px, 16);
  run_frames(frame, filter, timer);
  frame.params = full;
}

}  // namespace bokeh::gpu
