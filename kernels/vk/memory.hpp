#pragma once
// Device memory for buffers and storage images, and host transfers through a staging buffer.
#include <cstdint>
#include <map>
#include <memory>
#include <vector>

#include <vulkan/vulkan.h>

#include "context.hpp"
#include "handle.hpp"

namespace bokeh::vk {

class MemoryBlocks;

// A range of device memory bound to one buffer or image. Small requests (up to kMaxSubAllocation)
// share blocks of kBlockBytes with others of the same memory type and kind (buffers and optimal-tiling
// images never share a block, so bufferImageGranularity never applies): a driver allows few
// allocations and each costs (the Khronos best-practices advice). Larger ones get their own.
class Allocation {
 public:
  static constexpr VkDeviceSize kMaxSubAllocation = 1 << 20, kBlockBytes = 16 << 20;
  enum class Kind { buffer, image };
  Allocation() = default;
  Allocation(Context& ctx, const VkMemoryRequirements& req, std::uint32_t memory_type, Kind kind, bool map);
  Allocation(Allocation&& o) noexcept { *this = std::move(o); }
  Allocation& operator=(Allocation&& o) noexcept;
  Allocation(const Allocation&) = delete;
  Allocation& operator=(const Allocation&) = delete;
  ~Allocation() { reset(); }
  void reset();

  VkDeviceMemory memory() const { return memory_; }
  VkDeviceSize offset() const { return offset_; }
  void* mapped() const { return mapped_; }  // host-visible requests only

 private:
  MemoryBlocks* blocks_ = nullptr;  // sub-allocated: the blocks to give the range back to
  Handle<VkDeviceMemory> own_;      // or memory of its own
  VkDeviceMemory memory_ = VK_NULL_HANDLE;
  VkDeviceSize offset_ = 0, size_ = 0;
  void* mapped_ = nullptr;
};

// The blocks small allocations share, per memory type and kind: first fit, neighbours merged on
// release. Owned by the Context (Context::memory_blocks()); every Allocation dies before it.
class MemoryBlocks {
 public:
  explicit MemoryBlocks(Context& ctx) : ctx_(ctx) {}
  struct Range {
    VkDeviceMemory memory = VK_NULL_HANDLE;
    VkDeviceSize offset = 0;
    void* mapped = nullptr;
  };
  Range allocate(const VkMemoryRequirements& req, std::uint32_t memory_type, Allocation::Kind kind, bool map);
  void release(VkDeviceMemory memory, VkDeviceSize offset, VkDeviceSize size);
  std::size_t block_count() const { return blocks_.size(); }

 private:
  struct Block {
    Handle<VkDeviceMemory> memory;
    std::uint32_t memory_type = 0;
    Allocation::Kind kind = Allocation::Kind::buffer;
    void* mapped = nullptr;
    std::map<VkDeviceSize, VkDeviceSize> free;  // offset -> bytes
  };
  Context& ctx_;
  std::vector<std::unique_ptr<Block>> blocks_;
};

class Buffer {
 public:
  enum class Where { device, host };  // host: mappable, for staging and readback
  Buffer(Context& ctx, VkDeviceSize bytes, VkBufferUsageFlags usage, Where where = Where::device);

  VkBuffer get() const { return buffer_; }
  VkDeviceSize bytes() const { return bytes_; }
  VkDeviceSize allocated_bytes() const { return allocated_bytes_; }
  void* mapped() const { return mapped_; }

 private:
  // Members die in reverse order: the buffer before the memory bound to it.
  Allocation memory_;
  Handle<VkBuffer> buffer_;
  VkDeviceSize bytes_ = 0, allocated_bytes_ = 0;
  void* mapped_ = nullptr;
};

// A storage buffer: checks the device's maxStorageBufferRange (128 MiB on lavapipe) up front.
// extra_usage: e.g. VK_BUFFER_USAGE_UNIFORM_TEXEL_BUFFER_BIT to read it through a TexelView, or
// VK_BUFFER_USAGE_INDIRECT_BUFFER_BIT for dispatch sizes a shader writes.
Buffer make_storage_buffer(Context& ctx, VkDeviceSize bytes, const char* what, VkBufferUsageFlags extra_usage = 0);
// A uniform buffer (small, read-only constants such as kernel taps): checks maxUniformBufferRange
// (64 KiB on lavapipe) up front.
Buffer make_uniform_buffer(Context& ctx, VkDeviceSize bytes, const char* what);

// A buffer (made with VK_BUFFER_USAGE_UNIFORM_TEXEL_BUFFER_BIT) read as a uniform texel buffer
// (samplerBuffer, texelFetch) of `format`, texel_bytes per texel. lavapipe fetches texels with vector
// gathers, while a storage-buffer load in non-uniform control flow is a loop of per-lane scalar
// loads. Checks maxTexelBufferElements and the format's uniform-texel-buffer support.
class TexelView {
 public:
  TexelView(Context& ctx, const Buffer& buffer, VkFormat format, std::uint32_t texel_bytes, const char* what);
  VkBufferView get() const { return view_; }

 private:
  Handle<VkBufferView> view_;
};

void upload(Context& ctx, const Buffer& dst, const void* data, VkDeviceSize bytes);
void download(Context& ctx, const Buffer& src, void* data, VkDeviceSize bytes);

// A 3D storage image in VK_IMAGE_LAYOUT_GENERAL, as FLAG's layer buffer.
class StorageImage3D {
 public:
  StorageImage3D(Context& ctx, VkFormat format, std::uint32_t width, std::uint32_t height, std::uint32_t depth);

  VkImageView view() const { return view_; }
  VkDeviceSize allocated_bytes() const { return allocated_bytes_; }

 private:
  Allocation memory_;  // declared first: freed after the image and view bound to it
  Handle<VkImage> image_;
  Handle<VkImageView> view_;
  VkDeviceSize allocated_bytes_ = 0;
};

// A 2D image a graphics pipeline draws into off-screen (colour attachment), filled from and read
// back into buffers by copies (graphics_pipeline.hpp). Between passes it rests in
// VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL.
class ColorTarget {
 public:
  ColorTarget(Context& ctx, VkFormat format, std::uint32_t width, std::uint32_t height);

  VkImage image() const { return image_; }
  VkImageView view() const { return view_; }
  VkFormat format() const { return format_; }
  std::uint32_t width() const { return width_; }
  std::uint32_t height() const { return height_; }
  VkDeviceSize allocated_bytes() const { return allocated_bytes_; }

 private:
  Allocation memory_;  // declared first: freed after the image and view bound to it
  Handle<VkImage> image_;
  Handle<VkImageView> view_;
  VkFormat format_;
  std::uint32_t width_, height_;
  VkDeviceSize allocated_bytes_ = 0;
};

// What the driver would allocate for such a target, without allocating.
VkDeviceSize color_target_requirement_bytes(Context& ctx, VkFormat format, std::uint32_t width, std::uint32_t height);

// What the driver would allocate for such an image (vkGetImageMemoryRequirements), without allocating.
VkDeviceSize image_3d_requirement_bytes(Context& ctx, VkFormat format, std::uint32_t width, std::uint32_t height,
                                        std::uint32_t depth);

}  // namespace bokeh::vk
