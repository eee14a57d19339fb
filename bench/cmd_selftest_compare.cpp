// `bokehbench selftest-compare`: measures `compare` itself on this machine. It runs the CI sweep
// (figure9 --quick --budget-s 60, as .ci/regression) repeatedly, with and without a known injected slowdown and, optionally, as a
// "second machine" (half the threads), interleaving the conditions, then compares every pair:
//   false alarms   A/A pairs (the same code twice) with a confident regression
//   detection      A against +P% runs (every sample ran P% more frames than it reports)
//   cross-machine  A against the half-thread runs, both ways (CI runs on another machine than the
//                  baseline's; normalisation by the calibration probes is what should carry over)
// for several thresholds, on normalised and raw times. It is a benchmark (minutes), not a test.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <sstream>
#include <thread>

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <unistd.h>

#include "commands.hpp"
#include "compare.hpp"
#include "report.hpp"

namespace bokeh {

namespace {

struct SelftestOptions {
  int runs = 5;
  std::vector<int> slowdowns_pct = {10, 25};
  std::vector<double> thresholds_pct = {5, 10, 15, 20, 25};
  bool cross_machine = false;
  std::string sweep = "figure9 --quick --budget-s 60";  // what .ci/regression runs
  std::string work_dir = "build/selftest-compare", out = "results/selftest_compare.json";
  bool reuse = false;
};

struct Condition {
  std::string name;  // a, slow10, slow25, half
  int slowdown_pct = 0;
  bool half_threads = false;
};

std::string self_exe() {
  std::error_code ec;
  const auto p = std::filesystem::read_symlink("/proc/self/exe", ec);
  if (ec) throw std::runtime_error("cannot find this program's path (/proc/self/exe)");
  return p.string();
}

std::string shell_quote(const std::string& s) {
  std::string out = "'";
  for (char c : s) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return out + "'";
}

// Runs the sweep for one condition; returns the results file.
std::string run_sweep_process(const SelftestOptions& o, const Condition& c, int run, const std::string& exe) {
  const std::string dir = fmt::format("{}/{}_{}", o.work_dir, c.name, run);
  std::istringstream words(o.sweep);
  std::string name, args;
  words >> name;
  for (std::string w; words >> w;) args += " " + shell_quote(w);
  const std::string result = dir + "/" + name + ".json";
  if (o.reuse && std::filesystem::exists(result)) return result;
  if (o.sweep.find("--no-plot") == std::string::npos) args += " --no-plot";
  std::string cmd = fmt::format("{} {}{} --out-dir {}", shell_quote(exe), shell_quote(name), args, shell_quote(dir));
  if (c.slowdown_pct) cmd += fmt::format(" --inject-slowdown-pct {}", c.slowdown_pct);
  if (c.half_threads) {
    const unsigned cores = std::max(2u, std::thread::hardware_concurrency());
    cmd = fmt::format("LP_NUM_THREADS={} {} --cpu-threads {}", cores / 2, cmd, cores / 2);
  }
  std::filesystem::create_directories(dir);
  cmd += " > " + shell_quote(dir + "/log.txt") + " 2>&1";
  const auto start = std::chrono::steady_clock::now();
  std::fflush(stdout);
  const int status = std::system(cmd.c_str());
  if (status != 0) throw std::runtime_error(fmt::format("the sweep failed ({}): see {}/log.txt", cmd, dir));
  fmt::print("  {:<8} run {}: {:.0f} s\n", c.name, run,
             std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  return result;
}

struct Tally {
  int pairs = 0, pairs_flagged = 0;    // compare's exit status 2 (any point slower)
  int points = 0, points_flagged = 0;  // points with the verdict slower
  int points_same = 0, points_inconclusive = 0;
  nlohmann::json to_json() const {
    auto rate = [](int a, int b) { return b ? static_cast<double>(a) / b : 0.0; };
    return {{"pairs", pairs},
            {"pairs_flagged", pairs_flagged},
            {"pair_rate", rate(pairs_flagged, pairs)},
            {"points", points},
            {"points_slower", points_flagged},
            {"point_rate", rate(points_flagged, points)},
            {"points_same", points_same},
            {"points_inconclusive", points_inconclusive}};
  }
};

double quantile(std::vector<double> v, double q) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  const double pos = q * static_cast<double>(v.size() - 1);
  const auto lo = static_cast<std::size_t>(pos);
  const auto hi = std::min(lo + 1, v.size() - 1);
  return v[lo] + (v[hi] - v[lo]) * (pos - static_cast<double>(lo));
}

void selftest(const SelftestOptions& o) {
  if (o.runs < 2) throw std::invalid_argument("--runs must be at least 2 (A/A pairs)");
  std::vector<Condition> conditions = {{"a", 0, false}};
  for (int pct : o.slowdowns_pct) conditions.push_back({fmt::format("slow{}", pct), pct, false});
  if (o.cross_machine) conditions.push_back({"half", 0, true});
  const std::string exe = self_exe();
  fmt::print("selftest-compare: {} runs of '{}' per condition ({}), interleaved; work in {}\n", o.runs, o.sweep,
             fmt::join([&] {
               std::vector<std::string> n;
               for (const auto& c : conditions) n.push_back(c.name);
               return n;
             }(), ", "),
             o.work_dir);
  const auto start = std::chrono::steady_clock::now();
  std::map<std::string, std::vector<nlohmann::json>> docs;
  std::map<std::string, std::vector<std::string>> paths;
  for (int run = 0; run < o.runs; ++run)
    for (std::size_t k = 0; k < conditions.size(); ++k) {
      // Rotate the order each run so that drift over the session does not favour one condition.
      const Condition& c = conditions[(k + static_cast<std::size_t>(run)) % conditions.size()];
      const std::string path = run_sweep_process(o, c, run, exe);
      paths[c.name].push_back(path);
      docs[c.name].push_back(compare::load_results(path));
    }
  const double sweeps_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

  // Every pair at every threshold, for compare's default (CPU time on lavapipe, normalised) and the
  // alternatives.
  struct Variant {
    const char* label;
    const char* times;
    const char* normalise;
  };
  const Variant variants[] = {{"default (--times auto --normalise auto)", "auto", "auto"},
                              {"cpu time, raw", "cpu", "none"},
                              {"wall time, normalised", "wall", "auto"},
                              {"wall time, raw", "wall", "none"}};
  nlohmann::json by_times = nlohmann::json::object();
  for (const Variant& variant : variants) {
    nlohmann::json by_threshold = nlohmann::json::array();
    for (double t_pct : o.thresholds_pct) {
      compare::Options opt;
      opt.rule.threshold = t_pct / 100;
      opt.times = variant.times;
      opt.normalise = variant.normalise;
      std::vector<double> aa_low, aa_half_width;  // A/A interval lows and half widths, per point
      auto tally = [&](const std::string& base, const std::string& cur, bool skip_same_run, Tally& t,
                       std::vector<double>* lows, double scale) {
        for (std::size_t i = 0; i < docs[base].size(); ++i)
          for (std::size_t j = 0; j < docs[cur].size(); ++j) {
            if (skip_same_run && i == j) continue;
            const compare::Report r = compare::compare_results(docs[base][i], docs[cur][j], opt, paths[base][i], paths[cur][j]);
            if (!r.mismatches.empty())
              throw std::runtime_error(fmt::format("{} and {} are not comparable: {}", paths[base][i], paths[cur][j],
                                                   r.mismatches.front()));
            ++t.pairs;
            if (r.exit_code() == compare::kRegression) ++t.pairs_flagged;
            for (const auto& p : r.points) {
              ++t.points;
              t.points_flagged += p.judgement.verdict == compare::Verdict::slower;
              t.points_same += p.judgement.verdict == compare::Verdict::same;
              t.points_inconclusive += p.judgement.verdict == compare::Verdict::inconclusive;
              if (lows && p.judgement.interval.exists) {
                lows->push_back(p.judgement.interval.low / scale);
                aa_half_width.push_back(std::sqrt(p.judgement.interval.high / p.judgement.interval.low) - 1);
              }
            }
          }
      };
      Tally aa;
      tally("a", "a", true, aa, &aa_low, 1.0);
      nlohmann::json entry = {{"threshold_pct", t_pct}, {"a_a", aa.to_json()}};
      std::vector<double> all_lows = aa_low;  // A/A lows, and injected lows scaled back by the known slowdown
      for (const Condition& c : conditions) {
        if (c.slowdown_pct == 0) continue;
        Tally d;
        tally("a", c.name, false, d, &all_lows, 1 + c.slowdown_pct / 100.0);
        entry[fmt::format("slowdown_{}pct", c.slowdown_pct)] = d.to_json();
      }
      if (o.cross_machine) {
        Tally x;
        tally("a", "half", false, x, nullptr, 1.0);
        tally("half", "a", false, x, nullptr, 1.0);
        entry["cross_machine"] = x.to_json();
      }
      // A slowdown s multiplies the current's samples by 1 + s, so a point is flagged when
      // low_AA (1 + s) > 1 + t: the slowdown detected 95% of the time is (1 + t) / q05(low_AA) - 1.
      if (!all_lows.empty()) {
        entry["smallest_slowdown_detected_95pct"] = (1 + t_pct / 100) / quantile(all_lows, 0.05) - 1;
        entry["interval_half_width_median"] = quantile(aa_half_width, 0.5);
        entry["lows_used"] = all_lows.size();
      }
      by_threshold.push_back(entry);
    }
    by_times[variant.label] = by_threshold;
  }

  nlohmann::json runs = nlohmann::json::object();
  for (const auto& [name, list] : paths) runs[name] = list;
  const nlohmann::json first = docs["a"].front();
  nlohmann::json doc = {{"sweep", o.sweep},
                        {"runs_per_condition", o.runs},
                        {"conditions", [&] {
                           nlohmann::json c = nlohmann::json::array();
                           for (const auto& x : conditions)
                             c.push_back({{"name", x.name}, {"slowdown_pct", x.slowdown_pct}, {"half_threads", x.half_threads}});
                           return c;
                         }()},
                        {"points_per_run", first["points"].size()},
                        {"rule", {{"confidence", 0.95}, {"min_samples", 5}}},
                        {"pairs",
                         "a_a: ordered pairs of distinct A runs (K (K - 1)); slowdown: every A run against every slowed "
                         "run (K^2); cross_machine: A against half-thread runs and back (2 K^2). Pairs share runs, so "
                         "they are not independent trials"},
                        {"sweeps_s", sweeps_s},
                        {"reused_runs", o.reuse},  // true: runs from an earlier session, sweeps_s does not time them
                        {"runs", runs},
                        {"results", by_times}};
  write_results(o.out, "bokehbench.selftest_compare", first["context"], doc);

  for (const Variant& variant : variants) {
    const char* times = variant.label;
    fmt::print("\n{} ({} runs per condition, {} points per run):\n", times, o.runs, first["points"].size());
    fmt::print("{:>9}  {:>22}", "threshold", "A/A false alarms");
    for (int pct : o.slowdowns_pct) fmt::print("  {:>22}", fmt::format("+{}% detected", pct));
    if (o.cross_machine) fmt::print("  {:>22}", "cross-machine alarms");
    fmt::print("  {:>12}\n", "95% detects");
    for (const auto& e : by_times[times]) {
      auto cell = [](const nlohmann::json& t) {
        return fmt::format("{}/{} runs, {:.1f}% pts", t["pairs_flagged"].get<int>(), t["pairs"].get<int>(),
                           100 * t["point_rate"].get<double>());
      };
      fmt::print("{:>8}%  {:>22}", e["threshold_pct"].get<double>(), cell(e["a_a"]));
      for (int pct : o.slowdowns_pct) fmt::print("  {:>22}", cell(e[fmt::format("slowdown_{}pct", pct)]));
      if (o.cross_machine) fmt::print("  {:>22}", cell(e["cross_machine"]));
      fmt::print("  {:>11}\n", e.contains("smallest_slowdown_detected_95pct")
                                    ? fmt::format("+{:.1f}%", 100 * e["smallest_slowdown_detected_95pct"].get<double>())
                                    : std::string("-"));
    }
  }
  fmt::print("\nwrote {} (sweeps took {:.0f} s)\n", o.out, sweeps_s);
}

}  // namespace

void add_selftest_compare_command(CLI::App& app) {
  auto o = std::make_shared<SelftestOptions>();
  auto* cmd = app.add_subcommand("selftest-compare",
                                 "Measure `compare` on this machine: false alarms over A/A runs, detection of injected "
                                 "slowdowns, and (--cross-machine) alarms against a half-thread 'other machine'");
  cmd->add_option("--runs", o->runs, "Runs per condition")->check(CLI::Range(2, 100))->capture_default_str();
  cmd->add_option("--slowdowns-pct", o->slowdowns_pct, "Injected slowdowns, percent (--inject-slowdown-pct)")
      ->check(CLI::Range(1, 100))
      ->capture_default_str();
  cmd->add_option("--thresholds-pct", o->thresholds_pct, "compare thresholds to evaluate, percent")
      ->check(CLI::Range(0.0, 1000.0))
      ->capture_default_str();
  cmd->add_flag("--cross-machine", o->cross_machine,
                "Also run as a slower 'other machine' (LP_NUM_THREADS and --cpu-threads at half the cores) and count "
                "the alarms between the two");
  cmd->add_option("--sweep", o->sweep, "The sweep command and its arguments, as CI runs it")->capture_default_str();
  cmd->add_option("--work-dir", o->work_dir, "Where the runs' results go")->capture_default_str();
  cmd->add_option("--out", o->out, "The summary JSON")->capture_default_str();
  cmd->add_flag("--reuse", o->reuse, "Reuse runs already in --work-dir (to re-evaluate without measuring again)");
  cmd->callback([o] { selftest(*o); });
}

}  // namespace bokeh
