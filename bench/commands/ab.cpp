// `bokehbench ab BASELINE CANDIDATE`: is the candidate build slower than the baseline build on this
// machine? Both builds serve the same sweep as worker processes and are timed back to back, round
// by round (bench/runner/paired.hpp); verdicts and exit codes are those of `compare`.
// bench/ab does the same for two commits (it builds them first).
#include <fmt/format.h>

#include <algorithm>

#include "commands.hpp"
#include "runner.hpp"
#include "store.hpp"
#include "compare.hpp"
#include "paired.hpp"
#include "report.hpp"

namespace bokeh {

namespace {

struct AbOptions {
  std::string baseline, candidate, sweep = paired::kDefaultSweep, json_out, store;
  double threshold_pct = 5;
  paired::Options run;
};

// Both builds' samples into the results store, as two runs of sweep "ab-<sweep>" (their own series:
// paired samples of CI's check are not pooled with a sweep's), each under its own commit and context;
// the candidate's run also holds the paired new / old ratio per point (headline figures new_over_old/ID).
void append_builds(const compare::Report& report, const AbOptions& o) {
  if (!report.mismatches.empty() || o.run.inject_slowdown_pct > 0) return;  // nothing measured, or a test
  auto store = history::Store::open(o.store, true);
  const std::string sweep = "ab-" + (o.run.sweep.empty() ? std::string("sweep") : o.run.sweep.front());
  for (int side = 0; side < 2; ++side) {
    nlohmann::json doc = {{"schema", "bokehbench." + sweep}, {"context", report.contexts[side]}, {"status", "complete"},
                          {"points", nlohmann::json::array()}};
    for (const auto& p : report.points) {
      if (p.wall_ms[side].empty()) continue;
      std::vector<double> sorted = p.wall_ms[side];
      std::sort(sorted.begin(), sorted.end());
      const auto at = [&](double q) { return sorted[static_cast<std::size_t>(q * (sorted.size() - 1))]; };
      doc["points"].push_back({{"id", p.id},
                               {"method", p.id.substr(0, p.id.find('/'))},
                               {"backend", p.backend},
                               {"frame_ms", {{"median", runner::quantile(p.wall_ms[side], 0.5)}, {"q1", at(0.25)}, {"q3", at(0.75)}}},
                               {"samples_ms", p.wall_ms[side]},
                               {"samples_cpu_ms", p.cpu_ms[side]}});
    }
    // The candidate's run carries the paired comparison itself (new / old per point, with its interval):
    // the series CI's check reads over commits, a few percent wide where a point's own median moves 12-17%.
    if (side == 1) {
      doc["paired_ratios"] = nlohmann::json::array();
      for (const auto& p : report.points) {
        const compare::Judgement& j = p.judgement;
        if (!(j.ratio_of_medians > 0)) continue;
        nlohmann::json r = {{"id", p.id}, {"ratio", j.ratio_of_medians}, {"times", p.times}};
        if (j.interval.exists) r.update({{"low", j.interval.low}, {"high", j.interval.high}});
        doc["paired_ratios"].push_back(std::move(r));
      }
    }
    const auto id = store->append_document(doc, command_line(), side == 0 ? "ab baseline" : "ab candidate");
    fmt::print("appended the {} build's samples as run {} to the results store {}\n", side == 0 ? "baseline" : "candidate",
               id, store->url());
  }
}

void run_ab(AbOptions& o) {
  // Before any measuring: a file that cannot be written fails now, not after the pairs (and never after a verdict).
  if (!o.json_out.empty()) check_writable_file(o.json_out);
  o.run.rule.threshold = o.threshold_pct / 100;
  paired::set_sides(o.run, o.baseline, o.candidate, o.sweep);
  const compare::Report report = paired::run(o.run);
  fmt::print("\n");
  if (!o.store.empty()) append_builds(report, o);
  report_verdicts(report, o.json_out);
}

}  // namespace

void add_ab_command(CLI::App& app) {
  auto o = std::make_shared<AbOptions>();
  auto* cmd = app.add_subcommand(
      "ab",
      "Is CANDIDATE slower than BASELINE on this machine? Both builds (or both method packages: two versions of "
      "one's own shader, loaded side by side in one process) run the same sweep, timed back to back in paired rounds. Exit status as compare: 0 no confident regression, 1 error, 2 a point confidently slower by "
      "more than the threshold, 3 nothing comparable, 4 work counters changed without a timing regression");
  cmd->add_option("baseline", o->baseline,
                  "Build folder (or bokehbench binary) of the baseline, or a method package (FOLDER or FOLDER@GIT-REV)")
      ->required();
  cmd->add_option("candidate", o->candidate, "Build folder (or bokehbench binary) under test, or a method package")->required();
  cmd->add_option("--sweep", o->sweep,
                  "The sweep both builds serve: a command and its axis flags (two packages: default figure9 --quick, "
                  "over the two packages)")
      ->capture_default_str();
  add_verdict_flags(cmd, o->threshold_pct, o->run.rule.confidence);
  cmd->add_option("--min-pairs", o->run.rule.min_samples, "Pairs every point gets (fewer: inconclusive)")
      ->check(CLI::Range(2, 10000))
      ->capture_default_str();
  cmd->add_option("--max-pairs", o->run.max_pairs, "Pairs after which a point stops even if its interval is wide")
      ->check(CLI::Range(2, 10000))
      ->capture_default_str();
  cmd->add_option("--budget-s", o->run.budget_s, "Measuring time to aim for (every point still gets --min-pairs)")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  cmd->add_option("--sample-ms", o->run.sample_min_ms, "Each sample runs frames enough to last this long")
      ->check(CLI::Range(1.0, 10000.0))
      ->capture_default_str();
  cmd->add_option("--seed", o->run.seed, "Seed of the visiting order")->capture_default_str();
  cmd->add_option("--times", o->run.times,
                  "auto: process CPU time per frame for lavapipe and the CPU references, timestamps on a GPU; "
                  "wall; cpu")
      ->check(CLI::IsMember({"auto", "wall", "cpu"}))
      ->capture_default_str();
  cmd->add_flag("!--no-confirm", o->run.confirm,
                "Do not measure flagged points again with fresh processes (one process's memory layout can slow a point)");
  cmd->add_option("--store", o->store, "Also append both builds' samples to this results store (SQLite file or "
                                       "postgresql:// URL) as two runs of sweep ab-SWEEP");
  cmd->add_option("--json", o->json_out, "Also write the comparison as JSON here (schema compare, design paired)");
  cmd->add_option("--inject-slowdown-pct", o->run.inject_slowdown_pct,
                  "Test of ab itself only: multiply the candidate's times by 1 + this / 100")
      ->check(CLI::Range(0.0, 1000.0));
  cmd->add_option("--inject-point", o->run.inject_points, "With --inject-slowdown-pct: only these points (ids)");
  cmd->callback([o] { run_ab(*o); });
}

}  // namespace bokeh
