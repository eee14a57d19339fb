// `bokehbench selftest-compare`: measures CI's regression check itself on this machine. It runs
// `bokehbench ab` (paired, as .ci/regression does) repeatedly between two builds of the same code (or
// two copies of one method package, as a user's CI compares its shader), interleaving the conditions,
// and counts:
//   false alarms   A/A runs (no change) that fail, and points found slower
//   detection      runs with a known slowdown of every point, or of one point (a different one each
//                  run), injected into the candidate's times, that fail, and whether the slowed
//                  point was the one found
// and, from the A/A runs' intervals, the smallest slowdown of one point found in 95% of runs (a
// slowdown s multiplies the candidate's paired times, so it moves each interval by exactly 1 + s).
// It is a benchmark (an hour with the defaults), not a test.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <map>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "commands.hpp"
#include "compare.hpp"
#include "paired.hpp"
#include "report.hpp"
#include "runner.hpp"

namespace bokeh {

namespace {

struct SelftestOptions {
  std::string baseline = "build", candidate = "build";
  int runs = 20, injected_runs = 5;
  std::vector<double> slowdowns_pct = {10, 25};
  double threshold_pct = 5;  // what .ci/regression uses
  int max_pairs = paired::Options{}.max_pairs;
  double budget_s = paired::Options{}.budget_s;
  std::string sweep = paired::kDefaultSweep;
  std::string out = "results/selftest_compare.json";
};

struct Condition {
  std::string name;  // a_a, every_10, one_10, ...
  double slowdown_pct = 0;
  bool one_point = false;
};

void selftest(const SelftestOptions& o) {
  std::vector<Condition> conditions = {{"a_a", 0, false}};
  for (double pct : o.slowdowns_pct) {
    conditions.push_back({fmt::format("every_{:g}", pct), pct, false});
    conditions.push_back({fmt::format("one_{:g}", pct), pct, true});
  }
  paired::Options base;
  paired::set_sides(base, o.baseline, o.candidate, o.sweep);  // two builds, or two versions of one's shader
  base.rule.threshold = o.threshold_pct / 100;
  base.max_pairs = o.max_pairs;
  base.budget_s = o.budget_s;
  base.progress = false;

  std::vector<std::string> ids;  // the compared points, from the first run
  std::map<std::string, nlohmann::json> runs;
  std::map<std::string, int> done;
  const auto start = std::chrono::steady_clock::now();
  const int most = std::max(o.runs, o.injected_runs);
  const int total = o.runs + o.injected_runs * static_cast<int>(conditions.size() - 1);
  int finished = 0;
  fmt::print("selftest-compare: {} A/A runs and {} of each injected slowdown of `ab --sweep \"{}\"` at {:g}%, "
             "interleaved\n", o.runs, o.injected_runs, o.sweep, o.threshold_pct);
  for (int r = 0; r < most; ++r)
    for (std::size_t k = 0; k < conditions.size(); ++k) {
      // Rotate the order each run so that drift over the session favours no condition.
      const Condition& c = conditions[(k + static_cast<std::size_t>(r)) % conditions.size()];
      if (done[c.name] >= (c.slowdown_pct > 0 ? o.injected_runs : o.runs)) continue;
      if (c.slowdown_pct > 0 && ids.empty()) continue;  // the point list comes from an A/A run
      paired::Options run = base;
      run.seed = static_cast<std::uint64_t>(1000 * r + k + 1);
      run.inject_slowdown_pct = c.slowdown_pct;
      std::string injected;
      if (c.one_point) injected = ids[static_cast<std::size_t>(done[c.name] * 7 + r) % ids.size()];  // a spread of points
      if (!injected.empty()) run.inject_points = {injected};
      const auto t0 = std::chrono::steady_clock::now();
      const compare::Report report = paired::run(run);
      const double run_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      if (!report.mismatches.empty()) throw std::runtime_error("not comparable: " + report.mismatches.front());
      nlohmann::json points = nlohmann::json::array();
      std::vector<std::string> slower;
      for (const auto& p : report.points) {
        if (ids.size() < report.points.size()) ids.push_back(p.id);
        const auto& ci = p.judgement.interval;
        points.push_back({{"id", p.id},
                          {"verdict", compare::to_string(p.judgement.verdict)},
                          {"measured_again", p.times.find("measured again") != std::string::npos},
                          {"low", ci.exists ? ci.low : 0.0},
                          {"high", ci.exists ? ci.high : 0.0},
                          {"pairs", p.baseline_samples}});
        if (p.judgement.verdict == compare::Verdict::slower) slower.push_back(p.id);
      }
      runs[c.name].push_back({{"seed", run.seed},
                              {"injected_point", injected},
                              {"exit_code", report.exit_code()},
                              {"slower", slower},
                              {"seconds", run_s},
                              {"points", points}});
      ++done[c.name];
      ++finished;
      const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      fmt::print("[{}/{}] {:<9} run {:>2}: exit {}, {} slower{}, {:.0f} s; ~{:.0f} min left\n", finished, total, c.name,
                 done[c.name], report.exit_code(), slower.size(), injected.empty() ? "" : " (slowed: " + injected + ")",
                 run_s, elapsed / finished * (total - finished) / 60);
      std::fflush(stdout);
    }
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

  // Per condition: runs that failed, points found slower, and (one point) whether it was the slowed one.
  nlohmann::json summary = nlohmann::json::object();
  for (const Condition& c : conditions) {
    int failed = 0, points = 0, points_slower = 0, slowed_found = 0, others_found = 0;
    for (const auto& run : runs[c.name]) {
      failed += run["exit_code"].get<int>() == compare::kRegression;
      for (const auto& p : run["points"]) {
        ++points;
        const bool slow = p["verdict"] == "slower";
        points_slower += slow;
        if (c.one_point) (p["id"] == run["injected_point"] ? slowed_found : others_found) += slow;
      }
    }
    const int n = static_cast<int>(runs[c.name].size());
    nlohmann::json entry = {{"slowdown_pct", c.slowdown_pct},
                            {"one_point", c.one_point},
                            {"runs", n},
                            {"runs_failed", failed},
                            {"run_rate", n ? static_cast<double>(failed) / n : 0.0},
                            {"points", points},
                            {"points_slower", points_slower},
                            {"point_rate", points ? static_cast<double>(points_slower) / points : 0.0}};
    if (c.one_point) entry.update({{"slowed_point_found", slowed_found}, {"other_points_found", others_found}});
    summary[c.name] = entry;
  }
  // From the A/A intervals: a slowdown s of one point is found (in the first pass) when low (1 + s)
  // > 1 + t, so the slowdown found in 95% of runs is (1 + t) / q05(low) - 1, per point.
  std::map<std::string, std::vector<double>> lows;
  for (const auto& run : runs["a_a"])
    for (const auto& p : run["points"])
      if (p["low"].get<double>() > 0) lows[p["id"]].push_back(p["low"].get<double>());
  std::vector<double> per_point;
  nlohmann::json by_point = nlohmann::json::object();
  for (const auto& [id, v] : lows) {
    const double s = (1 + o.threshold_pct / 100) / runner::quantile(v, 0.05) - 1;
    by_point[id] = s;
    per_point.push_back(s);
  }
  nlohmann::json derived = {{"smallest_slowdown_found_95pct_by_point", by_point},
                            {"median_point", runner::quantile(per_point, 0.5)},
                            {"best_point", per_point.empty() ? 0.0 : *std::min_element(per_point.begin(), per_point.end())},
                            {"worst_point", per_point.empty() ? 0.0 : *std::max_element(per_point.begin(), per_point.end())},
                            {"how", "per point, (1 + threshold) / (5th percentile of its A/A interval lows) - 1: the "
                                    "slowdown whose first-pass interval clears the threshold in 95% of runs"}};

  nlohmann::json doc = {{"sweep", fmt::format("{}", fmt::join(base.sweep, " "))},
                        {"max_pairs", o.max_pairs},
                        {"budget_s", o.budget_s},
                        {"design", "paired: bokehbench ab between two builds of the same code or two copies of one package (A/A), with a known "
                                   "slowdown injected into the candidate's times (every point, or one point per run)"},
                        {"threshold_pct", o.threshold_pct},
                        {"baseline", base.baseline_exe},
                        {"candidate", base.candidate_exe},
                        {"points_per_run", ids.size()},
                        {"seconds", seconds},
                        {"summary", summary},
                        {"derived_from_a_a", derived},
                        {"runs", runs}};
  write_results(o.out, "bokehbench.selftest_compare", run_context(nullptr), doc);

  fmt::print("\n{:<10} {:>6} {:>14} {:>16} {:>22}\n", "condition", "runs", "runs failed", "points slower",
             "slowed point found");
  for (const Condition& c : conditions) {
    const auto& e = summary[c.name];
    fmt::print("{:<10} {:>6} {:>14} {:>16} {:>22}\n", c.name, e["runs"].get<int>(),
               fmt::format("{} ({:.0f}%)", e["runs_failed"].get<int>(), 100 * e["run_rate"].get<double>()),
               fmt::format("{}/{}", e["points_slower"].get<int>(), e["points"].get<int>()),
               c.one_point ? fmt::format("{}/{}", e["slowed_point_found"].get<int>(), e["runs"].get<int>()) : "-");
  }
  fmt::print("one point's slowdown found in 95% of runs (from the A/A intervals): median point +{:.1f}%, best +{:.1f}%, "
             "worst +{:.1f}%\nwrote {} ({:.0f} min)\n",
             100 * derived["median_point"].get<double>(), 100 * derived["best_point"].get<double>(),
             100 * derived["worst_point"].get<double>(), o.out, seconds / 60);
}

}  // namespace

void add_selftest_compare_command(CLI::App& app) {
  auto o = std::make_shared<SelftestOptions>();
  auto* cmd = app.add_subcommand("selftest-compare",
                                 "Measure CI's regression check (bokehbench ab) on this machine: false alarms over A/A "
                                 "runs, detection of slowdowns injected into every point or one point");
  cmd->add_option("--baseline", o->baseline,
                  "Build folder (or bokehbench) of the baseline, or a method package (then --candidate is one too, "
                  "or a built-in's name, and --sweep names no methods)")
      ->capture_default_str();
  cmd->add_option("--candidate", o->candidate, "Build folder (or bokehbench) of the candidate, or a method package")
      ->capture_default_str();
  cmd->add_option("--runs", o->runs, "A/A runs")->check(CLI::Range(1, 1000))->capture_default_str();
  cmd->add_option("--injected-runs", o->injected_runs, "Runs of each injected condition")
      ->check(CLI::Range(0, 1000))
      ->capture_default_str();
  cmd->add_option("--slowdowns-pct", o->slowdowns_pct, "Injected slowdowns, percent")
      ->check(CLI::Range(0.1, 1000.0))
      ->capture_default_str();
  cmd->add_option("--threshold-pct", o->threshold_pct, "The threshold of the check (.ci/regression's)")
      ->check(CLI::Range(0.1, 1000.0))
      ->capture_default_str();
  cmd->add_option("--sweep", o->sweep, "The sweep, as .ci/regression runs it")->capture_default_str();
  cmd->add_option("--max-pairs", o->max_pairs, "Pairs after which a point stops (ab's --max-pairs)")
      ->check(CLI::Range(2, 10000))
      ->capture_default_str();
  cmd->add_option("--budget-s", o->budget_s, "Measuring time each run aims for (ab's --budget-s)")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  cmd->add_option("--out", o->out, "The summary JSON")->capture_default_str();
  cmd->callback([o] { selftest(*o); });
}

}  // namespace bokeh
