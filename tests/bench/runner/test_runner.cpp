// The interleaved runner on fake targets with known times (no GPU), and the sweep's axes.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>

#include "runner.hpp"
#include "run.hpp"
#include "sweep.hpp"
#include "targets.hpp"

namespace bokeh {
namespace {

using runner::Policy;
using runner::RunRecord;
using runner::Sample;

// A target whose frames take `ms` (plus a repeating jitter), logging every visit.
struct Log {
  std::vector<std::size_t> visits;  // point index per measured sample, in order
  std::map<std::size_t, int> warm_ups;
  std::map<std::size_t, std::size_t> frames_measured;  // per point, over all its targets (jitter index)
};

class FakeTarget : public runner::Target {
 public:
  FakeTarget(std::size_t index, double ms, std::vector<double> jitter, Log& log, std::uint64_t bytes = 0)
      : index_(index), ms_(ms), jitter_(std::move(jitter)), log_(log), bytes_(bytes) {}
  void warm_up() override { ++log_.warm_ups[index_]; }
  Sample measure(int frames) override {
    // Warm-up frames come one at a time; samples have frames_hint frames (the tests use times that
    // need more than one).
    if (frames == frames_hint_) log_.visits.push_back(index_);
    const double j = jitter_.empty() ? 0.0 : jitter_[log_.frames_measured[index_]++ % jitter_.size()];
    return {ms_ * (1 + j), {{"pass", ms_ * (1 + j)}}};
  }
  std::uint64_t resident_bytes() const override { return bytes_; }
  int frames_hint_ = 0;

 private:
  std::size_t index_;
  double ms_;
  std::vector<double> jitter_;
  Log& log_;
  std::uint64_t bytes_;
};

// Runs `times.size()` fake points: point i's frames take times[i] ms.
struct Harness {
  Log log;
  std::vector<std::vector<double>> jitter;
  std::uint64_t bytes = 0;
  std::vector<std::string> fail_on_prepare;  // per point: throw this text from prepare
  std::vector<std::size_t> visit_group;                      // runner::Hooks::visit_group
  std::vector<std::size_t> visit_block;                      // runner::Hooks::visit_block
  std::function<std::vector<bool>(const RunRecord&)> points_needed;  // runner::Hooks::points_needed
  double ms_per_preparation = 0;  // each later target of a point takes this much longer than the one before
  std::map<std::size_t, int> preparations;

  RunRecord run(const std::vector<double>& times, const Policy& policy, const std::vector<std::string>& skip = {},
                std::function<void(const RunRecord&)> checkpoint = {}) {
    std::vector<std::string> names;
    for (std::size_t i = 0; i < times.size(); ++i) names.push_back("p" + std::to_string(i));
    runner::Hooks hooks;
    hooks.prepare = [&](std::size_t i) -> std::unique_ptr<runner::Target> {
      if (i < fail_on_prepare.size() && !fail_on_prepare[i].empty()) throw std::runtime_error(fail_on_prepare[i]);
      const double ms = times[i] + ms_per_preparation * preparations[i]++;
      auto t = std::make_unique<FakeTarget>(i, ms, i < jitter.size() ? jitter[i] : std::vector<double>{}, log, bytes);
      // Frames per sample follow from the pilot: ceil(sample_min_ms / ms).
      t->frames_hint_ = std::clamp(static_cast<int>(std::ceil(policy.sample_min_ms / times[i])), 1,
                                   policy.max_frames_per_sample);
      return t;
    };
    hooks.checkpoint = std::move(checkpoint);
    hooks.visit_group = visit_group;
    hooks.visit_block = visit_block;
    hooks.points_needed = points_needed;
    return runner::run(names, skip, policy, hooks);
  }
};

Policy fast_policy() {
  Policy p;
  p.budget_s = 1e9;  // stop by settling, not by the clock
  p.min_samples = 3;
  p.max_samples = 6;
  p.sample_min_ms = 10;
  p.warm_up_max_s = 0;
  return p;
}

// Replicas: each point prepared that many times, its samples taking the targets in turn (sample s from
// replica s mod R), each replica's first frame untimed.
TEST(Runner, ReplicasTakeTurnsEachWithTargetsOfTheirOwn) {
  Harness h;
  h.ms_per_preparation = 0.5;  // replica r's frames take 0.5 r ms more: which replica took a sample shows
  Policy p = fast_policy();
  p.min_samples = p.max_samples = 6;
  p.replicas = 2;
  const RunRecord r = h.run({2, 3}, p);
  ASSERT_EQ(r.status, "complete");
  for (std::size_t i = 0; i < 2; ++i) {
    const runner::PointRecord& rec = r.points[i];
    EXPECT_EQ(rec.preparations, 2);
    ASSERT_EQ(rec.samples.size(), 6u);
    for (std::size_t s = 0; s < rec.samples.size(); ++s)
      EXPECT_DOUBLE_EQ(rec.samples[s].frame_ms, (i == 0 ? 2.0 : 3.0) + 0.5 * static_cast<double>(s % 2)) << i << " " << s;
  }
  p.replicas = 0;
  EXPECT_THROW(h.run({2}, p), std::invalid_argument);
}

TEST(Runner, EveryPointGetsItsFirstSampleBeforeAnyGetsItsSecond) {
  Harness h;
  h.jitter = {{0.0, 0.3}, {0.0, 0.3}, {0.0, 0.3}, {0.0, 0.3}, {0.0, 0.3}};  // never settles: max_samples rounds
  const RunRecord r = h.run({1, 2, 3, 4, 5}, fast_policy());
  ASSERT_EQ(r.status, "complete");
  ASSERT_EQ(r.round_order.size(), 6u);
  // The log, cut into rounds, is exactly the recorded order, and each round visits every point once.
  ASSERT_EQ(h.log.visits.size(), 30u);
  std::set<std::vector<std::size_t>> distinct;
  for (std::size_t round = 0; round < r.round_order.size(); ++round) {
    const std::vector<std::size_t> visited(h.log.visits.begin() + 5 * round, h.log.visits.begin() + 5 * (round + 1));
    EXPECT_EQ(visited, r.round_order[round]) << "round " << round;
    std::vector<std::size_t> sorted = visited;
    std::sort(sorted.begin(), sorted.end());
    EXPECT_EQ(sorted, (std::vector<std::size_t>{0, 1, 2, 3, 4}));
    distinct.insert(visited);
  }
  EXPECT_GT(distinct.size(), 1u) << "the order is shuffled anew each round";
  for (const auto& p : r.points) {
    EXPECT_EQ(p.samples.size(), 6u);
    EXPECT_EQ(p.sample_round, (std::vector<int>{0, 1, 2, 3, 4, 5}));
  }
}

TEST(Runner, TheSeedFixesTheOrder) {
  Harness a, b, c;
  Policy p = fast_policy();
  const auto ra = a.run({1, 2, 3, 4, 5, 6}, p), rb = b.run({1, 2, 3, 4, 5, 6}, p);
  p.seed = 2;
  const auto rc = c.run({1, 2, 3, 4, 5, 6}, p);
  EXPECT_EQ(ra.round_order, rb.round_order);
  EXPECT_NE(ra.round_order, rc.round_order);
}

TEST(Runner, KnownTimesComeBackAsMediansAndFramesFillASample) {
  Harness h;
  const RunRecord r = h.run({0.5, 4, 25}, fast_policy());
  const double expected[] = {0.5, 4, 25};
  const int frames[] = {20, 3, 1};  // ceil(10 ms / t)
  for (std::size_t i = 0; i < 3; ++i) {
    EXPECT_DOUBLE_EQ(runner::distribution(r.points[i].frame_ms()).median, expected[i]);
    EXPECT_EQ(r.points[i].frames_per_sample, frames[i]);
    EXPECT_TRUE(r.points[i].settled);
    EXPECT_EQ(r.points[i].samples.size(), 3u) << "steady points leave after min_samples";
  }
}

TEST(Runner, NoisyPointsStayUntilMaxSamplesSteadyOnesLeave) {
  Harness h;
  h.jitter = {{}, {0.0, 0.5, -0.3}};
  const RunRecord r = h.run({2, 2}, fast_policy());
  EXPECT_EQ(r.points[0].samples.size(), 3u);
  EXPECT_EQ(r.points[1].samples.size(), 6u);
  EXPECT_EQ(r.round_order.back(), (std::vector<std::size_t>{1}));
}

TEST(Runner, SkippedPointsKeepTheirReasonAndAreNeverPrepared) {
  Harness h;
  h.fail_on_prepare = {"", "needs 2 GiB, over the device's limit", ""};
  const RunRecord r = h.run({1, 1, 1}, fast_policy(), {"", "", "over --max-buffer-mb 1 (not allocated)"});
  EXPECT_TRUE(r.points[0].skipped.empty());
  EXPECT_EQ(r.points[1].skipped, "needs 2 GiB, over the device's limit");
  EXPECT_EQ(r.points[2].skipped, "over --max-buffer-mb 1 (not allocated)");
  EXPECT_EQ(r.points[2].preparations, 0);
  EXPECT_TRUE(r.points[1].samples.empty());
  for (const auto& round : r.round_order) EXPECT_EQ(std::count(round.begin(), round.end(), 2u), 0);
  EXPECT_EQ(r.points[0].samples.size(), 3u);
}

TEST(Runner, AnInterruptionKeepsEverySampleTakenSoFar) {
  Harness h;
  h.jitter = {{0.0, 0.3}, {0.0, 0.3}, {0.0, 0.3}};
  std::size_t checkpoints = 0;
  runner::InterruptScope scope;
  const RunRecord r = h.run({1, 1, 1}, fast_policy(), {}, [&](const RunRecord& partial) {
    ++checkpoints;
    EXPECT_EQ(partial.status, "partial");
    if (checkpoints == 7) runner::request_interrupt();  // as SIGINT during the third round
  });
  EXPECT_EQ(r.status, "interrupted");
  EXPECT_EQ(h.log.visits.size(), 7u);
  std::size_t samples = 0;
  for (const auto& p : r.points) samples += p.samples.size();
  EXPECT_EQ(samples, 7u);
  for (const auto& p : r.points) EXPECT_GE(p.samples.size(), 2u);
}

TEST(Runner, TargetsOverTheResidentLimitAreFreedAndPreparedAgain) {
  Harness h;
  h.bytes = 100;
  // Never settles: a visit that prepares again also runs one untimed frame, so each visit takes two
  // jitter values; a period of 3 keeps the samples apart.
  h.jitter = {{0.0, 0.3, 0.6}, {0.0, 0.3, 0.6}, {0.0, 0.3, 0.6}};
  Policy p = fast_policy();
  p.resident_limit_bytes = 150;  // one target at a time
  const RunRecord r = h.run({1, 1, 1}, p);
  int preparations = 0;
  for (const auto& pt : r.points) {
    preparations += pt.preparations;
    EXPECT_EQ(pt.samples.size(), 6u);
  }
  EXPECT_GT(preparations, 3);
  for (const auto& [i, n] : h.log.warm_ups) EXPECT_GE(n, 1);
}

TEST(Runner, TheBudgetStopsRoundsOnceEveryPointHasItsMinimum) {
  Harness h;
  h.jitter = {{0.0, 0.3}, {0.0, 0.3}};
  Policy p = fast_policy();
  p.budget_s = 0;  // spent from the start
  const RunRecord r = h.run({1, 1}, p);
  for (const auto& pt : r.points) EXPECT_EQ(pt.samples.size(), 3u);
}

TEST(Runner, TheBudgetOrSettlingIsTheRecordedStopReason) {
  Harness spent, steady;
  spent.jitter = {{0.0, 0.3}};
  Policy p = fast_policy();
  EXPECT_EQ(steady.run({1}, p).stop_reason, "every point settled");
  p.budget_s = 0;
  EXPECT_EQ(spent.run({1}, p).stop_reason, "budget spent");
}

// The rounds end where the run comes nearest its budget: another round runs while it would end
// closer to the budget (past it or not) than the run is now.
TEST(Runner, TheBudgetEndsTheRoundsNearestToIt) {
  EXPECT_FALSE(runner::budget_spent(85, 20, 100));  // 15 s short now; the next round ends 5 s past
  EXPECT_TRUE(runner::budget_spent(95, 20, 100));   // 5 s short now; the next round ends 15 s past
  EXPECT_TRUE(runner::budget_spent(90, 20, 100));   // as near either way: stop
  EXPECT_TRUE(runner::budget_spent(101, 0, 100));   // past it already
  EXPECT_FALSE(runner::budget_spent(99.9, 0, 100));
}

// A later process of a run sees the rounds of those before it, then its own: rounds renumbered after
// the earlier ones, each tagged with the process that measured it, each point's samples in order.
TEST(Runner, ALaterProcessFollowsTheEarlierProcessesRounds) {
  RunRecord earlier;
  earlier.points.resize(2);
  earlier.round_order = {{0, 1}, {1, 0}, {0, 1}};
  earlier.round_process = {0, 0, 1};  // two processes before
  earlier.points[0].samples = {{1.0, {}, 2.0}, {1.1, {}, 2.1}, {1.2, {}, 2.2}};
  earlier.points[0].sample_round = {0, 1, 2};
  earlier.points[1].samples = {{5.0, {}, 6.0}};  // it left the rounds after the first
  earlier.points[1].sample_round = {0};
  RunRecord later;
  later.points.resize(2);
  later.round_order = {{1, 0}, {0}};
  later.points[0].samples = {{1.3, {}, 2.3}, {1.4, {}, 2.4}};
  later.points[0].sample_round = {0, 1};
  later.points[1].samples = {{5.5, {}, 6.5}};
  later.points[1].sample_round = {0};
  later.points[1].settled = true;
  earlier.probe_ms["copy"] = {1, 2, 3};
  later.probe_ms["copy"] = {4, 5};
  earlier.points[0].warm_up_ms = {9.0};
  earlier.points[0].frames_per_sample = 3;
  earlier.points[0].wall_s = 1.5;
  later.points[0].warm_up_ms = {8.0};
  later.points[0].frames_per_sample = 4;
  later.points[0].wall_s = 0.5;

  const RunRecord joined = runner::followed_by(earlier, later);
  EXPECT_EQ(joined.probe_ms.at("copy"), (std::vector<double>{1, 2, 3, 4, 5}));
  EXPECT_EQ(joined.points[0].warm_up_ms, (std::vector<double>{9.0, 8.0}));
  EXPECT_EQ(joined.points[0].frames_per_sample, 3);  // the first process's
  EXPECT_DOUBLE_EQ(joined.points[0].wall_s, 2.0);
  EXPECT_EQ(joined.round_order, (std::vector<std::vector<std::size_t>>{{0, 1}, {1, 0}, {0, 1}, {1, 0}, {0}}));
  EXPECT_EQ(joined.round_process, (std::vector<int>{0, 0, 1, 2, 2}));
  EXPECT_EQ(joined.points[0].sample_round, (std::vector<int>{0, 1, 2, 3, 4}));
  EXPECT_EQ(joined.points[0].frame_ms(), (std::vector<double>{1.0, 1.1, 1.2, 1.3, 1.4}));
  EXPECT_EQ(joined.points[0].cpu_ms(), (std::vector<double>{2.0, 2.1, 2.2, 2.3, 2.4}));
  EXPECT_EQ(joined.points[1].sample_round, (std::vector<int>{0, 3}));
  EXPECT_TRUE(joined.points[1].settled);

  // Skipped: a later reason counts only where nothing measured the point; measuring it later clears one.
  RunRecord skipped_later = later;
  skipped_later.points[1] = {};
  skipped_later.points[1].skipped = "out of memory";
  EXPECT_EQ(runner::followed_by(earlier, skipped_later).points[1].skipped, "");
  RunRecord never_measured = earlier;
  never_measured.points[1] = {};
  EXPECT_EQ(runner::followed_by(never_measured, skipped_later).points[1].skipped, "out of memory");
  never_measured.points[1].skipped = "too slow";
  EXPECT_EQ(runner::followed_by(never_measured, later).points[1].skipped, "");

  RunRecord first_process;  // one process before, its rounds untagged
  first_process.points.resize(2);
  first_process.round_order = {{0, 1}};
  EXPECT_EQ(runner::followed_by(first_process, later).round_process, (std::vector<int>{0, 1, 1}));
  RunRecord other_points;
  other_points.points.resize(3);
  EXPECT_THROW(runner::followed_by(other_points, later), std::invalid_argument);
}

// A group's points are visited back to back in every round and take turns going first, so a ratio
// of theirs is measured side by side; the groups' order is still shuffled.
TEST(Runner, PointsOfAGroupAreVisitedBackToBackTakingTurnsFirst) {
  Harness h;
  h.jitter.assign(6, {0.0, 0.3});
  h.visit_group = {0, 1, 2, 0, 1, 2};  // pairs (0, 3), (1, 4), (2, 5)
  const RunRecord r = h.run({1, 2, 3, 4, 5, 6}, fast_policy());
  ASSERT_EQ(r.round_order.size(), 6u);
  std::set<std::vector<std::size_t>> group_orders;
  for (std::size_t round = 0; round < r.round_order.size(); ++round) {
    const auto& order = r.round_order[round];
    ASSERT_EQ(order.size(), 6u);
    std::vector<std::size_t> groups;
    for (std::size_t at = 0; at < 6; at += 2) {
      EXPECT_EQ(h.visit_group[order[at]], h.visit_group[order[at + 1]]) << "round " << round;
      const std::size_t first = std::min(order[at], order[at + 1]) == order[at] ? 0 : 1;
      EXPECT_EQ(first, round % 2) << "round " << round << ": the lower index goes first in even rounds";
      groups.push_back(h.visit_group[order[at]]);
    }
    group_orders.insert(groups);
  }
  EXPECT_GT(group_orders.size(), 1u) << "the groups' order is shuffled anew each round";
}

// The groups of a block (a curve's sizes) are visited one after another, each group still back to back
// and taking turns going first; the blocks' order and the groups' order inside a block are shuffled.
TEST(Runner, GroupsOfABlockAreVisitedOneAfterAnother) {
  Harness h;
  h.jitter.assign(8, {0.0, 0.3});
  h.visit_group = {0, 1, 2, 3, 0, 1, 2, 3};  // pairs (0, 4), (1, 5), (2, 6), (3, 7)
  h.visit_block = {0, 0, 1, 1, 0, 0, 1, 1};  // blocks {pairs 0, 1} and {pairs 2, 3}
  const RunRecord r = h.run({1, 2, 3, 4, 5, 6, 7, 8}, fast_policy());
  ASSERT_EQ(r.round_order.size(), 6u);
  std::set<std::vector<std::size_t>> block_orders, group_orders;
  for (std::size_t round = 0; round < r.round_order.size(); ++round) {
    const auto& order = r.round_order[round];
    ASSERT_EQ(order.size(), 8u);
    std::vector<std::size_t> blocks, groups;
    for (std::size_t at = 0; at < 8; at += 2) {
      EXPECT_EQ(h.visit_group[order[at]], h.visit_group[order[at + 1]]) << "round " << round;
      const std::size_t first = std::min(order[at], order[at + 1]) == order[at] ? 0 : 1;
      EXPECT_EQ(first, round % 2) << "round " << round << ": the lower index goes first in even rounds";
      groups.push_back(h.visit_group[order[at]]);
    }
    for (std::size_t at = 0; at < 8; at += 4) {
      for (std::size_t k = 1; k < 4; ++k)
        EXPECT_EQ(h.visit_block[order[at]], h.visit_block[order[at + k]]) << "round " << round << ": a block split";
      blocks.push_back(h.visit_block[order[at]]);
    }
    block_orders.insert(blocks);
    group_orders.insert(groups);
  }
  EXPECT_GT(block_orders.size(), 1u) << "the blocks' order is shuffled anew each round";
  EXPECT_GT(group_orders.size(), 2u) << "the groups' order inside a block is shuffled too";
}

// A point no unsettled figure needs leaves the rounds (once every point has its minimum samples);
// the others go on, and the run ends when none is needed. No point leaves on its own IQR (the jitter
// would let it): the hook alone decides.
TEST(Runner, PointsNoFigureNeedsLeaveTheRounds) {
  Harness h;
  h.jitter.assign(3, {0.0, 0.3});
  // Point 1 is never needed; points 0 and 2 until point 2 has 5 samples.
  h.points_needed = [](const RunRecord& r) {
    const bool more = r.points[2].samples.size() < 5;
    return std::vector<bool>{more, false, more};
  };
  Policy p = fast_policy();
  p.max_samples = 50;
  const RunRecord r = h.run({1, 2, 3}, p);
  EXPECT_EQ(r.points[1].samples.size(), static_cast<std::size_t>(p.min_samples)) << "left at its minimum";
  EXPECT_EQ(r.points[0].samples.size(), 5u);
  EXPECT_EQ(r.points[2].samples.size(), 5u);
  EXPECT_TRUE(r.points[1].settled);
  EXPECT_EQ(r.stop_reason, "headlines settled");
  for (std::size_t round = static_cast<std::size_t>(p.min_samples); round < r.round_order.size(); ++round)
    EXPECT_EQ(std::count(r.round_order[round].begin(), r.round_order[round].end(), 1u), 0) << "round " << round;
}

// A command whose claims are drawn from several points ends the rounds when they are tight: no point
// leaves on its own IQR before (a ratio needs both points in the same rounds).
TEST(Runner, HeadlinesSettledEndsTheRoundsAndKeepsEveryPointInThem) {
  Harness h;
  h.jitter = {{}, {0.0, 0.5, -0.3}};
  Policy p = fast_policy();
  p.max_samples = 20;
  h.points_needed = [](const RunRecord& r) { return std::vector<bool>(2, r.round_order.size() < 4); };
  const RunRecord r = h.run({2, 2}, p);
  EXPECT_EQ(r.stop_reason, "headlines settled");
  EXPECT_EQ(r.round_order.size(), 4u);
  for (const auto& pt : r.points) EXPECT_EQ(pt.sample_round, (std::vector<int>{0, 1, 2, 3})) << pt.name;
}

TEST(Runner, DistributionMatchesHandComputedQuartiles) {
  const runner::Distribution d = runner::distribution({4, 1, 3, 2, 5});
  EXPECT_DOUBLE_EQ(d.median, 3);
  EXPECT_DOUBLE_EQ(d.q1, 2);
  EXPECT_DOUBLE_EQ(d.q3, 4);
  EXPECT_DOUBLE_EQ(d.min, 1);
  EXPECT_DOUBLE_EQ(d.max, 5);
  EXPECT_DOUBLE_EQ(d.mean, 3);
  EXPECT_NEAR(d.relative_iqr(), 2.0 / 3.0, 1e-12);
}

TEST(Runner, InjectedExtraWorkRunsWholeExtraFramesAndCountsThem) {
  // --inject-slowdown-pct: every sample runs 25% more frames than it reports, so a point whose
  // frames take exactly 1 ms reads 1.25 ms; frames per sample become a multiple of 4.
  Harness h;
  Policy p = fast_policy();
  p.extra_work_fraction = 0.25;
  std::vector<int> frames_asked;
  struct Counting : runner::Target {
    std::vector<int>& asked;
    explicit Counting(std::vector<int>& a) : asked(a) {}
    void warm_up() override {}
    Sample measure(int frames) override {
      asked.push_back(frames);
      return {1.0, {{"pass", 0.4}}};
    }
  };
  runner::Hooks hooks;
  hooks.prepare = [&](std::size_t) -> std::unique_ptr<runner::Target> { return std::make_unique<Counting>(frames_asked); };
  const RunRecord r = runner::run({"p0"}, {}, p, hooks);
  const auto& pt = r.points[0];
  EXPECT_EQ(pt.frames_per_sample, 12) << "ceil(10 ms / 1 ms) = 10, rounded up to a multiple of 4";
  ASSERT_EQ(pt.samples.size(), 3u);
  for (const auto& s : pt.samples) {
    EXPECT_DOUBLE_EQ(s.frame_ms, 1.25);
    EXPECT_DOUBLE_EQ(s.pass_ms.at("pass"), 0.5);
  }
  EXPECT_EQ(frames_asked.back(), 15) << "12 frames reported, 3 more run";
  p.extra_work_fraction = 0.125;  // not a whole percentage
  EXPECT_THROW(runner::run({"p0"}, {}, p, hooks), std::invalid_argument);
}

TEST(Runner, SamplesRecordTheProcessCpuTimePerFrame) {
  // A target whose every frame burns 2 ms of this process's CPU time (spinning on the CPU-time
  // clock itself): each sample's cpu_ms is 2 ms, however long the wall clock took.
  struct Burning : runner::Target {
    void warm_up() override {}
    Sample measure(int frames) override {
      const auto cpu_now = [] {
        timespec t{};
        clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
        return t.tv_sec * 1e3 + t.tv_nsec * 1e-6;
      };
      const double until = cpu_now() + 2.0 * frames;
      while (cpu_now() < until) {
      }
      return {2.0, {}};
    }
  };
  Policy p = fast_policy();
  p.sample_min_ms = 4;
  runner::Hooks hooks;
  hooks.prepare = [](std::size_t) -> std::unique_ptr<runner::Target> { return std::make_unique<Burning>(); };
  hooks.probes.emplace_back("probe", std::make_unique<Burning>());
  const RunRecord r = runner::run({"p0"}, {}, p, hooks);
  for (const auto& s : r.points[0].samples) {
    EXPECT_GE(s.cpu_ms, 2.0);
    EXPECT_LT(s.cpu_ms, 2.5);
  }
  ASSERT_EQ(r.probe_cpu_ms.at("probe").size(), r.round_order.size());
  for (double ms : r.probe_cpu_ms.at("probe")) EXPECT_GE(ms, 2.0);
}

// A device whose clock ramps up with work and decays while idle (a discrete GPU's behaviour, in a
// model: the constants are this test's, not any GPU's). Frames on it take base_ms at full clock and
// 4x that at idle.
struct ClockedDevice {
  double boost = 0;  // 0 idle .. 1 full clock
  double speed() const { return 0.25 + 0.75 * boost; }
  void busy(double ms) { boost = 1 - (1 - boost) * std::exp(-ms / 4.0); }
  void idle(double ms) { boost *= std::exp(-ms / 10.0); }
};

class ClockedTarget : public runner::Target {
 public:
  ClockedTarget(ClockedDevice& d, double base_ms) : device_(d), base_ms_(base_ms) {}
  void warm_up() override {}
  Sample measure(int frames) override {
    double total = 0;
    for (int f = 0; f < frames; ++f) {
      const double ms = base_ms_ / device_.speed();
      device_.busy(ms);
      total += ms;
    }
    return {total / frames, {}};
  }

 private:
  ClockedDevice& device_;
  double base_ms_;
};

// The CPU reference of a sweep: the device idles while it runs.
class HostTarget : public runner::Target {
 public:
  HostTarget(ClockedDevice& d, double ms) : device_(d), ms_(ms) {}
  void warm_up() override {}
  Sample measure(int frames) override {
    device_.idle(ms_ * frames);
    return {ms_, {}};
  }

 private:
  ClockedDevice& device_;
  double ms_;
};

TEST(Runner, WarmUpRunsBatchesUntilTheClockHasRamped) {
  ClockedDevice device;
  Policy p = fast_policy();
  p.warm_up_max_s = 10;
  runner::Hooks hooks;
  hooks.prepare = [&](std::size_t) -> std::unique_ptr<runner::Target> { return std::make_unique<ClockedTarget>(device, 0.1); };
  const RunRecord r = runner::run({"gpu"}, {}, p, hooks);
  const auto& pt = r.points[0];
  EXPECT_NEAR(pt.warm_up_ms.front(), 0.4, 0.01) << "the pilot frame runs at idle clock";
  EXPECT_GE(pt.warm_up_ms.size(), 4u) << "pilot, then batches while they still get faster, then two that do not";
  EXPECT_NEAR(runner::distribution(pt.frame_ms()).median, 0.1, 0.002) << "samples at full clock";
  EXPECT_EQ(pt.frames_per_sample, 100) << "sized from the warmed-up frame (10 ms / 0.1 ms), not the idle pilot's 25";
}

TEST(Runner, ALeadInBeforeEachSampleUndoesTheIdleTimeOfInterleavedCpuPoints) {
  auto gpu_median = [](double lead_in_ms) {
    ClockedDevice device;
    Policy p = fast_policy();
    p.warm_up_max_s = 10;
    p.min_samples = p.max_samples = 12;
    p.sample_min_ms = 2;
    p.lead_in_ms = lead_in_ms;
    runner::Hooks hooks;
    hooks.prepare = [&](std::size_t i) -> std::unique_ptr<runner::Target> {
      if (i == 0) return std::make_unique<ClockedTarget>(device, 0.1);
      return std::make_unique<HostTarget>(device, 50);
    };
    const RunRecord r = runner::run({"gpu", "cpu"}, {}, p, hooks);
    return runner::distribution(r.points[0].frame_ms()).median;
  };
  EXPECT_GT(gpu_median(0), 0.15) << "without a lead-in the samples after the CPU point start at idle clock";
  EXPECT_NEAR(gpu_median(20), 0.1, 0.005);
}

// ---- The sweep's axes (the real registry; nothing is measured). ----

TEST(Axes, ProductOfAxesLessWhatAMethodDoesNotAccept) {
  Axes axes;
  axes.methods = {"naive", "flag"};
  axes.backends = {"gpu", "cpu"};
  axes.patterns = {{9, 2}, {13, 2}};
  axes.precisions = {"all"};
  axes.scales = {0};
  const auto points = expand(axes);
  // naive: 1 precision x 1 scale; flag: every precision x every scale; x 2 backends x 2 patterns.
  const Method& flag = find_method("flag");
  EXPECT_EQ(points.size(), (1 + flag.precisions.size() * flag.buffer_scales.size()) * 2 * 2);
  std::set<std::string> ids;
  for (const auto& p : points) ids.insert(p.id);
  EXPECT_EQ(ids.size(), points.size()) << "ids are unique";
  EXPECT_TRUE(ids.count("flag/cpu/hoops/800x600/N:13/k:2/r11g11b10f/scale:1-4"));
  EXPECT_TRUE(ids.count("naive/gpu/hoops/800x600/N:9/k:2/f32"));
}

TEST(Axes, ListedPrecisionsApplyWhereAcceptedAndDefaultsElsewhere) {
  Axes axes;
  axes.methods = {"naive", "flag"};
  axes.patterns = {{9, 2}};
  axes.precisions = {"f32"};
  for (const auto& p : expand(axes)) EXPECT_EQ(p.options.precision, "f32") << p.id;
  axes.precisions = {};
  for (const auto& p : expand(axes)) EXPECT_EQ(p.options.precision, p.method->precisions.front()) << p.id;
}

TEST(Axes, MethodsThatOnlySeeTheLargestRadiusTakeOnePatternPerRadius) {
  Axes axes;
  axes.methods = {"circular2"};
  axes.patterns = {{41, 2}, {21, 4}, {11, 8}, {9, 2}};  // radii 40, 40, 40, 8
  const auto points = expand(axes);
  ASSERT_EQ(points.size(), 2u);
  EXPECT_EQ(points[0].options.pattern.size_n, 41);
  EXPECT_EQ(points[1].options.pattern.size_n, 9);
}

TEST(Axes, OptionsAreFixedWhenGivenAndSweptOnRequest) {
  Axes axes;
  axes.methods = {"circular2"};
  axes.patterns = {{9, 2}};
  axes.option_values = {{"near_components", 1}};
  const auto points = expand(axes);
  ASSERT_EQ(points.size(), 1u);
  EXPECT_EQ(points[0].options.integer("near_components"), 1);
  EXPECT_NE(points[0].id.find("near_components:1"), std::string::npos) << points[0].id;
}

// Apertures (issue 23): an axis; a point names any but the disc, carries it in its options, and a
// method that cannot draw it is planned as skipped with its reason, before anything is allocated.
TEST(Axes, ApertureIsAnAxisAndUndrawableShapesAreSkippedWithTheReason) {
  Axes axes;
  axes.methods = {"naive", "spiral"};  // spiral draws the disc only (flag draws polygons since issue 23)
  axes.patterns = {{9, 2}};
  axes.apertures = {Aperture{}, parse_aperture("blades5")};
  const auto points = expand(axes);
  ASSERT_EQ(points.size(), 4u);
  std::set<std::string> ids;
  for (const auto& p : points) ids.insert(p.id);
  EXPECT_TRUE(ids.count("naive/gpu/hoops/800x600/N:9/k:2/f32")) << "the disc's ids are unchanged";
  EXPECT_TRUE(ids.count("naive/gpu/hoops/800x600/N:9/k:2/f32/aperture:blades5"));
  for (const auto& p : points) {
    FramePlan plan;
    const std::string why = plan_frame(nullptr, *p.method, p.options, 64, 48, 0, plan);
    const bool spiral_polygon = p.method->name == "spiral" && !p.options.aperture.is_disc();
    EXPECT_EQ(why, spiral_polygon ? "spiral draws the disc only, not the aperture blades5" : "") << p.id;
  }
}

TEST(Axes, MaxCocFollowsThePatternUnlessFixed) {
  Axes axes;
  axes.methods = {"naive"};
  axes.patterns = {{9, 2}, {21, 2}};
  auto points = expand(axes);
  EXPECT_EQ(points[0].max_coc_px, 8);
  EXPECT_EQ(points[1].max_coc_px, 20);
  axes.max_coc_px = {12};
  for (const auto& p : expand(axes)) EXPECT_EQ(p.max_coc_px, 12);
  // Several radii: an axis of the product, outermost.
  axes.max_coc_px = {4, 12};
  points = expand(axes);
  ASSERT_EQ(points.size(), 4u);
  EXPECT_EQ(points[1].max_coc_px, 4);
  EXPECT_EQ(points[2].max_coc_px, 12);
  axes.max_coc_px = {0};
  EXPECT_THROW(expand(axes), std::invalid_argument);
}

// A frame that cannot fit the budget even at the ceiling rate is named before anything runs, with the
// estimate's parts (issue 22, finding 10); the floor is a lower bound, so a point under it always runs.
TEST(FrameBudget, AFrameEstimatedAboveTheBudgetIsSkippedWithTheEstimate) {
  // naive at 16384 x 16384, N = 201: ~1.1e13 taps.
  const FrameTimeFloor cpu = frame_time_floor(1.1e13, /*on_cpu=*/true, 2);
  EXPECT_DOUBLE_EQ(cpu.taps_per_s, 2e10);
  EXPECT_DOUBLE_EQ(cpu.seconds, 550.0);
  EXPECT_EQ(over_frame_budget(cpu, 300),
            "estimated at least 9.2 min for one frame (1.1e13 taps at <= 2e10 taps/s: 1e10 taps/s a CPU thread x 2 "
            "threads), over the budget of 300 s (--run-over-budget runs it anyway)");
  EXPECT_EQ(over_frame_budget(cpu, 600), "");
  EXPECT_EQ(over_frame_budget(cpu, 0), "");  // no budget: no check
  EXPECT_NE(over_frame_budget(frame_time_floor(1e17, true, 1), 300).find("estimated at least 115.7 days"),
            std::string::npos);
  const FrameTimeFloor gpu = frame_time_floor(1.1e13, /*on_cpu=*/false, 2);
  EXPECT_DOUBLE_EQ(gpu.seconds, 1.1);
  EXPECT_EQ(over_frame_budget(gpu, 1), "estimated at least 1 s for one frame (1.1e13 taps at <= 1e13 taps/s: 1e13 "
                                       "taps/s, above any GPU's gather), over the budget of 1 s (--run-over-budget "
                                       "runs it anyway)");
}

// Figures that fail after the rounds (a fit with too few distinct sizes, say) lose no measurement: the
// measured document is written as the partial results, and the error names it.
TEST(Sweep, FiguresThatFailAfterMeasuringKeepTheRounds) {
  const std::filesystem::path dir = std::filesystem::temp_directory_path() / "bokeh_sweep_derive_fault";
  std::filesystem::remove_all(dir);
  Axes axes;
  axes.methods = {"naive"};
  axes.backends = {"cpu"};
  axes.resolutions = {Resolution{32, 24}};
  axes.patterns = {{3, 1}};
  SweepSettings s;
  s.name = "derive_fault";
  s.out_dir = dir.string();
  s.reference_cache = (dir / "references").string();
  s.plot = false;
  s.cpu_threads = 1;
  s.policy = fast_policy();
  s.policy.min_samples = s.policy.max_samples = 2;
  s.derive = [](nlohmann::json&) { throw std::runtime_error("power-law fit needs distinct x values"); };
  try {
    run_sweep(expand(axes), s);
    ADD_FAILURE() << "the figures' error was swallowed";
  } catch (const std::runtime_error& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find("power-law fit needs distinct x values"), std::string::npos) << message;
    EXPECT_NE(message.find("derive_fault.partial.json"), std::string::npos) << message;
  }
  std::ifstream partial(dir / "derive_fault.partial.json");
  ASSERT_TRUE(partial.good());
  const nlohmann::json doc = nlohmann::json::parse(partial);
  ASSERT_EQ(doc["points"].size(), 1u);
  EXPECT_EQ(doc["points"][0]["samples_ms"].size(), 2u);
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace bokeh
