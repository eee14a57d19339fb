#pragma once
// The one GPU timing path: a timestamp before the first pass and after each pass, in one
// submission; pass times are the differences, the frame time is last minus first.
#include <cstdint>
#include <string>
#include <vector>

#include <vulkan/vulkan.h>

#include "context.hpp"
#include "handle.hpp"

namespace bokeh::vk {

struct PassTime {
  std::string pass;
  double ms = 0;
};

class TimestampQueries {
 public:
  TimestampQueries(Context& ctx, std::uint32_t capacity = 64);

  // Makes room for `stamps` timestamps in one frame (a batch of frames needs passes x frames + 1);
  // call outside recording.
  void reserve(std::uint32_t stamps);

  void begin_frame(VkCommandBuffer cmd);                       // resets and writes the start stamp
  void end_pass(VkCommandBuffer cmd, const std::string& pass);  // stamp once all prior work is done
  // After the submission completed: per-pass milliseconds in recording order.
  std::vector<PassTime> read() const;

 private:
  void stamp(VkCommandBuffer cmd, std::uint32_t index);

  Context& ctx_;
  std::uint32_t capacity_ = 0;
  Handle<VkQueryPool> pool_;
  Handle<VkQueryPool> flush_pool_;  // written after each stamp, never read (see stamp())
  std::vector<std::string> passes_;
};

double frame_ms(const std::vector<PassTime>& passes);

// A batch's stamps, summed per pass name (first-seen order) and divided by `frames`.
std::vector<PassTime> mean_per_frame(const std::vector<PassTime>& batch, int frames);

}  // namespace bokeh::vk
