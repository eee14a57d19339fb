#include "history.hpp"

#include <algorithm>
#include <map>
#include <stdexcept>

namespace bokeh::history {

namespace {
double quantile_of(std::vector<double> v, double q) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  const double pos = q * static_cast<double>(v.size() - 1);
  const std::size_t lo = static_cast<std::size_t>(pos);
  const std::size_t hi = std::min(lo + 1, v.size() - 1);
  return v[lo] + (pos - static_cast<double>(lo)) * (v[hi] - v[lo]);
}
}  // namespace

Metric parse_metric(const std::string& text) {
  if (text == "wall") return Metric::wall;
  if (text == "cpu") return Metric::cpu;
  throw std::invalid_argument("--metric '" + text + "': wall (frame_ms) or cpu (process CPU time per frame)");
}

const char* metric_name(Metric metric) { return metric == Metric::wall ? "wall ms per frame" : "CPU ms per frame"; }

namespace {
// What a value of a series is: the harness's commit, and the package's version where the point is a
// package's (an edit of the package at the same commit is a value of its own).
std::string version_of(const std::string& commit, const std::string& package) { return commit + '\n' + package; }
std::string version_of(const SeriesValue& r) { return version_of(r.commit, r.package); }
}  // namespace

std::vector<CommitValue> over_commits(const std::vector<SeriesValue>& runs, Metric metric) {
  std::vector<CommitValue> out;
  std::vector<std::vector<double>> pooled;
  std::map<std::string, std::size_t> index;
  for (const auto& r : runs) {
    const auto& samples = metric == Metric::wall ? r.samples_ms : r.samples_cpu_ms;
    if (samples.empty()) continue;
    auto [it, added] = index.emplace(version_of(r), out.size());
    if (added) {
      out.push_back({r.commit, r.date_utc, r.package});
      pooled.emplace_back();
    }
    CommitValue& c = out[it->second];
    ++c.runs;
    pooled[it->second].insert(pooled[it->second].end(), samples.begin(), samples.end());
  }
  for (std::size_t i = 0; i < out.size(); ++i) {
    out[i].median_ms = quantile_of(pooled[i], 0.5);
    out[i].q1_ms = quantile_of(pooled[i], 0.25);
    out[i].q3_ms = quantile_of(pooled[i], 0.75);
    out[i].samples = static_cast<int>(pooled[i].size());
  }
  // Headline figures: the interval each run gave, where every run of the commit gave one.
  std::map<std::string, std::pair<std::vector<double>, std::vector<double>>> ends;
  std::map<std::string, bool> all_have;
  for (const auto& r : runs) {
    auto [it, added] = all_have.emplace(version_of(r), true);
    it->second = it->second && r.has_interval;
    ends[version_of(r)].first.push_back(r.q1_ms), ends[version_of(r)].second.push_back(r.q3_ms);
  }
  for (auto& c : out) {
    const std::string key = version_of(c.commit, c.package);
    if (all_have[key]) {
      c.has_interval = true;
      c.q1_ms = quantile_of(ends[key].first, 0.5);
      c.q3_ms = quantile_of(ends[key].second, 0.5);
    }
  }
  return out;
}

std::vector<Series> series(Store& store, const std::string& point_id, Metric metric, const ChangePointOptions& options) {
  struct Wanted {
    std::string id, sweep, unit;
    bool headline;
  };
  std::vector<Wanted> ids;
  for (const auto& [id, sweep] : store.point_ids())
    if (point_id.empty() || id == point_id) ids.push_back({id, sweep, "ms", false});
  for (const auto& [key, unit] : store.headline_names())
    if (point_id.empty() || key.first == point_id) ids.push_back({key.first, key.second, unit, true});
  if (!point_id.empty() && ids.empty())
    throw std::runtime_error("no point or headline figure '" + point_id + "' in the store " + store.url());
  std::vector<Series> out;
  for (const auto& w : ids) {
    std::map<std::string, std::vector<SeriesValue>> by_machine;
    for (auto& v : w.headline ? store.headline_series(w.id) : store.series(w.id))
      if (v.sweep == w.sweep) by_machine[v.machine].push_back(std::move(v));  // another sweep's is another design
    for (const auto& [machine, runs] : by_machine) {
      Series s{w.id, w.sweep, machine, w.unit, w.headline, over_commits(runs, w.headline ? Metric::wall : metric), {}};
      if (s.values.empty()) continue;
      std::vector<double> medians;
      for (const auto& v : s.values) medians.push_back(v.median_ms);
      if (std::all_of(medians.begin(), medians.end(), [](double m) { return m > 0; }))
        for (const auto& c : e_divisive(medians, options))
          s.steps.push_back({s.values[c.index].commit, s.values[c.index - 1].commit, c.index, c.ratio, c.p_value});
      out.push_back(std::move(s));
    }
  }
  return out;
}

}  // namespace bokeh::history
