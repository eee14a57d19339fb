#include "timestamps.hpp"

#include <algorithm>
#include <stdexcept>

#include "vk_check.hpp"

namespace bokeh::vk {

namespace {
constexpr std::uint32_t kMaxCountedPasses = 64;
}  // namespace

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

void TimestampQueries::count_invocations(bool on) {
  counting_ = on && ctx_.info().pipeline_statistics;
  if (!counting_ || statistics_.get() != VK_NULL_HANDLE) return;
  VkQueryPoolCreateInfo info{VK_STRUCTURE_TYPE_QUERY_POOL_CREATE_INFO};
  info.queryType = VK_QUERY_TYPE_PIPELINE_STATISTICS;
  info.queryCount = kMaxCountedPasses;
  info.pipelineStatistics = VK_QUERY_PIPELINE_STATISTIC_COMPUTE_SHADER_INVOCATIONS_BIT;
  VkQueryPool pool = VK_NULL_HANDLE;
  VK_CHECK(vkCreateQueryPool(ctx_.device(), &info, nullptr, &pool));
  statistics_ = {pool, [d = ctx_.device()](VkQueryPool p) { vkDestroyQueryPool(d, p, nullptr); }};
}

void TimestampQueries::begin_frame(VkCommandBuffer cmd) {
  passes_.clear();
  commands_.clear();
  commands_at_pass_start_ = ctx_.commands_recorded;
  vkCmdResetQueryPool(cmd, pool_, 0, capacity_);
  vkCmdResetQueryPool(cmd, flush_pool_, 0, capacity_);
  stamp(cmd, 0);
  if (counting_) {
    vkCmdResetQueryPool(cmd, statistics_, 0, kMaxCountedPasses);
    vkCmdBeginQuery(cmd, statistics_, 0, 0);
  }
}

void TimestampQueries::end_pass(VkCommandBuffer cmd, const std::string& pass) {
  if (passes_.size() + 1 >= capacity_) throw std::logic_error("more passes than timestamp queries");
  passes_.push_back(pass);
  commands_.push_back(ctx_.commands_recorded - commands_at_pass_start_);
  commands_at_pass_start_ = ctx_.commands_recorded;
  const auto index = static_cast<std::uint32_t>(passes_.size());
  stamp(cmd, index);
  if (counting_) {
    if (index >= kMaxCountedPasses) throw std::logic_error("more passes than statistics queries");
    vkCmdEndQuery(cmd, statistics_, index - 1);
    vkCmdBeginQuery(cmd, statistics_, index, 0);
  }
}

void TimestampQueries::end_frame(VkCommandBuffer cmd) {
  if (counting_) vkCmdEndQuery(cmd, statistics_, static_cast<std::uint32_t>(passes_.size()));
}

std::vector<PassTime> TimestampQueries::read() const {
  const std::uint32_t count = static_cast<std::uint32_t>(passes_.size()) + 1;
  std::vector<std::uint64_t> ticks(count);
  VK_CHECK(vkGetQueryPoolResults(ctx_.device(), pool_, 0, count, ticks.size() * sizeof(std::uint64_t), ticks.data(),
                                 sizeof(std::uint64_t), VK_QUERY_RESULT_64_BIT | VK_QUERY_RESULT_WAIT_BIT));
  const std::uint32_t bits = ctx_.info().timestamp_valid_bits;
  const std::uint64_t mask = bits >= 64 ? ~0ull : ((1ull << bits) - 1);
  std::vector<std::uint64_t> invocations;
  if (counting_) {
    invocations.resize(passes_.size() + 1);
    VK_CHECK(vkGetQueryPoolResults(ctx_.device(), statistics_, 0, count, invocations.size() * sizeof(std::uint64_t),
                                   invocations.data(), sizeof(std::uint64_t),
                                   VK_QUERY_RESULT_64_BIT | VK_QUERY_RESULT_WAIT_BIT));
  }
  std::vector<PassTime> out;
  for (std::size_t i = 0; i < passes_.size(); ++i) {
    const std::uint64_t delta = (ticks[i + 1] - ticks[i]) & mask;  // wraps correctly within valid bits
    out.push_back({passes_[i], static_cast<double>(delta) * ctx_.info().timestamp_period_ns * 1e-6, commands_[i],
                   counting_ ? static_cast<std::int64_t>(invocations[i]) : -1});
  }
  return out;
}

std::vector<PassTime> mean_per_frame(const std::vector<PassTime>& batch, int frames) {
  std::vector<PassTime> out;
  for (const auto& p : batch) {
    auto it = std::find_if(out.begin(), out.end(), [&](const PassTime& o) { return o.pass == p.pass; });
    if (it == out.end()) out.push_back({p.pass, 0.0, 0, -1}), it = out.end() - 1;
    it->ms += p.ms;
    it->commands += p.commands;
    if (p.invocations >= 0) it->invocations = std::max<std::int64_t>(it->invocations, 0) + p.invocations;
  }
  for (auto& p : out) {
    p.ms /= frames;
    p.commands /= static_cast<std::uint64_t>(frames);
    if (p.invocations > 0) p.invocations /= frames;
  }
  return out;
}

double frame_ms(const std::vector<PassTime>& passes) {
  double total = 0;
  for (const auto& p : passes) total += p.ms;
  return total;
}

}  // namespace bokeh::vk
