#include "runner.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <csignal>
#include <ctime>
#include <list>
#include <numeric>
#include <random>
#include <stdexcept>

#include <fmt/format.h>

namespace bokeh::runner {

namespace {

std::atomic<bool> g_interrupted{false};
std::atomic<std::int64_t> g_first_signal_ms{0};

std::int64_t now_ms() {
  return std::chrono::duration_cast<std::chrono::milliseconds>(std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

extern "C" void on_signal(int) {
  // `timeout -s INT` and a terminal's Ctrl-C reach the process and its group, sometimes twice at
  // once: only a second signal well after the first means "stop now".
  const std::int64_t t = now_ms();
  std::int64_t first = 0;
  if (g_first_signal_ms.compare_exchange_strong(first, t)) {
    g_interrupted = true;
    return;
  }
  if (t - first > 1000) std::_Exit(130);
}

double process_cpu_ms() {
  timespec t{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) * 1e3 + static_cast<double>(t.tv_nsec) * 1e-6;
}

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace

InterruptScope::InterruptScope() {
  g_interrupted = false;
  g_first_signal_ms = 0;
  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);
}

InterruptScope::~InterruptScope() {
  std::signal(SIGINT, SIG_DFL);
  std::signal(SIGTERM, SIG_DFL);
  g_interrupted = false;  // the run that saw it has recorded it in its status
}

bool interrupted() { return g_interrupted; }
void request_interrupt() { g_interrupted = true; }

double quantile(std::vector<double> v, double q) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  const double pos = q * static_cast<double>(v.size() - 1);
  const auto lo = static_cast<std::size_t>(std::floor(pos));
  const auto hi = std::min(lo + 1, v.size() - 1);
  return v[lo] + (v[hi] - v[lo]) * (pos - static_cast<double>(lo));
}

Distribution distribution(const std::vector<double>& v) {
  Distribution d;
  if (v.empty()) return d;
  double sum = 0, sq = 0;
  for (double x : v) sum += x, sq += x * x;
  d.mean = sum / static_cast<double>(v.size());
  d.stddev = std::sqrt(std::max(0.0, sq / static_cast<double>(v.size()) - d.mean * d.mean));
  d.median = quantile(v, 0.5), d.q1 = quantile(v, 0.25), d.q3 = quantile(v, 0.75);
  d.min = *std::min_element(v.begin(), v.end()), d.max = *std::max_element(v.begin(), v.end());
  return d;
}

std::vector<double> PointRecord::frame_ms() const {
  std::vector<double> out;
  for (const auto& s : samples) out.push_back(s.frame_ms);
  return out;
}

std::vector<double> PointRecord::cpu_ms() const {
  std::vector<double> out;
  for (const auto& s : samples) out.push_back(s.cpu_ms);
  return out;
}

namespace {

// Frames per sample from a pilot frame's time.
int frames_for(double pilot_ms, const Policy& p) {
  if (!(pilot_ms > 0)) return p.max_frames_per_sample;
  return std::clamp(static_cast<int>(std::ceil(p.sample_min_ms / pilot_ms)), 1, p.max_frames_per_sample);
}

}  // namespace

// Warms up: the target's own warm-up (JIT compilation), a pilot frame, then batches as long as a
// sample until two in a row are no faster than the fastest so far by 3% (clocks ramping from
// idle). Batches, not single frames: between single short frames a GPU waits on the host and
// idles, so its clocks stay low and the ramp never shows; and a pilot taken at idle clocks would
// size samples several times too short. Returns the last batch's frame time.
double warm_up(Target& target, const Policy& p, PointRecord& rec) {
  const auto start = std::chrono::steady_clock::now();
  target.warm_up();
  double last = target.measure(1).frame_ms;
  rec.warm_up_ms.push_back(last);
  if (last >= p.sample_min_ms) return last;  // one frame fills a sample: it keeps the device busy by itself
  double best = last;
  int not_falling = 0;
  while (not_falling < 2 && seconds_since(start) < p.warm_up_max_s) {
    last = target.measure(frames_for(last, p)).frame_ms;
    rec.warm_up_ms.push_back(last);
    if (last < 0.97 * best) not_falling = 0; else ++not_falling;
    best = std::min(best, last);
  }
  return last;
}

// `frames` frames, with the process CPU time they took per `reported` frame.
Sample timed(Target& target, int frames, int reported) {
  const double cpu_start = process_cpu_ms();
  Sample s = target.measure(frames);
  s.cpu_ms = (process_cpu_ms() - cpu_start) / reported;
  return s;
}

namespace {

// Whole frames that make `extra_work_fraction` of `frames` (0 when off).
int extra_frames(int frames, const Policy& p) {
  return static_cast<int>(std::lround(frames * p.extra_work_fraction));
}

// Frames per sample of a point: from its warmed-up frame time, and with extra work injected, a
// multiple of 100/gcd(p, 100) so that the extra is whole frames.
int point_frames(double frame_ms, const Policy& p) {
  int frames = frames_for(frame_ms, p);
  if (p.extra_work_fraction > 0) {
    const int unit = static_cast<int>(100 / std::gcd(std::lround(p.extra_work_fraction * 100), 100L));
    frames = (frames + unit - 1) / unit * unit;
  }
  return frames;
}

// Untimed frames before a sample (Policy::lead_in_ms), sized from the target's last frame time.
void lead_in(Target& target, double frame_ms, const Policy& p) {
  if (p.lead_in_ms <= 0) return;
  const double ms = frame_ms > 0 ? frame_ms : p.lead_in_ms;
  target.measure(std::clamp(static_cast<int>(std::ceil(p.lead_in_ms / ms)), 1, p.max_frames_per_sample));
}

bool settled(const PointRecord& r, const Policy& p, bool by_headlines) {
  if (static_cast<int>(r.samples.size()) >= p.max_samples) return true;
  if (by_headlines || static_cast<int>(r.samples.size()) < p.min_samples) return false;
  return distribution(r.frame_ms()).relative_iqr() <= p.settled_relative_iqr;
}

// This round's visiting order of the active points (Hooks::visit_block and visit_group).
std::vector<std::size_t> round_order(const std::vector<std::size_t>& active, const std::vector<std::size_t>& group,
                                     const std::vector<std::size_t>& block, int round, std::mt19937_64& rng) {
  std::vector<std::size_t> order = active;
  if (group.empty() && block.empty()) {
    std::shuffle(order.begin(), order.end(), rng);
    return order;
  }
  // Active points by block, then group (a point's own index when it has none), in index order.
  std::map<std::size_t, std::map<std::size_t, std::vector<std::size_t>>> members;
  for (std::size_t i : active) {
    const std::size_t g = group.empty() ? i : group.at(i);
    members[block.empty() ? g : block.at(i)][g].push_back(i);
  }
  std::vector<std::size_t> blocks;
  for (const auto& [b, groups] : members) blocks.push_back(b);
  std::shuffle(blocks.begin(), blocks.end(), rng);
  order.clear();
  for (std::size_t b : blocks) {
    std::vector<std::size_t> groups;
    for (const auto& [g, m] : members[b]) groups.push_back(g);
    std::shuffle(groups.begin(), groups.end(), rng);
    for (std::size_t g : groups) {
      std::vector<std::size_t>& m = members[b][g];
      std::rotate(m.begin(), m.begin() + static_cast<std::ptrdiff_t>(round % m.size()), m.end());
      order.insert(order.end(), m.begin(), m.end());
    }
  }
  return order;
}

}  // namespace

namespace {

// The prepared targets a run keeps, by point * replicas + replica, freeing the least recently
// visited when their resident memory passes the policy's limit.
class LiveTargets {
 public:
  LiveTargets(const Policy& policy, Hooks& hooks) : policy_(policy), hooks_(hooks), replicas_(static_cast<std::size_t>(policy.replicas)) {}

  // The target of the point's next sample (its replicas in turn), prepared and warmed when not live.
  Target& for_sample(std::size_t i, PointRecord& rec) {
    const std::size_t key = i * replicas_ + rec.samples.size() % replicas_;
    auto it = live_.find(key);
    if (it == live_.end()) {
      auto target = hooks_.prepare(i);
      ++rec.preparations;
      it = live_.emplace(key, std::move(target)).first;
      if (rec.frames_per_sample == 0) {
        rec.frames_per_sample = point_frames(warm_up(*it->second, policy_, rec), policy_);
        if (hooks_.first_ready) hooks_.first_ready(i, *it->second);
      } else {
        // Another replica, or freed earlier to save memory: compile caches are warm already; one
        // untimed frame takes the first touch of its fresh memory out of the samples.
        it->second->warm_up();
        it->second->measure(1);
      }
      make_room(key);
    }
    recency_.remove(key);
    recency_.push_back(key);
    return *it->second;
  }
  void drop(std::size_t i) {
    for (std::size_t r = 0; r < replicas_; ++r) drop_key(i * replicas_ + r);
  }

 private:
  void drop_key(std::size_t key) {
    live_.erase(key);
    recency_.remove(key);
  }
  void make_room(std::size_t keep) {
    const auto resident = [&] {
      std::uint64_t sum = 0;
      for (const auto& [i, t] : live_) sum += t->resident_bytes();
      return sum;
    };
    while (resident() > policy_.resident_limit_bytes && live_.size() > 1) {
      const auto victim = std::find_if(recency_.begin(), recency_.end(), [&](std::size_t i) { return i != keep; });
      if (victim == recency_.end()) break;
      drop_key(*victim);
    }
  }

  const Policy& policy_;
  Hooks& hooks_;
  std::size_t replicas_;
  std::map<std::size_t, std::unique_ptr<Target>> live_;
  std::list<std::size_t> recency_;  // least recently visited first
};

// One sample of each probe, at the start of a round (its frame count fixed in round 0).
void probe_round(Hooks& hooks, const Policy& policy, int round, std::map<std::string, int>& probe_frames,
                 RunRecord& record) {
  for (auto& [name, probe] : hooks.probes) {
    if (!probe) continue;
    try {
      if (round == 0) {
        PointRecord warm;
        probe_frames[name] = frames_for(warm_up(*probe, policy, warm), policy);
      } else {
        lead_in(*probe, record.probe_ms[name].back(), policy);
      }
      const Sample s = timed(*probe, probe_frames[name], probe_frames[name]);
      record.probe_ms[name].push_back(s.frame_ms);
      record.probe_cpu_ms[name].push_back(s.cpu_ms);
    } catch (const std::exception& e) {  // its device gone (a runaway submission): the rounds go on without it
      fmt::print(stderr, "warning: probe {} stopped after {} rounds: {}\n", name, record.probe_ms[name].size(), e.what());
      probe.reset();
    }
  }
}

// One timed sample of a point (after its lead-in), the extra frames' time spread over those reported.
void take_sample(Target& target, PointRecord& rec, const Policy& policy, int round) {
  lead_in(target, rec.samples.empty() ? rec.warm_up_ms.back() : rec.samples.back().frame_ms, policy);
  const int frames = rec.frames_per_sample, extra = extra_frames(frames, policy);
  Sample sample = timed(target, frames + extra, frames);
  if (extra > 0) {
    const double scale = static_cast<double>(frames + extra) / frames;
    sample.frame_ms *= scale;
    for (auto& [pass, ms] : sample.pass_ms) ms *= scale;
  }
  rec.samples.push_back(std::move(sample));
  rec.sample_round.push_back(round);
}

// After a round: the points still measuring, without those settled on their own and (once every
// point has its minimum samples) those the headlines no longer need.
std::vector<std::size_t> still_active(const std::vector<std::size_t>& active, const Policy& policy, Hooks& hooks,
                                      RunRecord& record, LiveTargets& live) {
  const bool by_headlines = static_cast<bool>(hooks.points_needed);
  std::vector<std::size_t> still;
  for (std::size_t i : active) {
    PointRecord& rec = record.points[i];
    if (!rec.skipped.empty()) continue;
    rec.settled = settled(rec, policy, by_headlines);
    if (rec.settled) live.drop(i); else still.push_back(i);
  }
  const bool everyone_has_min = std::all_of(still.begin(), still.end(), [&](std::size_t i) {
    return static_cast<int>(record.points[i].samples.size()) >= policy.min_samples;
  });
  if (!everyone_has_min || !by_headlines || still.empty()) return still;
  const std::vector<bool> needed = hooks.points_needed(record);
  std::vector<std::size_t> kept;
  for (std::size_t i : still) {
    if (i < needed.size() && !needed[i]) {
      record.points[i].settled = true;
      live.drop(i);
    } else {
      kept.push_back(i);
    }
  }
  if (kept.empty()) record.stop_reason = "headlines settled";
  return kept;
}

}  // namespace

RunRecord run(const std::vector<std::string>& names, const std::vector<std::string>& skip, const Policy& policy,
              Hooks& hooks) {
  const double extra_pct = policy.extra_work_fraction * 100;
  if (extra_pct < 0 || extra_pct > 100 || std::abs(extra_pct - std::round(extra_pct)) > 1e-9)
    throw std::invalid_argument("extra work must be a whole percentage from 0 to 100");
  if (policy.replicas < 1) throw std::invalid_argument("replicas must be at least 1");
  const auto start = std::chrono::steady_clock::now();
  RunRecord record;
  std::vector<std::size_t> active;
  for (std::size_t i = 0; i < names.size(); ++i) {
    PointRecord r;
    r.name = names[i];
    r.skipped = i < skip.size() ? skip[i] : "";
    if (r.skipped.empty()) active.push_back(i);
    record.points.push_back(std::move(r));
  }
  std::mt19937_64 rng(policy.seed);
  LiveTargets live(policy, hooks);
  std::vector<double> last_visit_s(names.size(), 0.0);
  std::map<std::string, int> probe_frames;
  std::size_t visits = 0;

  const bool by_headlines = static_cast<bool>(hooks.points_needed);
  for (int round = 0; !active.empty() && !interrupted(); ++round) {
    const std::vector<std::size_t> order = round_order(active, hooks.visit_group, hooks.visit_block, round, rng);
    record.round_order.push_back(order);
    const auto probes_start = std::chrono::steady_clock::now();
    probe_round(hooks, policy, round, probe_frames, record);
    const double probes_s = seconds_since(probes_start);
    for (std::size_t i : order) {
      if (interrupted()) break;
      PointRecord& rec = record.points[i];
      const auto visit_start = std::chrono::steady_clock::now();
      try {
        take_sample(live.for_sample(i, rec), rec, policy, round);
      } catch (const std::exception& e) {
        rec.skipped = e.what();
        live.drop(i);
      }
      last_visit_s[i] = seconds_since(visit_start);
      rec.wall_s += last_visit_s[i];
      ++visits;
      if (hooks.checkpoint) {
        record.elapsed_s = seconds_since(start);
        hooks.checkpoint(record);
      }
      if (hooks.progress) {
        Progress p;
        p.round = round;
        p.visits_done = visits;
        p.points_total = names.size();
        p.elapsed_s = seconds_since(start);
        // Time left: the rounds every point still owes (min_samples), at least; then what the budget
        // allows, up to max_samples.
        double round_s = 0;
        for (std::size_t a : active) round_s += last_visit_s[a];
        p.points_active = active.size();
        const double owed = std::max(0, policy.min_samples - round - 1) * round_s;
        const double most = std::max(0, policy.max_samples - round - 1) * round_s;
        p.eta_s = std::max(owed, std::min(most, policy.budget_s - p.elapsed_s));
        hooks.progress(p, rec);
      }
    }
    if (interrupted()) break;
    active = still_active(active, policy, hooks, record, live);
    if (active.empty()) {
      if (record.stop_reason.empty()) record.stop_reason = by_headlines ? "max_samples reached" : "every point settled";
      break;
    }
    const bool everyone_has_min = std::all_of(active.begin(), active.end(), [&](std::size_t i) {
      return static_cast<int>(record.points[i].samples.size()) >= policy.min_samples;
    });
    double next_round_s = probes_s;  // as the points still active took in their last visits
    for (std::size_t i : active) next_round_s += last_visit_s[i];
    if (everyone_has_min && budget_spent(seconds_since(start), next_round_s, policy.budget_s)) {
      record.stop_reason = "budget spent";
      break;
    }
  }
  record.status = interrupted() ? "interrupted" : "complete";
  if (interrupted()) record.stop_reason = "interrupted";
  record.elapsed_s = seconds_since(start);
  return record;
}

RunRecord followed_by(RunRecord earlier, const RunRecord& later) {
  if (earlier.points.size() != later.points.size())
    throw std::invalid_argument(fmt::format("followed_by: {} points before, {} after", earlier.points.size(),
                                            later.points.size()));
  const int offset = static_cast<int>(earlier.round_order.size());
  if (earlier.round_process.size() < earlier.round_order.size()) earlier.round_process.resize(earlier.round_order.size(), 0);
  const int process = earlier.round_process.empty()
                          ? 0
                          : *std::max_element(earlier.round_process.begin(), earlier.round_process.end()) + 1;
  for (const auto& order : later.round_order) {
    earlier.round_order.push_back(order);
    earlier.round_process.push_back(process);
  }
  for (const auto& [name, ms] : later.probe_ms) earlier.probe_ms[name].insert(earlier.probe_ms[name].end(), ms.begin(), ms.end());
  for (const auto& [name, ms] : later.probe_cpu_ms)
    earlier.probe_cpu_ms[name].insert(earlier.probe_cpu_ms[name].end(), ms.begin(), ms.end());
  for (std::size_t i = 0; i < later.points.size(); ++i) {
    PointRecord& to = earlier.points[i];
    const PointRecord& from = later.points[i];
    if (from.samples.empty()) {  // not measured later: a reason it was skipped counts where nothing measured it
      if (to.samples.empty() && !from.skipped.empty()) to.skipped = from.skipped;
      continue;
    }
    to.samples.insert(to.samples.end(), from.samples.begin(), from.samples.end());
    for (int round : from.sample_round) to.sample_round.push_back(offset + round);
    to.warm_up_ms.insert(to.warm_up_ms.end(), from.warm_up_ms.begin(), from.warm_up_ms.end());
    if (to.frames_per_sample == 0) to.frames_per_sample = from.frames_per_sample;
    to.wall_s += from.wall_s;
    to.settled = from.settled;
    to.skipped.clear();  // measured later, whatever stopped it before
  }
  return earlier;
}

}  // namespace bokeh::runner
