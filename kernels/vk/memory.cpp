#include "memory.hpp"

#include <cstring>
#include <iterator>
#include <utility>
#include <stdexcept>

#include <fmt/format.h>

#include "vk_check.hpp"

namespace bokeh::vk {

namespace {

Handle<VkDeviceMemory> allocate_memory(Context& ctx, VkDeviceSize bytes, std::uint32_t memory_type) {
  VkMemoryAllocateInfo info{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO};
  info.allocationSize = bytes;
  info.memoryTypeIndex = memory_type;
  VkDeviceMemory memory = VK_NULL_HANDLE;
  VK_CHECK(vkAllocateMemory(ctx.device(), &info, nullptr, &memory));
  return {memory, [d = ctx.device()](VkDeviceMemory m) { vkFreeMemory(d, m, nullptr); }};
}

VkDeviceSize align_up(VkDeviceSize value, VkDeviceSize alignment) {
  return alignment > 1 ? (value + alignment - 1) / alignment * alignment : value;
}

VkImageCreateInfo image_3d_info(VkFormat format, std::uint32_t width, std::uint32_t height, std::uint32_t depth) {
  VkImageCreateInfo info{VK_STRUCTURE_TYPE_IMAGE_CREATE_INFO};
  info.imageType = VK_IMAGE_TYPE_3D;
  info.format = format;
  info.extent = {width, height, depth};
  info.mipLevels = 1;
  info.arrayLayers = 1;
  info.samples = VK_SAMPLE_COUNT_1_BIT;
  info.tiling = VK_IMAGE_TILING_OPTIMAL;
  info.usage = VK_IMAGE_USAGE_STORAGE_BIT;
  info.initialLayout = VK_IMAGE_LAYOUT_UNDEFINED;
  return info;
}

Handle<VkImage> create_image_3d(Context& ctx, VkFormat format, std::uint32_t width, std::uint32_t height,
                                std::uint32_t depth) {
  const std::uint32_t limit = ctx.info().max_image_dimension_3d;
  if (width > limit || height > limit || depth > limit)
    throw std::runtime_error(fmt::format("3D buffer {}x{}x{} exceeds the device's maxImageDimension3D {}", width,
                                         height, depth, limit));
  const VkImageCreateInfo info = image_3d_info(format, width, height, depth);
  VkImage image = VK_NULL_HANDLE;
  VK_CHECK(vkCreateImage(ctx.device(), &info, nullptr, &image));
  return {image, [d = ctx.device()](VkImage i) { vkDestroyImage(d, i, nullptr); }};
}

VkImageCreateInfo color_target_info(VkFormat format, std::uint32_t width, std::uint32_t height) {
  VkImageCreateInfo info{VK_STRUCTURE_TYPE_IMAGE_CREATE_INFO};
  info.imageType = VK_IMAGE_TYPE_2D;
  info.format = format;
  info.extent = {width, height, 1};
  info.mipLevels = 1;
  info.arrayLayers = 1;
  info.samples = VK_SAMPLE_COUNT_1_BIT;
  info.tiling = VK_IMAGE_TILING_OPTIMAL;
  info.usage = VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT | VK_IMAGE_USAGE_TRANSFER_DST_BIT;
  info.initialLayout = VK_IMAGE_LAYOUT_UNDEFINED;
  return info;
}

Handle<VkImage> create_image(Context& ctx, const VkImageCreateInfo& info) {
  VkImage image = VK_NULL_HANDLE;
  VK_CHECK(vkCreateImage(ctx.device(), &info, nullptr, &image));
  return {image, [d = ctx.device()](VkImage i) { vkDestroyImage(d, i, nullptr); }};
}

}  // namespace

MemoryBlocks::Range MemoryBlocks::allocate(const VkMemoryRequirements& req, std::uint32_t memory_type,
                                           Allocation::Kind kind, bool map) {
  for (int attempt = 0; attempt < 2; ++attempt) {
    for (auto& block : blocks_) {
      if (block->memory_type != memory_type || block->kind != kind) continue;
      for (auto it = block->free.begin(); it != block->free.end(); ++it) {
        const VkDeviceSize start = align_up(it->first, req.alignment), end = it->first + it->second;
        if (start + req.size > end) continue;
        const VkDeviceSize before = start - it->first, after = end - (start + req.size);
        block->free.erase(it);
        if (before > 0) block->free[start - before] = before;
        if (after > 0) block->free[start + req.size] = after;
        // One memory type can be both device-local and host-visible (lavapipe): map on first need.
        if (map && !block->mapped) VK_CHECK(vkMapMemory(ctx_.device(), block->memory, 0, VK_WHOLE_SIZE, 0, &block->mapped));
        return {block->memory, start, block->mapped ? static_cast<char*>(block->mapped) + start : nullptr};
      }
    }
    auto block = std::make_unique<Block>();
    block->memory = allocate_memory(ctx_, Allocation::kBlockBytes, memory_type);
    block->memory_type = memory_type;
    block->kind = kind;
    block->free[0] = Allocation::kBlockBytes;
    if (map) VK_CHECK(vkMapMemory(ctx_.device(), block->memory, 0, VK_WHOLE_SIZE, 0, &block->mapped));
    blocks_.push_back(std::move(block));
  }
  throw std::logic_error("MemoryBlocks: a small request did not fit a new block");
}

void MemoryBlocks::release(VkDeviceMemory memory, VkDeviceSize offset, VkDeviceSize size) {
  for (auto& block : blocks_) {
    if (block->memory.get() != memory) continue;
    auto next = block->free.emplace(offset, size).first;
    if (auto after = std::next(next); after != block->free.end() && next->first + next->second == after->first) {
      next->second += after->second;
      block->free.erase(after);
    }
    if (next != block->free.begin())
      if (auto before = std::prev(next); before->first + before->second == next->first) {
        before->second += next->second;
        block->free.erase(next);
      }
    return;
  }
}

MemoryBlocks& Context::memory_blocks() {
  if (!memory_blocks_) memory_blocks_ = std::make_unique<MemoryBlocks>(*this);
  return *memory_blocks_;
}

Allocation::Allocation(Context& ctx, const VkMemoryRequirements& req, std::uint32_t memory_type, Kind kind, bool map)
    : size_(req.size) {
  if (req.size <= kMaxSubAllocation) {
    blocks_ = &ctx.memory_blocks();
    const MemoryBlocks::Range range = blocks_->allocate(req, memory_type, kind, map);
    memory_ = range.memory, offset_ = range.offset, mapped_ = range.mapped;
    return;
  }
  own_ = allocate_memory(ctx, req.size, memory_type);
  memory_ = own_;
  if (map) VK_CHECK(vkMapMemory(ctx.device(), memory_, 0, VK_WHOLE_SIZE, 0, &mapped_));
}

Allocation& Allocation::operator=(Allocation&& o) noexcept {
  if (this != &o) {
    reset();
    blocks_ = std::exchange(o.blocks_, nullptr);
    own_ = std::move(o.own_);
    memory_ = std::exchange(o.memory_, VK_NULL_HANDLE);
    offset_ = std::exchange(o.offset_, 0);
    size_ = std::exchange(o.size_, 0);
    mapped_ = std::exchange(o.mapped_, nullptr);
  }
  return *this;
}

void Allocation::reset() {
  if (blocks_ && memory_ != VK_NULL_HANDLE) blocks_->release(memory_, offset_, size_);
  own_.reset();  // vkFreeMemory unmaps it
  blocks_ = nullptr;
  memory_ = VK_NULL_HANDLE;
  mapped_ = nullptr;
}

Buffer::Buffer(Context& ctx, VkDeviceSize bytes, VkBufferUsageFlags usage, Where where) : bytes_(bytes) {
  VkBufferCreateInfo info{VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO};
  info.size = bytes;
  info.usage = usage;
  info.sharingMode = VK_SHARING_MODE_EXCLUSIVE;
  VkBuffer buffer = VK_NULL_HANDLE;
  VK_CHECK(vkCreateBuffer(ctx.device(), &info, nullptr, &buffer));
  buffer_ = Handle<VkBuffer>(buffer, [d = ctx.device()](VkBuffer b) { vkDestroyBuffer(d, b, nullptr); });

  VkMemoryRequirements req{};
  vkGetBufferMemoryRequirements(ctx.device(), buffer_, &req);
  allocated_bytes_ = req.size;
  const VkMemoryPropertyFlags host = VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT;
  const std::uint32_t type = where == Where::host
                                 ? ctx.find_memory_type(req.memoryTypeBits, host | VK_MEMORY_PROPERTY_HOST_CACHED_BIT, host)
                                 : ctx.find_memory_type(req.memoryTypeBits, VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT, 0);
  memory_ = Allocation(ctx, req, type, Allocation::Kind::buffer, where == Where::host);
  VK_CHECK(vkBindBufferMemory(ctx.device(), buffer_, memory_.memory(), memory_.offset()));
  mapped_ = memory_.mapped();
}

Buffer make_storage_buffer(Context& ctx, VkDeviceSize bytes, const char* what, VkBufferUsageFlags extra_usage) {
  const auto limit = ctx.info().max_storage_buffer_range_bytes;
  if (bytes > limit)
    throw std::runtime_error(fmt::format("{} needs {:.1f} MiB, over the device's maxStorageBufferRange of {:.1f} MiB",
                                         what, bytes / 1048576.0, limit / 1048576.0));
  return Buffer(ctx, bytes,
                VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_SRC_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT |
                    extra_usage);
}

TexelView::TexelView(Context& ctx, const Buffer& buffer, VkFormat format, std::uint32_t texel_bytes, const char* what) {
  const std::uint64_t texels = buffer.bytes() / texel_bytes, limit = ctx.info().max_texel_buffer_elements;
  if (texels > limit)
    throw std::runtime_error(
        fmt::format("{} has {} texels, over the device's maxTexelBufferElements of {}", what, texels, limit));
  VkFormatProperties props{};
  vkGetPhysicalDeviceFormatProperties(ctx.physical_device(), format, &props);
  if (!(props.bufferFeatures & VK_FORMAT_FEATURE_UNIFORM_TEXEL_BUFFER_BIT))
    throw std::runtime_error(fmt::format("{}: the device cannot read format {} as a uniform texel buffer", what,
                                         static_cast<int>(format)));
  VkBufferViewCreateInfo info{VK_STRUCTURE_TYPE_BUFFER_VIEW_CREATE_INFO};
  info.buffer = buffer.get();
  info.format = format;
  info.offset = 0;
  info.range = texels * texel_bytes;
  VkBufferView view = VK_NULL_HANDLE;
  VK_CHECK(vkCreateBufferView(ctx.device(), &info, nullptr, &view));
  view_ = Handle<VkBufferView>(view, [d = ctx.device()](VkBufferView v) { vkDestroyBufferView(d, v, nullptr); });
}

Buffer make_uniform_buffer(Context& ctx, VkDeviceSize bytes, const char* what) {
  const auto limit = ctx.info().max_uniform_buffer_range_bytes;
  if (bytes > limit)
    throw std::runtime_error(fmt::format("{} needs {} bytes, over the device's maxUniformBufferRange of {} bytes", what,
                                         bytes, limit));
  return Buffer(ctx, bytes, VK_BUFFER_USAGE_UNIFORM_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT);
}

void upload(Context& ctx, const Buffer& dst, const void* data, VkDeviceSize bytes) {
  Buffer staging(ctx, bytes, VK_BUFFER_USAGE_TRANSFER_SRC_BIT, Buffer::Where::host);
  std::memcpy(staging.mapped(), data, bytes);
  ctx.submit_and_wait([&](VkCommandBuffer cmd) {
    const VkBufferCopy region{0, 0, bytes};
    vkCmdCopyBuffer(cmd, staging.get(), dst.get(), 1, &region);
  });
}

void download(Context& ctx, const Buffer& src, void* data, VkDeviceSize bytes) {
  Buffer staging(ctx, bytes, VK_BUFFER_USAGE_TRANSFER_DST_BIT, Buffer::Where::host);
  ctx.submit_and_wait([&](VkCommandBuffer cmd) {
    VkMemoryBarrier barrier{VK_STRUCTURE_TYPE_MEMORY_BARRIER};
    barrier.srcAccessMask = VK_ACCESS_SHADER_WRITE_BIT;
    barrier.dstAccessMask = VK_ACCESS_TRANSFER_READ_BIT;
    vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, VK_PIPELINE_STAGE_TRANSFER_BIT, 0, 1, &barrier, 0,
                         nullptr, 0, nullptr);
    const VkBufferCopy region{0, 0, bytes};
    vkCmdCopyBuffer(cmd, src.get(), staging.get(), 1, &region);
  });
  std::memcpy(data, staging.mapped(), bytes);
}

namespace {

// Device memory for `image` (small images share blocks), bound; returns the driver's size.
VkDeviceSize allocate_and_bind(Context& ctx, VkImage image, Allocation& memory) {
  VkMemoryRequirements req{};
  vkGetImageMemoryRequirements(ctx.device(), image, &req);
  memory = Allocation(ctx, req, ctx.find_memory_type(req.memoryTypeBits, VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT, 0),
                      Allocation::Kind::image, false);
  VK_CHECK(vkBindImageMemory(ctx.device(), image, memory.memory(), memory.offset()));
  return req.size;
}

constexpr VkImageSubresourceRange kColorRange{VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, 1};

Handle<VkImageView> make_view(Context& ctx, VkImage image, VkImageViewType type, VkFormat format) {
  VkImageViewCreateInfo view_info{VK_STRUCTURE_TYPE_IMAGE_VIEW_CREATE_INFO};
  view_info.image = image;
  view_info.viewType = type;
  view_info.format = format;
  view_info.subresourceRange = kColorRange;
  VkImageView view = VK_NULL_HANDLE;
  VK_CHECK(vkCreateImageView(ctx.device(), &view_info, nullptr, &view));
  return {view, [d = ctx.device()](VkImageView v) { vkDestroyImageView(d, v, nullptr); }};
}

// From UNDEFINED into the layout the image rests in between passes; its contents stay undefined
// until a pass or a copy writes them.
void initial_layout(Context& ctx, VkImage image, VkImageLayout layout, VkPipelineStageFlags stage, VkAccessFlags access) {
  ctx.submit_and_wait([&](VkCommandBuffer cmd) {
    VkImageMemoryBarrier barrier{VK_STRUCTURE_TYPE_IMAGE_MEMORY_BARRIER};
    barrier.dstAccessMask = access;
    barrier.oldLayout = VK_IMAGE_LAYOUT_UNDEFINED;
    barrier.newLayout = layout;
    barrier.srcQueueFamilyIndex = barrier.dstQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED;
    barrier.image = image;
    barrier.subresourceRange = kColorRange;
    vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_TOP_OF_PIPE_BIT, stage, 0, 0, nullptr, 0, nullptr, 1, &barrier);
  });
}

}  // namespace

StorageImage3D::StorageImage3D(Context& ctx, VkFormat format, std::uint32_t width, std::uint32_t height,
                               std::uint32_t depth) {
  image_ = create_image_3d(ctx, format, width, height, depth);
  allocated_bytes_ = allocate_and_bind(ctx, image_, memory_);
  view_ = make_view(ctx, image_, VK_IMAGE_VIEW_TYPE_3D, format);
  initial_layout(ctx, image_, VK_IMAGE_LAYOUT_GENERAL, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT,
                 VK_ACCESS_SHADER_READ_BIT | VK_ACCESS_SHADER_WRITE_BIT);
}

ColorTarget::ColorTarget(Context& ctx, VkFormat format, std::uint32_t width, std::uint32_t height)
    : format_(format), width_(width), height_(height) {
  image_ = create_image(ctx, color_target_info(format, width, height));
  allocated_bytes_ = allocate_and_bind(ctx, image_, memory_);
  view_ = make_view(ctx, image_, VK_IMAGE_VIEW_TYPE_2D, format);
  initial_layout(ctx, image_, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL, VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT,
                 VK_ACCESS_COLOR_ATTACHMENT_READ_BIT | VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT);
}

VkDeviceSize color_target_requirement_bytes(Context& ctx, VkFormat format, std::uint32_t width, std::uint32_t height) {
  Handle<VkImage> image = create_image(ctx, color_target_info(format, width, height));
  VkMemoryRequirements req{};
  vkGetImageMemoryRequirements(ctx.device(), image, &req);
  return req.size;
}

VkDeviceSize image_3d_requirement_bytes(Context& ctx, VkFormat format, std::uint32_t width, std::uint32_t height,
                                        std::uint32_t depth) {
  Handle<VkImage> image = create_image_3d(ctx, format, width, height, depth);
  VkMemoryRequirements req{};
  vkGetImageMemoryRequirements(ctx.device(), image, &req);
  return req.size;
}

}  // namespace bokeh::vk
