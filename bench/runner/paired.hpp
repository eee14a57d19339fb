#pragma once
// Two builds compared on one machine in one run (`bokehbench ab`, CI's regression check).
//
// Timings made on another machine do not transfer: CPU kinds differ in clock, cache and ISA, and no
// calibration probe maps one microarchitecture's times onto another's. So the baseline is a build
// (of a commit), not a file: each build runs as a worker process that has made the same sweep's
// points ready, and the coordinator asks them for samples in turns. Every round visits every
// unsettled point in a shuffled order, and at each visit the two builds take one sample each, back
// to back, the one going first alternating, so whatever the machine does at that moment (its clock,
// a neighbour's burst, slow drift) is in both halves of the pair and cancels in their ratio. The
// verdict per point comes from the paired log-ratios (compare::judge_paired), with the verdicts and
// exit codes of `compare`.
//
// The worker is a sweep command run with --serve: it answers one JSON request per line on stdin
// and replies one JSON line each on the stdout it was started with (its other output goes to
// stderr). Requests: {"op":"warm","point":i} (prepare and warm up; replies frame_ms),
// {"op":"sample","point":i,"frames":n} (replies frame_ms and cpu_ms per frame), {"op":"quit"}.
// Its first line, unasked, is the hello: protocol, context, and every point with its skip reason
// and work model. An error answers {"error": "..."}.
#include <cstdint>
#include <string>
#include <vector>

#include "compare.hpp"
#include "sweep.hpp"

namespace bokeh::paired {

constexpr int kProtocol = 1;

// The worker's side: serves `points` until "quit" or the end of stdin.
void serve(const std::vector<SweepPoint>& points, const SweepSettings& settings);

struct Options {
  std::string baseline_exe, candidate_exe;  // bokehbench binaries
  // Two method packages' names (A, B) in place of two builds: one worker process of baseline_exe
  // serves the sweep over both (--methods PACKAGE_A PACKAGE_B), so they are loaded side by side and
  // alternate sample by sample in one process; A's points pair with B's of the same axes, named as A's.
  std::vector<std::string> package_methods;
  std::string labels[2];  // how the report names each side ("" : the binary and its commit)
  std::vector<std::string> sweep = {"figure9", "--quick"};  // the sweep command both serve
  compare::Rule rule{0.05, 0.95, 6};  // min_samples: the fewest pairs
  int max_pairs = 15;
  double budget_s = 60;        // measuring time to aim for; every point still gets min pairs
  double sample_min_ms = 40;   // a sample runs enough frames to last this long (on the baseline)
  std::uint64_t seed = 1;      // of the visiting order
  std::string times = "auto";  // auto: process CPU time for lavapipe and the CPU references, wall for a GPU
  // A test of the comparison itself (selftest-compare), 0 in real runs: the candidate's times of
  // the injected points are multiplied by 1 + pct/100 as they arrive, an exact slowdown carrying
  // the run's own noise.
  double inject_slowdown_pct = 0;
  std::vector<std::string> inject_points;  // ids; empty: every point
  // Points the first pass finds slower are measured again by fresh processes of both builds, and
  // stay slower only if they are slower again (paired.cpp says why).
  bool confirm = true;
  bool progress = true;
};

// The bokehbench to run for `given`: a build folder holding one, or a binary (absolute path). Throws
// std::invalid_argument naming `role` and what is wrong.
std::string bokehbench_in(const std::string& given, const std::string& role);
// The sweep `ab` and selftest-compare serve by default: every built-in method, quick.
inline constexpr const char* kDefaultSweep = "figure9 --quick --methods all";
// The two sides of a comparison and the sweep they serve (o.baseline_exe, candidate_exe, sweep, and
// for packages package_methods and labels). Two builds: folders or binaries (bokehbench_in). Two method
// packages (two versions of one's own shader), or a package and a built-in: this binary serves the
// sweep over both in one worker process, the two alternating sample by sample; the sweep must not
// name methods, and kDefaultSweep becomes figure9 --quick over the two.
void set_sides(Options& o, const std::string& baseline, const std::string& candidate, const std::string& sweep);
// A sweep command line ("figure9 --quick") as the words a worker is started with.
std::vector<std::string> sweep_words(const std::string& command_line);

// Runs both workers and returns the comparison (Report::design "paired"). Throws
// std::runtime_error when a worker cannot be started or stops answering (naming it).
compare::Report run(const Options& options);

}  // namespace bokeh::paired
