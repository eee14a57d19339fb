#include "sprites_gpu.hpp"

#include <algorithm>
#include <bit>
#include <optional>

#include "naive_gpu.hpp"
#include "vk/graphics_pipeline.hpp"
#include "vk/memory.hpp"
#include "vk/spirv.hpp"

namespace bokeh {

namespace {

constexpr VkDescriptorType kBuffer = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER;

// Mirrors the push constants of shaders/sprites/quad.vert and quad.frag.
struct TargetSize {
  std::int32_t width_px, height_px;
  std::int32_t shape_half_px;  // non-disc apertures: the gauge table's reach (0 for the disc)
};

// The sprite shape's tables (non-disc apertures): the gauges the fragments test, and sorted, the ones
// detection counts (sprite_shape_lattice).
struct ShapeTables {
  ShapeTables(vk::Context& ctx, const Aperture& aperture, const GatherPattern& pattern)
      : lattice(sprite_shape_lattice(aperture, pattern)),
        gauge(vk::make_storage_buffer(ctx, lattice.gauge.size() * sizeof(float), "sprite shape gauges")),
        sorted(vk::make_storage_buffer(ctx, lattice.sorted.size() * sizeof(float), "sorted sprite shape gauges")) {
    vk::upload(ctx, gauge, lattice.gauge.data(), lattice.gauge.size() * sizeof(float));
    vk::upload(ctx, sorted, lattice.sorted.data(), lattice.sorted.size() * sizeof(float));
  }
  ShapeLattice lattice;
  vk::Buffer gauge, sorted;
};

class SpritesGpu final : public gpu::GpuFilter {
 public:
  SpritesGpu(gpu::GpuFrame& frame, const FilterOptions& options, const SpriteSettings& settings)
      : frame_(frame),
        shape_(options.aperture.is_disc() ? std::nullopt
                                          : std::optional<ShapeTables>(std::in_place, frame.ctx, options.aperture,
                                                                       options.pattern)),
        max_sprites_(settings.max_sprites),
        counters_(frame.ctx, sizeof(SpriteCounters),
                  VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_INDIRECT_BUFFER_BIT |
                      VK_BUFFER_USAGE_TRANSFER_SRC_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT),
        sprites_(vk::make_storage_buffer(frame.ctx, std::max(1, settings.max_sprites) * sizeof(Sprite),
                                         "sprite buffer")),
        target_(frame.ctx, kSpriteTargetFormat, frame.width(), frame.height()),
        // Float options travel as their bits: specialisation data is raw 4-byte words.
        detect_(frame.ctx, vk::spirv(shape_ ? "sprites/detect_shape" : "sprites/detect"),
                std::vector<VkDescriptorType>(shape_ ? 5 : 4, kBuffer), sizeof(gpu::PassParams),
                shape_ ? std::vector<std::int32_t>{settings.max_sprites, std::bit_cast<std::int32_t>(settings.threshold),
                                                   std::bit_cast<std::int32_t>(settings.min_radius_px),
                                                   static_cast<std::int32_t>(shape_->lattice.sorted.size())}
                       : std::vector<std::int32_t>{settings.max_sprites, std::bit_cast<std::int32_t>(settings.threshold),
                                                   std::bit_cast<std::int32_t>(settings.min_radius_px)}),
        // The disc: naive's gather of the packed input, from which detection takes the sprites' colour.
        // A shape: naive's shape gather, run in two halves around detection (its weighted input).
        gather_(shape_ ? nullptr : make_naive_gpu(frame, options)),
        shape_gather_(shape_ ? std::make_unique<NaiveShapeGather>(frame, options.aperture, 0) : nullptr),
        quads_(frame.ctx, target_, vk::spirv("sprites/quad_vertex"),
               vk::spirv(shape_ ? "sprites/quad_fragment_shape" : "sprites/quad_fragment"),
               std::vector<VkDescriptorType>(shape_ ? 2 : 1, kBuffer), sizeof(TargetSize),
               vk::GraphicsPipeline::Blend::additive) {
    detect_.bind(0, frame.color);
    detect_.bind(1, shape_gather_ ? shape_gather_->weighted() : frame.packed);
    detect_.bind(2, counters_);
    detect_.bind(3, sprites_);
    quads_.bind(0, sprites_);
    if (shape_) {
      detect_.bind(4, shape_->sorted);
      quads_.bind(1, shape_->gauge);
    }
  }

  void record(VkCommandBuffer cmd, vk::TimestampQueries& timer) override {
    const std::uint32_t w = frame_.width(), h = frame_.height();
    // Reset the counters once the previous frame's draw has read them.
    VkMemoryBarrier barrier{VK_STRUCTURE_TYPE_MEMORY_BARRIER};
    vkCmdPipelineBarrier(cmd,
                         VK_PIPELINE_STAGE_DRAW_INDIRECT_BIT | VK_PIPELINE_STAGE_VERTEX_SHADER_BIT |
                             VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT | VK_PIPELINE_STAGE_TRANSFER_BIT,
                         VK_PIPELINE_STAGE_TRANSFER_BIT, 0, 0, nullptr, 0, nullptr, 0, nullptr);
    const SpriteCounters reset{{6, 0, 0, 0}, 0, 0, 0};
    vkCmdUpdateBuffer(cmd, counters_.get(), 0, sizeof(reset), &reset);
    barrier.srcAccessMask = VK_ACCESS_TRANSFER_WRITE_BIT;
    barrier.dstAccessMask = VK_ACCESS_SHADER_READ_BIT | VK_ACCESS_SHADER_WRITE_BIT;
    vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, 0, 1, &barrier, 0,
                         nullptr, 0, nullptr);
    if (shape_gather_) shape_gather_->record_pack(cmd, timer);  // stamps "shape_pack"
    detect_.dispatch(cmd, &frame_.params, w, h);
    timer.end_pass(cmd, "detect");

    if (shape_gather_) shape_gather_->record_gather(cmd, timer);  // stamps "gather"
    else gather_->record(cmd, timer);

    vk::copy_to_target(cmd, frame_.output, target_, w, h);
    const TargetSize size{frame_.params.width_px, frame_.params.height_px,
                          shape_ ? (shape_->lattice.side - 1) / 2 : 0};
    quads_.draw_indirect(cmd, &size, w, h, counters_);
    vk::copy_from_target(cmd, target_, frame_.output, w, h);
    timer.end_pass(cmd, "sprites");
  }

  std::uint64_t intermediate_bytes() const override {
    return counters_.allocated_bytes() + sprites_.allocated_bytes() + target_.allocated_bytes() +
           (shape_ ? shape_->gauge.allocated_bytes() + shape_->sorted.allocated_bytes() : 0) +
           (shape_gather_ ? shape_gather_->intermediate_bytes() : gather_->intermediate_bytes());
  }

  nlohmann::json stats() override {
    SpriteCounters c{};
    vk::download(frame_.ctx, counters_, &c, sizeof(c));
    SpriteStats s;
    s.drawn = c.draw.instanceCount;
    s.overflowed = c.overflowed;
    s.detected = s.drawn + s.overflowed;
    s.quad_pixels = static_cast<std::int64_t>((std::uint64_t{c.quad_pixels_high} << 32) | c.quad_pixels_low);
    s.max_sprites = max_sprites_;
    return to_json(s);
  }

 private:
  gpu::GpuFrame& frame_;
  std::optional<ShapeTables> shape_;  // non-disc apertures
  int max_sprites_;
  vk::Buffer counters_, sprites_;
  vk::ColorTarget target_;
  vk::ComputePipeline detect_;
  std::unique_ptr<gpu::GpuFilter> gather_;          // the disc
  std::unique_ptr<NaiveShapeGather> shape_gather_;  // any other aperture
  vk::GraphicsPipeline quads_;
};

}  // namespace

std::unique_ptr<gpu::GpuFilter> make_sprites_gpu(gpu::GpuFrame& frame, const FilterOptions& options,
                                                 const SpriteSettings& settings) {
  return std::make_unique<SpritesGpu>(frame, options, settings);
}

}  // namespace bokeh
