#pragma once
// The interleaved measuring loop, for any kind of point (it knows nothing of Vulkan or methods).
//
// A machine whose speed drifts (a shared VM moved by 1.6x within minutes, a GPU ramping its clocks)
// biases any comparison of points measured one after the other. So points are measured in rounds:
// every round visits every unfinished point once, in a fresh shuffled order (recorded), and each
// visit takes one sample. Every point gets its first sample before any gets its second, and slow
// drift spreads over all points instead of landing on one method. Probes (the calibration kernels)
// are timed at the start of every round, so the drift over the run is on record.
//
// A point leaves the rounds once it has min_samples and its relative IQR is at most
// settled_relative_iqr, or at max_samples; rounds stop when no point is left, or when the budget is
// spent and every point has min_samples. A command whose claims are figures derived from several
// points (a ratio, a growth exponent) stops on those instead (Hooks::points_needed).
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

namespace bokeh::runner {

struct Sample {
  double frame_ms = 0;                    // mean over the sample's frames
  std::map<std::string, double> pass_ms;  // per pass, mean per frame (GPU timestamps; empty on the CPU)
  // The process's CPU time per frame over the sample, all threads (set by the runner). With
  // lavapipe and the CPU references this is the work done, which other processes competing for
  // the cores do not inflate the way they inflate wall-clock time; on a real GPU it is host overhead.
  double cpu_ms = 0;
};

// A point made ready to measure: its resources allocated and its inputs uploaded.
class Target {
 public:
  virtual ~Target() = default;
  virtual void warm_up() = 0;                  // before its first sample (JIT compilation, page faults)
  virtual Sample measure(int frames) = 0;      // `frames` frames back to back
  virtual std::uint64_t resident_bytes() const { return 0; }  // what it holds while alive
};

struct Policy {
  double budget_s = 60;                // measuring time to aim for, all points together
  int min_samples = 5;  // fewer make a poor IQR (with 3, the IQR is half the range)
  int max_samples = 15;
  double settled_relative_iqr = 0.05;
  double sample_min_ms = 60;           // a sample runs enough frames to last at least this long
  int max_frames_per_sample = 4096;    // so that frames of 0.015 ms (a fast GPU, small image) still fill one
  // Warm-up runs batches as long as a sample while successive batches still get faster (clocks
  // ramping from idle), for at most this long; frames longer than sample_min_ms warm up with one frame.
  double warm_up_max_s = 3;
  // Before every sample (and probe), frames worth this long run untimed: a discrete GPU left idle
  // while other points (or the CPU references) ran has lowered its clocks by then. <= 0: none
  // (run_sweep turns < 0 into its device's default).
  double lead_in_ms = -1;
  // A test of `compare` (--inject-slowdown-pct), 0 in real runs: every sample runs this fraction
  // more frames than it reports, so each point's frame time grows by exactly that fraction of its
  // own work. It must be p/100 with a whole p; frames per sample become multiples of 100/gcd(p, 100).
  double extra_work_fraction = 0;
  std::uint64_t resident_limit_bytes = 4ull << 30;  // live targets beyond this are freed, least recent first
  // Independent preparations of each point, its visits taking them in turn: each has allocations of its
  // own, whose placement is a draw on some machines (FLAG's GPU vertical pass up to 35% apart between two
  // identical targets on the EPYC VM, README), so a point's samples span that many draws.
  int replicas = 1;
  std::uint64_t seed = 1;                            // of the shuffled visiting order
};

struct PointRecord {
  std::string name;
  std::string skipped;  // why it was not measured (or stopped being measured); empty when measured
  int frames_per_sample = 0;
  std::vector<Sample> samples;
  std::vector<int> sample_round;   // the round each sample was taken in
  std::vector<double> warm_up_ms;  // the frame times while warming up, in order
  int preparations = 0;            // how often it was made ready (more than once: freed to save memory)
  double wall_s = 0;               // time spent on it, preparation and warm-up included
  bool settled = false;

  std::vector<double> frame_ms() const;
  std::vector<double> cpu_ms() const;
};

struct RunRecord {
  std::vector<PointRecord> points;
  std::vector<std::vector<std::size_t>> round_order;   // per round, the point indices in visiting order
  std::vector<int> round_process;  // per round, the process (0-based) that measured it (processes.hpp); empty: one
  std::map<std::string, std::vector<double>> probe_ms;  // per probe, one time per round
  std::map<std::string, std::vector<double>> probe_cpu_ms;  // per probe, its process CPU time per round
  std::string status = "partial";                       // partial (running), complete, interrupted
  // Why the rounds ended: "every point settled", "headlines settled", "budget spent",
  // "max_samples reached", "interrupted".
  std::string stop_reason;
  double elapsed_s = 0;
};

// Whether the rounds end on the budget after a round that ended `elapsed_s` into the run, the next
// expected to take `next_round_s`: once that round would end further past the budget than now is
// short of it (elapsed + next / 2 >= budget), so a run ends as near its budget as its rounds allow,
// on either side, rather than always up to a round past it (3 processes of 100 s each ran 5m18s-5m25s).
inline bool budget_spent(double elapsed_s, double next_round_s, double budget_s) {
  return elapsed_s + next_round_s / 2 >= budget_s;
}

// `earlier`'s rounds followed by `later`'s (the same points, in the same order), `later`'s measured by
// the process after the last of `earlier`'s: a run of several processes as a later one of them sees it,
// its own rounds after those the processes before it measured (processes.hpp), and how processes::run
// joins the processes' results. A point measured later takes the later settled flag and is not skipped;
// one not measured later keeps what it had, or the later reason it was skipped if nothing measured it.
RunRecord followed_by(RunRecord earlier, const RunRecord& later);

// Whether a run's rounds ended because its figures settled (not on the budget, a cap or an interrupt).
inline bool stopped_settled(const std::string& stop_reason) {
  return stop_reason == "every point settled" || stop_reason == "headlines settled";
}

struct Progress {
  int round = 0;  // 0-based
  std::size_t visits_done = 0, points_active = 0, points_total = 0;
  double elapsed_s = 0, eta_s = 0;
};

struct Hooks {
  // Makes point i ready; an exception skips the point with its text as the reason.
  std::function<std::unique_ptr<Target>(std::size_t i)> prepare;
  // Once per point, after its first warm-up (e.g. to read its output and measure its error); an
  // exception skips the point.
  std::function<void(std::size_t i, Target& target)> first_ready;
  // Timed once at the start of every round.
  std::vector<std::pair<std::string, std::unique_ptr<Target>>> probes;
  // After every visit, with the record so far (e.g. to write partial results).
  std::function<void(const RunRecord& record)> checkpoint;
  // After every visit: where the run stands.
  std::function<void(const Progress& progress, const PointRecord& visited)> progress;
  // visit_group[i]: points with the same value are visited back to back in every round (e.g. the
  // methods compared at one size, so their ratio comes from adjacent measurements); the groups'
  // order is shuffled and the order inside a group turns by one each round, so two points take
  // turns going first. Empty: every point is a group of its own.
  std::vector<std::size_t> visit_group;
  // visit_block[i]: groups whose points share a block are visited one after another, as one run of
  // visits in every round (e.g. every size of one backend, so a growth exponent fitted to one round's
  // curve comes from measurements seconds apart, not spread over the whole round); the blocks' order
  // and the groups' order inside a block are shuffled. Empty: every group is a block of its own.
  std::vector<std::size_t> visit_block;
  // After every round once every active point has min_samples: needed[i] false takes point i out of
  // the rounds (settled): every figure it feeds is as tight as asked, so later rounds spend their time
  // on the figures still too wide; the run ends when no point is needed ("headlines settled"). When
  // set, no point leaves by its own IQR, since a figure drawn from several points needs them all in
  // the same rounds; max_samples and the budget still end the run. Empty: points leave as above.
  std::function<std::vector<bool>(const RunRecord& record)> points_needed;
};

// Warms `target` up as the rounds do (its own warm-up, a pilot frame, then batches as long as a
// sample until two in a row are no faster), recording the batches in rec.warm_up_ms; returns the
// last batch's frame time.
double warm_up(Target& target, const Policy& policy, PointRecord& rec);
// `frames` frames back to back, with the process CPU time they took per `reported` frame.
Sample timed(Target& target, int frames, int reported);

// names[i] is point i; skip[i], when not empty, keeps it out of the rounds with that reason.
RunRecord run(const std::vector<std::string>& names, const std::vector<std::string>& skip, const Policy& policy,
              Hooks& hooks);

// Median, quartiles, min, max, mean and standard deviation of a sample.
struct Distribution {
  double median = 0, q1 = 0, q3 = 0, min = 0, max = 0, mean = 0, stddev = 0;
  double relative_iqr() const { return median > 0 ? (q3 - q1) / median : 0; }
};
Distribution distribution(const std::vector<double>& values);
double quantile(std::vector<double> values, double q);

// SIGINT and SIGTERM (to the process or its whole group) ask a run to stop after the current visit;
// a second signal more than a second later ends the process at once.
class InterruptScope {
 public:
  InterruptScope();
  ~InterruptScope();
  InterruptScope(const InterruptScope&) = delete;
  InterruptScope& operator=(const InterruptScope&) = delete;
};
bool interrupted();
void request_interrupt();  // as a signal would (tests)

}  // namespace bokeh::runner
