#pragma once
// The one GPU timing path: a timestamp before the first pass and after each pass, in one
// submission; pass times are the differences, the frame time is last minus first. On request it
// also counts, per pass, the commands recorded (dispatches, draws) and the compute-shader
// invocations (pipeline-statistics queries, where the device has them): counters that do not
// depend on timing.
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
  std::uint64_t commands = 0;      // dispatches and draws recorded in the pass
  std::int64_t invocations = -1;   // compute-shader invocations; -1 when not counted
};

class TimestampQueries {
 public:
  TimestampQueries(Context& ctx, std::uint32_t capacity = 64);

  // Makes room for `stamps` timestamps in one frame (a batch of frames needs passes x frames + 1);
  // call outside recording.
  void reserve(std::uint32_t stamps);

  // Count compute-shader invocations per pass from the next frame on (ignored without device
  // support: DeviceInfo::pipeline_statistics). Queries cost a little: take counts outside timing.
  void count_invocations(bool on);

  void begin_frame(VkCommandBuffer cmd);                       // resets and writes the start stamp
  void end_pass(VkCommandBuffer cmd, const std::string& pass);  // stamp once all prior work is done
  void end_frame(VkCommandBuffer cmd);                          // closes the last pass's counters
  // After the submission completed: per-pass milliseconds in recording order.
  std::vector<PassTime> read() const;

 private:
  void stamp(VkCommandBuffer cmd, std::uint32_t index);

  Context& ctx_;
  std::uint32_t capacity_ = 0;
  Handle<VkQueryPool> pool_, statistics_;
  Handle<VkQueryPool> flush_pool_;  // written after each stamp, never read (see stamp())
  bool counting_ = false;
  std::vector<std::string> passes_;
  std::vector<std::uint64_t> commands_;  // per pass
  std::uint64_t commands_at_pass_start_ = 0;
};

double frame_ms(const std::vector<PassTime>& passes);

// A batch's stamps, summed per pass name (first-seen order) and divided by `frames`.
std::vector<PassTime> mean_per_frame(const std::vector<PassTime>& batch, int frames);

}  // namespace bokeh::vk
