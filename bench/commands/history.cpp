// `bokehbench history ...`: the results store's runs, a point's series over commits per machine, the
// change points of every series, importing results files, and the measurements of the history itself
// (change-point detection on synthetic histories, the store's cost). `bokehbench merge`: shards into one
// results file.
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <map>
#include <random>
#include <set>
#include <thread>

#include <fmt/format.h>

#include "commands.hpp"
#include "compare.hpp"
#include "history.hpp"
#include "html_report.hpp"
#include "intervals.hpp"
#include "merge.hpp"
#include "report.hpp"
#include "store.hpp"

namespace bokeh {

namespace {

using history::Store;

struct HistoryOptions {
  std::string store = history::default_store_url("results");
  std::string point, sweep, metric = "wall", json_out;
  bool list_points = false;  // list: each run's points and its scheduler job
  double max_p_value = 0.01;
  int permutations = 999, min_segment = 3;
  std::vector<std::string> files;
  // evaluate
  int commits = 30, histories = 10;
  std::vector<std::string> steps = {"10:5", "20:10"};
  unsigned seed = 1;
  // cost
  int runs = 1000, writers = 1;
  std::string out_html;
};

history::ChangePointOptions change_point_options(const HistoryOptions& o) {
  history::ChangePointOptions c;
  c.max_p_value = o.max_p_value;
  c.permutations = o.permutations;
  c.min_segment = o.min_segment;
  c.seed = o.seed;
  return c;
}

void add_store_option(CLI::App* cmd, HistoryOptions& o) {
  cmd->add_option("--store", o.store, "Results store: a file (SQLite) or postgresql://user@host/db")->capture_default_str();
}
void add_change_point_options(CLI::App* cmd, HistoryOptions& o) {
  cmd->add_option("--max-p-value", o.max_p_value, "A change point is kept when its permutation p-value is at most this")
      ->check(finite_number())
      ->check(CLI::Range(1e-6, 0.5))
      ->capture_default_str();
  cmd->add_option("--permutations", o.permutations, "Permutations of each test")->check(CLI::Range(19, 100000))->capture_default_str();
  cmd->add_option("--min-segment", o.min_segment, "Commits on each side of a change point, at least")
      ->check(CLI::Range(2, 1000))
      ->capture_default_str();
  cmd->add_option("--metric", o.metric, "wall: frame time (timestamps, wall clock); cpu: process CPU time per frame")
      ->check(CLI::IsMember({"wall", "cpu"}))
      ->capture_default_str();
}

void list_runs(const HistoryOptions& o) {
  auto store = Store::open(o.store, false);
  const auto runs = store->runs();
  fmt::print("{} runs in {} ({})\n", runs.size(), o.store, store->kind());
  fmt::print("{:>5}  {:<20}  {:<14}  {:<9}  {:<6}  {:<11}  {:>6}  {:>7}  {}\n", "id", "date (UTC)", "commit", "sweep", "shard",
             "status", "points", "figures", "machine");
  for (const auto& r : runs) {
    const auto points = store->points(r.id);
    fmt::print("{:>5}  {:<20}  {:<14}  {:<9}  {:<6}  {:<11}  {:>6}  {:>7}  {}\n", r.id, r.date_utc, r.commit.substr(0, 14),
               r.sweep, r.shard.empty() ? "all" : r.shard, r.status, points.size(), store->headlines(r.id).size(),
               r.machine);
    if (!o.list_points) continue;
    // Which task measured which point: a shard's run names its job (context.sweep_id, e.g. slurm:JOB).
    const auto context = nlohmann::json::parse(r.context, nullptr, false);
    const std::string job = context.is_object() ? context.value("sweep_id", std::string()) : std::string();
    if (!job.empty()) fmt::print("       job {}\n", job);
    for (const auto& p : points) fmt::print("       {}\n", p.point_id);
  }
}

void print_series(const HistoryOptions& o) {
  auto store = Store::open(o.store, false);
  const auto all = history::series(*store, o.point, history::parse_metric(o.metric), change_point_options(o));
  for (const auto& s : all) {
    const bool interval = !s.values.empty() && std::all_of(s.values.begin(), s.values.end(), [](auto& v) { return v.has_interval; });
    if (s.headline)
      fmt::print("{} ({}), headline figure ({}), on {}:\n", s.point_id, s.sweep, s.unit, s.machine);
    else
      fmt::print("{} ({}), {}, on {}:\n", s.point_id, s.sweep, history::metric_name(history::parse_metric(o.metric)), s.machine);
    fmt::print("  {:<14}  {:<20}  {:>12}  {:>23}  {:>4}\n", "commit", "date (UTC)", s.headline ? s.unit : "median ms",
               !s.headline ? "IQR ms" : interval ? "95% interval" : "spread over runs", "runs");
    for (std::size_t i = 0; i < s.values.size(); ++i) {
      const auto& v = s.values[i];
      for (const auto& st : s.steps)
        if (st.index == i)
          fmt::print("  ---- change point: {:+.1f}% (p {:.3f}) ----\n", (st.ratio - 1) * 100, st.p_value);
      if (i > 0 && v.package != s.values[i - 1].package)
        fmt::print("  ---- the method package changed: content hash {} -> {} ----\n",
                   s.values[i - 1].package.empty() ? "none" : s.values[i - 1].package, v.package.empty() ? "none" : v.package);
      fmt::print("  {:<14}  {:<20}  {:>12.4f}  {:>10.4f} - {:<10.4f}  {:>4}\n", v.commit.substr(0, 14), v.date_utc, v.median_ms,
                 v.q1_ms, v.q3_ms, v.runs);
    }
  }
}

void print_changes(const HistoryOptions& o) {
  auto store = Store::open(o.store, false);
  const auto all = history::series(*store, o.point, history::parse_metric(o.metric), change_point_options(o));
  std::size_t with_steps = 0;
  nlohmann::json out = nlohmann::json::array();
  for (const auto& s : all) {
    if (!o.sweep.empty() && s.sweep != o.sweep) continue;
    nlohmann::json steps = nlohmann::json::array();
    for (const auto& st : s.steps) {
      fmt::print("{}  on {}: {:+.1f}% between {} and {} (p {:.3f}, confidence {:.1f}%), {} commits in the series\n", s.point_id,
                 s.machine, (st.ratio - 1) * 100, st.before_commit.substr(0, 12), st.commit.substr(0, 12), st.p_value,
                 (1 - st.p_value) * 100, s.values.size());
      steps.push_back({{"commit", st.commit}, {"before_commit", st.before_commit}, {"ratio", st.ratio}, {"p_value", st.p_value}});
    }
    with_steps += !s.steps.empty();
    out.push_back({{"point", s.point_id}, {"headline", s.headline}, {"unit", s.unit}, {"sweep", s.sweep}, {"machine", s.machine},
                   {"commits", s.values.size()}, {"steps", steps}});
  }
  fmt::print("{} of {} series have change points (E-divisive means, p <= {}, {} permutations, {} commits a side at least)\n",
             with_steps, all.size(), o.max_p_value, o.permutations, o.min_segment);
  if (!o.json_out.empty()) {
    write_results(o.json_out, "bokehbench.history_changes", run_context(nullptr),
                  {{"store", o.store}, {"metric", o.metric}, {"max_p_value", o.max_p_value}, {"permutations", o.permutations},
                   {"min_segment", o.min_segment}, {"series", out}});
    fmt::print("wrote {}\n", o.json_out);
  }
}

// Every file is read and checked before anything is appended: a bad file leaves the store as it was.
void import_files(const HistoryOptions& o) {
  std::vector<std::pair<history::RunRow, nlohmann::json>> runs;
  for (const auto& path : o.files) {
    nlohmann::json doc = compare::load_results(path);
    try {
      auto run = history::run_of(doc, "imported", std::filesystem::path(path).filename().string());  // checks doc first
      runs.emplace_back(std::move(run), std::move(doc));
    } catch (const std::exception& e) {
      throw std::runtime_error(fmt::format("{}: {}; nothing was imported", path, e.what()));
    }
  }
  auto store = Store::open(o.store, true);
  std::set<std::tuple<std::string, std::string, std::string, std::string>> stored;
  for (const auto& r : store->runs()) stored.emplace(r.sweep, r.commit, r.date_utc, r.machine);
  for (std::size_t i = 0; i < runs.size(); ++i) {
    const auto& [run, doc] = runs[i];
    if (!stored.emplace(run.sweep, run.commit, run.date_utc, run.machine).second) {
      fmt::print("{}: already in the store ({} of {} at {}), skipped\n", o.files[i], run.sweep, run.commit, run.date_utc);
      continue;
    }
    std::int64_t duplicate_of = 0;
    const auto id = store->append_document(doc, "imported", run.source, &duplicate_of);
    fmt::print("{}: run {} ({}, {}, {} points, {} headline figures){}\n", o.files[i], id, run.sweep, run.commit,
               history::points_of(doc).size(), history::headlines_of(doc).size(),
               duplicate_of ? fmt::format("; shard {} of this sweep is already run {}: kept as '{}', counted once", run.shard,
                                          duplicate_of, history::kDuplicateShard)
                            : "");
  }
}

void merge_files(const HistoryOptions& o) {
  if (o.json_out.empty()) throw std::invalid_argument("merge: --out FILE is required");
  check_writable_file(o.json_out, o.files);
  std::vector<nlohmann::json> docs;
  for (const auto& f : o.files) docs.push_back(compare::load_results(f));
  nlohmann::json merged = merge_shards(docs, o.files);
  add_median_intervals(merged);
  // The command's derived figures over all the merged points, by the command's own code (commands.hpp).
  static const std::map<std::string, void (*)(nlohmann::json&)> derivers = {{"bokehbench.figure9", derive_figure9},
                                                                             {"bokehbench.adaptive", derive_adaptive},
                                                                             {"bokehbench.tradeoff", derive_tradeoff},
                                                                             {"bokehbench.buffers", derive_buffers}};
  const std::string schema = merged.value("schema", "");
  const auto deriver = derivers.find(schema);
  const std::string shard1 = merged["shards"][0]["shard"].get<std::string>();
  // merge_shards keeps round_process only when every shard has the same one.
  const bool round_map_dropped =
      !merged["measurement"].contains("round_process") &&
      std::any_of(merged["shards"].begin(), merged["shards"].end(),
                  [](const nlohmann::json& s) { return s["measurement"].contains("round_process"); });
  if (deriver != derivers.end()) {
    deriver->second(merged);
    merged["derived_recomputed"] = true;
    merged["merged_note"] = fmt::format("{} shards joined by `bokehbench merge`; context and measurement are shard {}'s (each "
                                        "shard's are under shards); the command's derived figures were recomputed over "
                                        "all merged points by the command's own code{}{}",
                                        docs.size(), shard1,
                                        schema == "bokehbench.figure9" ? " (probe drift and stop reason: shard " + shard1 + "'s)" : "",
                                        round_map_dropped ? "; the shards split their rounds between processes differently, "
                                                            "so no figure is widened by the spread between processes"
                                                          : "");
  } else {
    merged["derived_recomputed"] = false;
    merged["merged_note"] = fmt::format("{} shards joined by `bokehbench merge`; context and measurement are shard {}'s (each "
                                        "shard's are under shards); derived figures were NOT recomputed ({} has no "
                                        "derivation merge knows): only the points are merged",
                                        docs.size(), shard1, schema);
  }
  write_text_atomically(o.json_out, merged.dump(2) + "\n");
  fmt::print("merged {} shards ({} points, {} skipped, {}) into {}; derived figures {}\n", o.files.size(), merged["points"].size(),
             merged["skipped"].size(), merged["status"].get<std::string>(), o.json_out,
             deriver != derivers.end() ? "recomputed over all points" : "NOT recomputed (" + schema + " has none merge knows)");
  if (merged["context"].contains("shard_machines"))
    fmt::print("note: the shards were measured on {} machines: {}\n", merged["context"]["shard_machines"].size(),
               merged["context"]["shard_machines"].dump());
}

// --steps "COMMIT:PCT": a step of PCT percent at commit index COMMIT (0-based, the first commit after it).
std::vector<std::pair<int, double>> parse_steps(const std::vector<std::string>& steps, int commits) {
  std::vector<std::pair<int, double>> out;
  for (const auto& s : steps) {
    const auto colon = s.find(':');
    try {
      if (colon == std::string::npos) throw std::invalid_argument(s);
      std::size_t used = 0;
      const int at = std::stoi(s.substr(0, colon), &used);
      const double pct = std::stod(s.substr(colon + 1));
      if (at < 1 || at >= commits || !std::isfinite(pct) || pct <= -100) throw std::invalid_argument(s);
      out.emplace_back(at, pct);
    } catch (const std::exception&) {
      throw std::invalid_argument(fmt::format("--steps '{}': COMMIT:PCT with 1 <= COMMIT < --commits ({}) and PCT > -100", s, commits));
    }
  }
  std::sort(out.begin(), out.end());
  return out;
}

// Synthetic histories built from real runs: commit c of a point's history is a bootstrap resample of
// the samples of one real run of that point (drawn at random), so it carries that machine's real noise
// within and between runs; the steps multiply the samples from their commit on.
// Given paired comparisons (ab's --json: design paired, each point's pairs), commit c's value is
// instead the paired new/old ratio (ab's Hodges-Lehmann estimate) of a bootstrap resample of one real
// comparison's pairs, times the steps: the headline series new_over_old/POINT as CI's check stores it.
void evaluate(const HistoryOptions& o) {
  if (o.files.empty()) throw std::invalid_argument("history evaluate: give real runs' results files (--from)");
  const auto steps = parse_steps(o.steps, o.commits);
  const history::Metric metric = history::parse_metric(o.metric);
  using Pairs = std::vector<std::pair<double, double>>;  // (old, new) per pair
  std::map<std::string, std::vector<std::vector<double>>> runs_of_point;  // point -> each run's samples
  std::map<std::string, std::vector<Pairs>> pairs_of_point;               // point -> each comparison's pairs
  for (const auto& path : o.files) {
    const nlohmann::json doc = compare::load_results(path);
    if (doc.value("design", "") == "paired") {
      for (const auto& p : doc.value("points", nlohmann::json::array())) {
        if (!p.contains("paired_ms")) continue;
        const auto b = p["paired_ms"]["baseline"].get<std::vector<double>>(), c = p["paired_ms"]["current"].get<std::vector<double>>();
        Pairs pairs;
        for (std::size_t i = 0; i < std::min(b.size(), c.size()); ++i)
          if (b[i] > 0 && c[i] > 0) pairs.emplace_back(b[i], c[i]);
        if (pairs.size() >= 6) pairs_of_point[p.value("id", "?")].push_back(std::move(pairs));
      }
      continue;
    }
    for (const auto& p : history::points_of(doc)) {
      const auto& samples = metric == history::Metric::wall ? p.samples_ms : p.samples_cpu_ms;
      if (samples.size() >= 3) runs_of_point[p.point_id].push_back(samples);
    }
  }
  if (!runs_of_point.empty() && !pairs_of_point.empty())
    throw std::invalid_argument("history evaluate: give sweeps' results files or paired comparisons (ab --json), not both");
  const bool paired = !pairs_of_point.empty();
  if (paired)  // the same loop below draws from either
    for (const auto& [point, comparisons] : pairs_of_point) runs_of_point[point].resize(comparisons.size());
  if (runs_of_point.empty())
    throw std::runtime_error("history evaluate: no point with 3 samples (or 6 pairs) or more in the files given");
  std::mt19937_64 rng(o.seed);
  const auto options = change_point_options(o);
  struct Tally {
    int series = 0, false_points = 0, commits = 0;
    std::vector<int> exact, near;  // per step: found at its commit; within one commit
  };
  Tally with_steps{0, 0, 0, std::vector<int>(steps.size(), 0), std::vector<int>(steps.size(), 0)}, aa{};
  const auto start = std::chrono::steady_clock::now();
  for (int h = 0; h < o.histories; ++h)
    for (const auto& [point, runs] : runs_of_point)
      for (int kind = 0; kind < 2; ++kind) {  // 0: with the steps, 1: A/A
        Tally& t = kind == 0 ? with_steps : aa;
        std::vector<history::SeriesValue> values;
        for (int c = 0; c < o.commits; ++c) {
          const std::size_t drawn = std::uniform_int_distribution<std::size_t>(0, runs.size() - 1)(rng);
          const auto& run = runs[drawn];
          double factor = 1;
          if (kind == 0)
            for (const auto& [at, pct] : steps)
              if (c >= at) factor *= 1 + pct / 100;
          history::SeriesValue v;
          v.commit = fmt::format("c{:03d}", c);
          if (paired) {
            const Pairs& pairs = pairs_of_point.at(point)[drawn];
            std::vector<double> old_ms, new_ms;
            for (std::size_t i = 0; i < pairs.size(); ++i) {
              const auto& pair = pairs[std::uniform_int_distribution<std::size_t>(0, pairs.size() - 1)(rng)];
              old_ms.push_back(pair.first), new_ms.push_back(pair.second);
            }
            v.samples_ms = {compare::judge_paired(old_ms, new_ms, compare::Rule{}).ratio_of_medians * factor};
            v.samples_cpu_ms = v.samples_ms;
            values.push_back(std::move(v));
            continue;
          }
          for (std::size_t i = 0; i < run.size(); ++i)
            v.samples_ms.push_back(run[std::uniform_int_distribution<std::size_t>(0, run.size() - 1)(rng)] * factor);
          v.samples_cpu_ms = v.samples_ms;
          values.push_back(std::move(v));
        }
        const auto commits = history::over_commits(values, history::Metric::wall);
        std::vector<double> medians;
        for (const auto& c : commits) medians.push_back(c.median_ms);
        const auto found = history::e_divisive(medians, options);
        ++t.series;
        t.commits += o.commits;
        std::vector<bool> matched(found.size(), false);
        if (kind == 0)
          for (std::size_t s = 0; s < steps.size(); ++s) {
            for (std::size_t f = 0; f < found.size(); ++f)
              if (static_cast<int>(found[f].index) == steps[s].first) ++t.exact[s], matched[f] = true;
            for (std::size_t f = 0; f < found.size(); ++f)
              if (std::abs(static_cast<int>(found[f].index) - steps[s].first) <= 1) {
                ++t.near[s];
                matched[f] = true;
                break;
              }
          }
        for (bool m : matched) t.false_points += !m;
      }
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  fmt::print("synthetic histories from {} real {} file(s), {} points, {} commits each, {} histories a point "
             "(E-divisive means, p <= {}, {} permutations, {} commits a side; {}); {:.1f} s\n",
             o.files.size(), paired ? "paired comparison (ab)" : "run", runs_of_point.size(), o.commits, o.histories,
             o.max_p_value, o.permutations, o.min_segment,
             paired ? "each commit's paired new/old ratio" : o.metric + " metric", seconds);
  nlohmann::json step_json = nlohmann::json::array();
  for (std::size_t s = 0; s < steps.size(); ++s) {
    fmt::print("  step {:+.1f}% at commit {}: found at that commit in {} of {} series ({:.1f}%), within one commit in {} ({:.1f}%)\n",
               steps[s].second, steps[s].first, with_steps.exact[s], with_steps.series, 100.0 * with_steps.exact[s] / with_steps.series,
               with_steps.near[s], 100.0 * with_steps.near[s] / with_steps.series);
    step_json.push_back({{"commit", steps[s].first}, {"pct", steps[s].second}, {"series", with_steps.series},
                         {"found_at_commit", with_steps.exact[s]}, {"found_within_one", with_steps.near[s]}});
  }
  const double false_with = 100.0 * with_steps.false_points / with_steps.commits, false_aa = 100.0 * aa.false_points / aa.commits;
  fmt::print("  false change points per 100 commits: {:.2f} in the histories with steps, {:.2f} in A/A histories "
             "({} in {} A/A series)\n",
             false_with, false_aa, aa.false_points, aa.series);
  if (!o.json_out.empty()) {
    write_results(o.json_out, "bokehbench.history_evaluate", run_context(nullptr),
                  {{"files", o.files}, {"series_of", paired ? "paired new/old ratio (ab)" : "point medians"},
                   {"points", runs_of_point.size()}, {"commits", o.commits}, {"histories", o.histories},
                   {"metric", o.metric}, {"max_p_value", o.max_p_value}, {"permutations", o.permutations},
                   {"min_segment", o.min_segment}, {"seed", o.seed}, {"steps", step_json},
                   {"false_per_100_commits_with_steps", false_with}, {"false_per_100_commits_aa", false_aa},
                   {"aa_series", aa.series}, {"aa_false_change_points", aa.false_points}, {"elapsed_s", seconds}});
    fmt::print("wrote {}\n", o.json_out);
  }
}

// What the store costs: a real run appended --runs times (as commits c0000, ...), each append timed,
// by one writer or by --writers at once (each a connection of its own, as shards finishing together
// are); the store's size; then the HTML report over all of it, timed.
void cost(const HistoryOptions& o) {
  if (o.files.size() != 1) throw std::invalid_argument("history cost: give one real run's results file (--from)");
  const nlohmann::json doc = compare::load_results(o.files[0]);
  const history::RunRow run = history::run_of(doc, "history cost", o.files[0]);
  const auto points = history::points_of(doc);
  const auto headlines = history::headlines_of(doc);
  const bool sqlite = o.store.find("://") == std::string::npos;
  const std::string path = o.store.rfind("sqlite:", 0) == 0 ? o.store.substr(7) : o.store;
  if (sqlite && std::filesystem::exists(path))
    throw std::runtime_error(fmt::format("history cost: '{}' exists; give a new store (it is filled with synthetic runs)", o.store));
  auto store = Store::open(o.store, true);
  if (!store->runs().empty())
    throw std::runtime_error(fmt::format("history cost: '{}' already holds runs; give a new store (it is filled with "
                                         "synthetic runs)",
                                         o.store));
  const std::uint64_t empty_bytes = store->size_bytes();  // PostgreSQL's catalog, SQLite's empty tables
  const int writers = std::min(o.writers, o.runs);
  // Run i is commit c{i}: writer w appends runs w, w + writers, ... so that together they append each once.
  std::vector<std::vector<double>> append_ms(writers);
  std::vector<std::string> errors(writers);
  // Each writer's first append's start and last append's end: the elapsed time leaves out connecting.
  using Clock = std::chrono::steady_clock;
  std::vector<Clock::time_point> first_start(writers, Clock::time_point::max()), last_end(writers, Clock::time_point::min());
  std::atomic<int> ready{0};
  auto write = [&](int w) {
    bool counted = false;  // a writer that fails to connect still counts as ready: the others never wait forever
    try {
      std::unique_ptr<Store> own = writers == 1 ? nullptr : Store::open(o.store, true);  // its own connection
      Store& s = writers == 1 ? *store : *own;
      history::RunRow r = run;
      ++ready, counted = true;
      while (ready.load() < writers) std::this_thread::yield();  // every writer connected before any appends
      for (int i = w; i < o.runs; i += writers) {
        r.commit = fmt::format("c{:04d}", i);
        r.date_utc = fmt::format("2000-01-{:02d}T{:02d}:{:02d}:00Z", 1 + i / 1440, i / 60 % 24, i % 60);
        const auto t0 = Clock::now();
        s.append(r, points, headlines);
        const auto t1 = Clock::now();
        append_ms[w].push_back(std::chrono::duration<double, std::milli>(t1 - t0).count());
        first_start[w] = std::min(first_start[w], t0), last_end[w] = t1;
      }
    } catch (const std::exception& e) {
      if (!counted) ++ready;
      errors[w] = e.what();
    }
  };
  if (writers == 1) {
    write(0);
  } else {
    std::vector<std::thread> threads;
    for (int w = 0; w < writers; ++w) threads.emplace_back(write, w);
    for (auto& t : threads) t.join();
  }
  for (int w = 0; w < writers; ++w)
    if (!errors[w].empty()) throw std::runtime_error(fmt::format("history cost: writer {} of {}: {}", w + 1, writers, errors[w]));
  std::vector<double> all_ms;
  for (const auto& v : append_ms) all_ms.insert(all_ms.end(), v.begin(), v.end());
  std::sort(all_ms.begin(), all_ms.end());
  fmt::print("{} runs of {} points ({} samples in the first) appended to {} ({}): write per run median {:.2f} ms, "
             "90th percentile {:.2f} ms\n",
             o.runs, points.size(), doc["points"].empty() ? 0 : doc["points"][0]["samples_ms"].size(), o.store, store->kind(),
             all_ms[all_ms.size() / 2], all_ms[all_ms.size() * 9 / 10]);
  if (writers > 1) {
    // What the writers' load costs the store: its time per run (elapsed over runs, all writers together),
    // and whether every run is there once (commit c{i} for every i, no other).
    const double wall_ms = std::chrono::duration<double, std::milli>(*std::max_element(last_end.begin(), last_end.end()) -
                                                                      *std::min_element(first_start.begin(), first_start.end()))
                               .count();
    std::set<std::string> commits;
    std::size_t stored = 0;
    for (const auto& r : store->runs()) commits.insert(r.commit), ++stored;
    const bool every_run_once = stored == static_cast<std::size_t>(o.runs) && commits.size() == stored &&
                                commits.count("c0000") && commits.count(fmt::format("c{:04d}", o.runs - 1));
    fmt::print("{} writers at once: {:.2f} ms a run (elapsed {:.2f} s over {} runs); the store holds {} runs, {} distinct "
               "commits: {}\n",
               writers, wall_ms / o.runs, wall_ms / 1000, o.runs, stored, commits.size(),
               every_run_once ? "every run once" : "RUNS LOST OR DUPLICATED");
    if (!every_run_once) throw std::runtime_error("history cost: the store lost or duplicated runs under concurrent writers");
  }
  store.reset();  // the last connection closing checkpoints SQLite's write-ahead log into the file
  store = Store::open(o.store, false);
  const std::uint64_t bytes = store->size_bytes();
  const double grown_mib = (static_cast<double>(bytes) - static_cast<double>(empty_bytes)) / 1048576.0;
  fmt::print("store size: {:.1f} MiB ({:.1f} MiB empty); the runs added {:.1f} MiB per 1,000 runs{}\n", bytes / 1048576.0,
             empty_bytes / 1048576.0, grown_mib * 1000 / o.runs, sqlite ? "" : " (pg_database_size)");
  const auto t0 = std::chrono::steady_clock::now();
  history::HtmlReportInput in;
  in.store_url = o.store;
  in.change_points = change_point_options(o);
  in.runs = store->runs();
  in.series = history::series(*store, "", history::Metric::wall, in.change_points);
  const std::string html = history::html_report(in);
  if (!o.out_html.empty()) write_text_atomically(o.out_html, html);
  fmt::print("report over {} runs ({} series): {:.2f} s, {:.1f} MiB of HTML\n", in.runs.size(), in.series.size(),
             std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(), html.size() / 1048576.0);
}

}  // namespace

void add_history_command(CLI::App& app) {
  auto o = std::make_shared<HistoryOptions>();
  auto* cmd = app.add_subcommand("history", "The results store: runs, series over commits, change points, import");
  cmd->require_subcommand(1);

  auto* list = cmd->add_subcommand("list", "The runs in the store, oldest first");
  add_store_option(list, *o);
  list->add_flag("--points", o->list_points, "Under each run, the points it measured (and a shard's scheduler job): "
                                             "which task measured which point");
  list->callback([o] { list_runs(*o); });

  auto* series = cmd->add_subcommand("series", "One point's series over commits, one per machine, with its change points");
  add_store_option(series, *o);
  series->add_option("--point", o->point, "The point's id (as in the results files), or a headline figure's name "
                                          "(naive_over_flag/gpu/N:9, new_over_old/POINT, ...; history changes lists them)")
      ->required();
  add_change_point_options(series, *o);
  series->callback([o] { print_series(*o); });

  auto* changes = cmd->add_subcommand("changes", "The change points of every series (or one point's), the commit where "
                                                 "each step happened, its size and p-value");
  add_store_option(changes, *o);
  changes->add_option("--point", o->point, "Only this point (or headline figure)");
  changes->add_option("--sweep", o->sweep, "Only this sweep's points (figure9, tradeoff, ...)");
  changes->add_option("--json", o->json_out, "Also write them as JSON here");
  add_change_point_options(changes, *o);
  changes->callback([o] { print_changes(*o); });

  auto* import = cmd->add_subcommand("import", "Append existing results files (sweeps' JSON) to the store; a run "
                                               "already there (same sweep, commit, date, machine) is skipped");
  add_store_option(import, *o);
  import->add_option("files", o->files, "Results files (results/figure9.json, ...)")->required()->check(CLI::ExistingFile);
  import->callback([o] { import_files(*o); });

  auto* evaluate_cmd = cmd->add_subcommand(
      "evaluate", "Change-point detection on synthetic histories resampled from real runs, with steps injected at "
                  "known commits and A/A histories: how often each step is found at its commit, false change points "
                  "per 100 commits");
  evaluate_cmd->add_option("--from", o->files, "Real runs' results files (the same sweep), or paired comparisons (ab "
                                               "--json): then each commit is a paired new/old ratio")->required()->check(CLI::ExistingFile);
  evaluate_cmd->add_option("--commits", o->commits, "Commits a history")->check(CLI::Range(8, 10000))->capture_default_str();
  evaluate_cmd->add_option("--histories", o->histories, "Histories a point, of each kind")->check(CLI::Range(1, 100000))->capture_default_str();
  evaluate_cmd->add_option("--steps", o->steps, "Steps injected, COMMIT:PCT each (0-based commit: the first after the step)")
      ->capture_default_str();
  evaluate_cmd->add_option("--seed", o->seed, "Seed of the resampling and the permutations")->capture_default_str();
  evaluate_cmd->add_option("--json", o->json_out, "Also write the rates as JSON here");
  add_change_point_options(evaluate_cmd, *o);
  evaluate_cmd->callback([o] { evaluate(*o); });

  auto* cost_cmd = cmd->add_subcommand("cost", "What the store costs: one real run appended --runs times to a new store "
                                               "(write time per run, size), then the HTML report over all of it (time)");
  cost_cmd->add_option("--from", o->files, "One real run's results file")->required()->check(CLI::ExistingFile);
  cost_cmd->add_option("--store", o->store, "A new store (file or postgresql:// URL) to fill")->required();
  cost_cmd->add_option("--runs", o->runs, "Runs to append")->check(CLI::Range(1, 1000000))->capture_default_str();
  cost_cmd->add_option("--writers", o->writers,
                       "Writers appending at once, each a connection (thread) of its own, as shards finishing together: "
                       "also prints the time per run under that load (elapsed / runs) and checks every run is stored once")
      ->check(CLI::Range(1, 64))
      ->capture_default_str();
  cost_cmd->add_option("--html", o->out_html, "Also write the report here");
  cost_cmd->callback([o] { cost(*o); });
}

void add_merge_command(CLI::App& app) {
  auto o = std::make_shared<HistoryOptions>();
  auto* cmd = app.add_subcommand("merge", "Join the results files of a sweep's shards (--shard i/n runs, from one "
                                          "machine or many) into one results file that compare reads");
  cmd->add_option("shards", o->files, "Every shard's results file (e.g. shard1/figure9.json ...)")->required()->check(CLI::ExistingFile);
  cmd->add_option("--out", o->json_out, "The merged results file")->required();
  cmd->callback([o] { merge_files(*o); });
}

}  // namespace bokeh
