#include "timestamps.hpp"

#include <algorithm>
#include <stdexcept>

#include "vk_check.hpp"

namespace bokeh::vk {

TimestampQueries::TimestampQueries(Context& ctx, std::uint32_t capacity) : ctx_(ctx) { reserve(capacity); }

void TimestampQueries::reserve(std::uint32_t stamps) {
  if (pool_.get() != VK_NULL_HANDLE && stamps <= capacity_) return;
  capacity_ = std::max(stamps, 2u);
  for (Handle<VkQueryPool>* target : {&pool_, &flush_pool_}) {
    VkQueryPoolCreateInfo info{VK_STRUCTURE_TYPE_QUERY_POOL_CREATE_INFO};
    info.queryType = VK_QUERY_TYPE_TIMESTAMP;
    info.queryCount = capacity_;
    VkQueryPool pool = VK_NULL_HANDLE;
    VK_CHECK(vkCreateQueryPool(ctx_.device(), &info, nullptr, &pool));
    *target = {pool, [d = ctx_.device()](VkQueryPool p) { vkDestroyQueryPool(d, p, nullptr); }};
  }
}

// lavapipe (llvmpipe, Mesa 22.3 lp_setup_end_query) takes a timestamp at once only while no
// framebuffer is bound; once any draw has bound one (in any earlier submission too, as the state
// outlives it), it bins the timestamp into its rasteriser scene, which runs at the next flush: each
// pass would be stamped when the next one ends, shifting every pass's time onto the one before it.
// A second timestamp right after each one makes lavapipe flush, so the first is taken in place.
// Elsewhere it costs next to nothing; its pool is never read.
void TimestampQueries::stamp(VkCommandBuffer cmd, std::uint32_t index) {
  vkCmdWriteTimestamp(cmd, VK_PIPELINE_STAGE_BOTTOM_OF_PIPE_BIT, pool_, index);
  vkCmdWriteTimestamp(cmd, VK_PIPELINE_STAGE_BOTTOM_OF_PIPE_BIT, flush_pool_, index);
}

void TimestampQueries::begin_frame(VkCommandBuffer cmd) {
  passes_.clear();
  vkCmdResetQueryPool(cmd, pool_, 0, capacity_);
  vkCmdResetQueryPool(cmd, flush_pool_, 0, capacity_);
  stamp(cmd, 0);
}

void TimestampQueries::end_pass(VkCommandBuffer cmd, const std::string& pass) {
  if (passes_.size() + 1 >= capacity_) throw std::logic_error("more passes than timestamp queries");
  passes_.push_back(pass);
  stamp(cmd, static_cast<std::uint32_t>(passes_.size()));
}

std::vector<PassTime> TimestampQueries::read() const {
  const std::uint32_t count = static_cast<std::uint32_t>(passes_.size()) + 1;
  std::vector<std::uint64_t> ticks(count);
  VK_CHECK(vkGetQueryPoolResults(ctx_.device(), pool_, 0, count, ticks.size() * sizeof(std::uint64_t), ticks.data(),
                                 sizeof(std::uint64_t), VK_QUERY_RESULT_64_BIT | VK_QUERY_RESULT_WAIT_BIT));
  const std::uint32_t bits = ctx_.info().timestamp_valid_bits;
  const std::uint64_t mask = bits >= 64 ? ~0ull : ((1ull << bits) - 1);
  std::vector<PassTime> out;
  for (std::size_t i = 0; i < passes_.size(); ++i) {
    const std::uint64_t delta = (ticks[i + 1] - ticks[i]) & mask;  // wraps correctly within valid bits
    out.push_back({passes_[i], static_cast<double>(delta) * ctx_.info().timestamp_period_ns * 1e-6});
  }
  return out;
}

std::vector<PassTime> mean_per_frame(const std::vector<PassTime>& batch, int frames) {
  std::vector<PassTime> out;
  for (const auto& p : batch) {
    auto it = std::find_if(out.begin(), out.end(), [&](const PassTime& o) { return o.pass == p.pass; });
    if (it == out.end()) out.push_back({p.pass, 0.0}), it = out.end() - 1;
    it->ms += p.ms;
  }
  for (auto& p : out) p.ms /= frames;
  return out;
}

double frame_ms(const std::vector<PassTime>& passes) {
  double total = 0;
  for (const auto& p : passes) total += p.ms;
  return total;
}

}  // namespace bokeh::vk
