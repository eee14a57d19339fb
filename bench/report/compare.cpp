#include "compare.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <stdexcept>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "report.hpp"
#include "text_file.hpp"

namespace bokeh::compare {

using json = nlohmann::json;

// ---- The statistic ----

std::vector<double> mann_whitney_counts(int m, int n) {
  if (m < 0 || n < 0) throw std::invalid_argument("mann_whitney_counts: negative size");
  if (m > kExactMaxSamples && n > kExactMaxSamples)
    throw std::invalid_argument("mann_whitney_counts: both sizes over kExactMaxSamples (use the normal approximation)");
  // The counts are the coefficients of the Gaussian binomial [m + n choose m]_q (the same polynomial
  // as [m + n choose n]_q), built one factor (1 - q^(n+i)) / (1 - q^i) at a time over the smaller
  // size. The cancellations grow with the number of factors: at 50 the relative error is ~1e-16
  // (checked against exact integers), at 80 ~1e-12, at 150 the result is wrong.
  if (m > n) std::swap(m, n);
  std::vector<double> c = {1.0};
  for (int i = 1; i <= m; ++i) {
    std::vector<double> next(c.size() + static_cast<std::size_t>(n + i), 0.0);
    for (std::size_t k = 0; k < c.size(); ++k) {
      next[k] += c[k];
      next[k + static_cast<std::size_t>(n + i)] -= c[k];
    }
    for (std::size_t k = static_cast<std::size_t>(i); k < next.size(); ++k) next[k] += next[k - static_cast<std::size_t>(i)];
    next.resize(static_cast<std::size_t>(i) * static_cast<std::size_t>(n) + 1);
    for (double& v : next) v = std::max(0.0, v);  // rounding must not leave a tiny negative
    c = std::move(next);
  }
  return c;
}

namespace {

// The largest c with P(statistic <= c) <= (1 - confidence) / 2 under the null whose counts (one per
// value of the statistic, from 0) are given, or -1 when even the smallest value is more likely.
int lower_critical(const std::vector<double>& counts, double confidence) {
  double total = 0;
  for (double v : counts) total += v;
  const double tail = (1 - confidence) / 2;
  double cumulative = 0;
  int critical = -1;
  for (std::size_t u = 0; u < counts.size(); ++u) {
    cumulative += counts[u];
    if (cumulative / total > tail * (1 + 1e-12)) break;
    critical = static_cast<int>(u);
  }
  return critical;
}

}  // namespace

int mann_whitney_critical_normal(int m, int n, double confidence) {
  // P(U <= c) ~ Phi((c + 0.5 - m n / 2) / sd), sd^2 = m n (m + n + 1) / 12.
  const double tail = (1 - confidence) / 2;
  const double mean = 0.5 * m * n, sd = std::sqrt(m * n * (m + n + 1.0) / 12.0);
  const auto p = [&](int c) { return 0.5 * std::erfc(-(c + 0.5 - mean) / (sd * std::sqrt(2.0))); };
  int lo = -1, hi = static_cast<int>(mean);  // p(lo) <= tail (or lo = -1), p(hi) > tail
  while (hi - lo > 1) {
    const int mid = (lo + hi) / 2;
    (p(mid) <= tail ? lo : hi) = mid;
  }
  return lo;
}

int mann_whitney_critical(int m, int n, double confidence) {
  if (!(confidence > 0 && confidence < 1)) throw std::invalid_argument("confidence must be in (0, 1)");
  if (m < 1 || n < 1) return -1;
  if (std::min(m, n) > kExactMaxSamples) return mann_whitney_critical_normal(m, n, confidence);
  return lower_critical(mann_whitney_counts(m, n), confidence);
}

int min_samples_for_interval(double confidence) {
  for (int n = 1; n < 1000; ++n)
    if (mann_whitney_critical(n, n, confidence) >= 0) return n;
  throw std::invalid_argument("no sample size gives an interval at that confidence");
}

RatioInterval ratio_interval(const std::vector<double>& baseline, const std::vector<double>& current,
                             double confidence) {
  RatioInterval out;
  const int m = static_cast<int>(baseline.size()), n = static_cast<int>(current.size());
  const int c = mann_whitney_critical(m, n, confidence);
  if (c < 0) return out;
  std::vector<double> ratios;
  ratios.reserve(baseline.size() * current.size());
  for (double b : baseline)
    for (double x : current) ratios.push_back(x / b);
  std::sort(ratios.begin(), ratios.end());
  out.exists = true;
  out.low = ratios[static_cast<std::size_t>(c)];
  out.high = ratios[ratios.size() - 1 - static_cast<std::size_t>(c)];
  if (std::min(m, n) <= kExactMaxSamples) {
    const std::vector<double> counts = mann_whitney_counts(m, n);
    double total = 0, tail = 0;
    for (double v : counts) total += v;
    for (int u = 0; u <= c; ++u) tail += counts[static_cast<std::size_t>(u)];
    out.coverage = 1 - 2 * tail / total;
  } else {
    out.coverage = confidence;
  }
  return out;
}

std::string to_string(Verdict v) {
  switch (v) {
    case Verdict::same: return "same";
    case Verdict::faster: return "faster";
    case Verdict::slower: return "slower";
    case Verdict::inconclusive: return "inconclusive";
  }
  return "?";
}

namespace {

double median(std::vector<double> v) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  const std::size_t h = v.size() / 2;
  return v.size() % 2 ? v[h] : 0.5 * (v[h - 1] + v[h]);
}

// The verdict from j.interval: beyond the threshold either way, within it, or neither.
void set_verdict(Judgement& j, const Rule& rule) {
  const double up = 1 + rule.threshold, down = 1 / up;
  if (j.interval.low > up)
    j.verdict = Verdict::slower;
  else if (j.interval.high < down)
    j.verdict = Verdict::faster;
  else if (j.interval.low >= down && j.interval.high <= up)
    j.verdict = Verdict::same;
  else
    j.why = fmt::format("the interval reaches past {:+.0f}%", 100 * (j.interval.high > up ? rule.threshold : down - 1));
}

}  // namespace

Judgement judge(const std::vector<double>& baseline, const std::vector<double>& current, const Rule& rule) {
  Judgement j;
  const auto positive = [](const std::vector<double>& v) {
    return std::all_of(v.begin(), v.end(), [](double x) { return std::isfinite(x) && x > 0; });
  };
  if (!positive(baseline) || !positive(current)) {
    j.why = "a sample is not a positive time";
    return j;
  }
  if (!baseline.empty() && !current.empty()) j.ratio_of_medians = median(current) / median(baseline);
  const int fewest = static_cast<int>(std::min(baseline.size(), current.size()));
  if (fewest < rule.min_samples) {
    j.why = fmt::format("{} and {} samples, fewer than {}", baseline.size(), current.size(), rule.min_samples);
    return j;
  }
  j.interval = ratio_interval(baseline, current, rule.confidence);
  if (!j.interval.exists) {
    j.why = fmt::format("too few samples ({} and {}) for a {:g}% interval", baseline.size(), current.size(),
                        100 * rule.confidence);
    return j;
  }
  set_verdict(j, rule);
  return j;
}

std::vector<double> signed_rank_counts(int n) {
  if (n < 0) throw std::invalid_argument("signed_rank_counts: negative size");
  // Subset sums of {1 .. n}, one element at a time (counts up to 2^n: exact in doubles to n = 53,
  // relative error ~1e-16 beyond, far below what the tail sums need).
  std::vector<double> c(static_cast<std::size_t>(n) * (n + 1) / 2 + 1, 0.0);
  c[0] = 1;
  for (int k = 1; k <= n; ++k)
    for (std::size_t s = static_cast<std::size_t>(k) * (k + 1) / 2; s >= static_cast<std::size_t>(k); --s)
      c[s] += c[s - static_cast<std::size_t>(k)];
  return c;
}

int signed_rank_critical(int n, double confidence) {
  if (!(confidence > 0 && confidence < 1)) throw std::invalid_argument("confidence must be in (0, 1)");
  if (n < 1) return -1;
  return lower_critical(signed_rank_counts(n), confidence);
}

namespace {

// The Walsh averages of the paired log-ratios, sorted.
std::vector<double> walsh_averages(const std::vector<double>& baseline, const std::vector<double>& current) {
  if (baseline.size() != current.size()) throw std::invalid_argument("paired samples of different lengths");
  std::vector<double> d;
  for (std::size_t r = 0; r < baseline.size(); ++r) d.push_back(std::log(current[r] / baseline[r]));
  std::vector<double> w;
  for (std::size_t i = 0; i < d.size(); ++i)
    for (std::size_t j = i; j < d.size(); ++j) w.push_back(0.5 * (d[i] + d[j]));
  std::sort(w.begin(), w.end());
  return w;
}

}  // namespace

RatioInterval paired_ratio_interval(const std::vector<double>& baseline, const std::vector<double>& current,
                                    double confidence) {
  RatioInterval out;
  const int n = static_cast<int>(baseline.size());
  const int c = signed_rank_critical(n, confidence);
  if (c < 0) return out;
  const std::vector<double> w = walsh_averages(baseline, current);
  out.exists = true;
  out.low = std::exp(w[static_cast<std::size_t>(c)]);
  out.high = std::exp(w[w.size() - 1 - static_cast<std::size_t>(c)]);
  const std::vector<double> counts = signed_rank_counts(n);
  double tail = 0;
  for (int t = 0; t <= c; ++t) tail += counts[static_cast<std::size_t>(t)];
  out.coverage = 1 - 2 * tail / std::ldexp(1.0, n);
  return out;
}

Judgement judge_paired(const std::vector<double>& baseline, const std::vector<double>& current, const Rule& rule) {
  Judgement j;
  if (baseline.size() != current.size()) throw std::invalid_argument("paired samples of different lengths");
  const auto positive = [](const std::vector<double>& v) {
    return std::all_of(v.begin(), v.end(), [](double x) { return std::isfinite(x) && x > 0; });
  };
  if (!positive(baseline) || !positive(current)) {
    j.why = "a sample is not a positive time";
    return j;
  }
  if (!baseline.empty()) j.ratio_of_medians = std::exp(median(walsh_averages(baseline, current)));
  if (static_cast<int>(baseline.size()) < rule.min_samples) {
    j.why = fmt::format("{} pairs, fewer than {}", baseline.size(), rule.min_samples);
    return j;
  }
  j.interval = paired_ratio_interval(baseline, current, rule.confidence);
  if (!j.interval.exists) {
    j.why = fmt::format("too few pairs ({}) for a {:g}% interval", baseline.size(), 100 * rule.confidence);
    return j;
  }
  set_verdict(j, rule);
  return j;
}

// ---- Files ----

namespace {

// A results file with its path, so that every error names both the file and the key.
struct File {
  const json& doc;
  std::string path;

  [[noreturn]] void fail(const std::string& what) const { throw std::runtime_error(path + ": " + what); }

  const json& get(const json& obj, const std::string& key, const std::string& where, json::value_t type) const {
    if (!obj.is_object()) fail(fmt::format("{} is not an object", where.empty() ? "the document" : where));
    const std::string at = where.empty() ? fmt::format("'{}'", key) : fmt::format("{}: '{}'", where, key);
    const auto it = obj.find(key);
    if (it == obj.end()) fail(at + " is missing");
    const bool ok = type == json::value_t::number_float ? it->is_number()
                    : type == json::value_t::number_integer ? it->is_number_integer()
                                                            : it->type() == type;
    if (!ok) fail(fmt::format("{} is not {} (it is {})", at, type_name(type), it->type_name()));
    return *it;
  }
  static const char* type_name(json::value_t t) {
    switch (t) {
      case json::value_t::object: return "an object";
      case json::value_t::array: return "an array";
      case json::value_t::string: return "a string";
      case json::value_t::number_integer: return "an integer";
      case json::value_t::number_float: return "a number";
      case json::value_t::boolean: return "a boolean";
      default: return "of the expected type";
    }
  }
  std::vector<double> numbers(const json& obj, const std::string& key, const std::string& where) const {
    const json& a = get(obj, key, where, json::value_t::array);
    std::vector<double> out;
    for (std::size_t i = 0; i < a.size(); ++i) {
      if (!a[i].is_number()) fail(fmt::format("{}: '{}[{}]' is not a number", where, key, i));
      out.push_back(a[i].get<double>());
    }
    return out;
  }
};

struct Measured {
  const json* point = nullptr;  // null: skipped
  std::string method, skipped_reason;
};

// id -> measured point or skip reason; also checks each entry's id.
std::map<std::string, Measured> points_of(const File& f) {
  std::map<std::string, Measured> out;
  const json& points = f.get(f.doc, "points", "", json::value_t::array);
  for (std::size_t i = 0; i < points.size(); ++i) {
    const std::string where = fmt::format("points[{}]", i);
    const std::string id = f.get(points[i], "id", where, json::value_t::string).get<std::string>();
    if (out.count(id)) f.fail(fmt::format("point '{}' appears twice", id));
    out[id].point = &points[i];
    out[id].method = f.get(points[i], "method", where, json::value_t::string).get<std::string>();
  }
  const json& skipped = f.get(f.doc, "skipped", "", json::value_t::array);
  for (std::size_t i = 0; i < skipped.size(); ++i) {
    const std::string where = fmt::format("skipped[{}]", i);
    const std::string id = f.get(skipped[i], "id", where, json::value_t::string).get<std::string>();
    if (out.count(id)) f.fail(fmt::format("point '{}' appears twice", id));
    out[id].skipped_reason = f.get(skipped[i], "reason", where, json::value_t::string).get<std::string>();
    out[id].method = f.get(skipped[i], "method", where, json::value_t::string).get<std::string>();
  }
  return out;
}

// The probes that normalise a point on `backend`, per the --normalise option.
std::vector<std::string> probes_for(const std::string& normalise, const std::string& backend) {
  if (normalise == "none") return {};
  if (normalise == "auto") return {backend + "_copy", backend + "_fma"};
  std::vector<std::string> names;
  std::stringstream ss(normalise);
  for (std::string name; std::getline(ss, name, ',');)
    if (!name.empty()) names.push_back(name);
  return names;
}

// Per round, the geometric mean of the probes' times (wall or CPU) per unit of their work (bytes
// plus flops, when recorded: a probe's work may differ between runs, e.g. with the thread count).
std::vector<double> probe_per_round(const File& f, const std::vector<std::string>& probes, const std::string& clock) {
  const json& measurement = f.get(f.doc, "measurement", "", json::value_t::object);
  const json& all = f.get(measurement, "probes", "measurement", json::value_t::object);
  const std::string key = clock == "cpu" ? "cpu_ms_per_round" : "ms_per_round";
  std::vector<double> out;
  for (const auto& name : probes) {
    if (!all.contains(name)) {
      std::vector<std::string> present;
      for (const auto& item : all.items()) present.push_back(item.key());
      f.fail(fmt::format("normalising needs probe '{}' timed every round, which measurement.probes lacks (it has: {}); "
                         "compare with --normalise none for raw times",
                         name, present.empty() ? "none" : fmt::format("{}", fmt::join(present, ", "))));
    }
    const json& probe = f.get(all, name, "measurement.probes", json::value_t::object);
    const std::vector<double> ms = f.numbers(probe, key, "measurement.probes." + name);
    const double work = probe.value("bytes", 0.0) + probe.value("flops", 0.0);
    if (out.empty()) out.assign(ms.size(), 1.0);
    if (ms.size() != out.size()) f.fail("the probes were timed in different numbers of rounds");
    for (std::size_t r = 0; r < ms.size(); ++r) {
      if (!(ms[r] > 0) || !std::isfinite(ms[r]))
        f.fail(fmt::format("measurement.probes.{}.{}[{}] is not a positive time", name, key, r));
      out[r] *= std::pow(work > 0 ? ms[r] / work : ms[r], 1.0 / static_cast<double>(probes.size()));
    }
  }
  return out;
}

const char* samples_key(const std::string& clock) { return clock == "cpu" ? "samples_cpu_ms" : "samples_ms"; }

struct Series {
  std::vector<double> raw, normalised;
};

Series series_of(const File& f, const json& point, const std::vector<std::string>& probes, const std::string& clock,
                 std::map<std::string, std::vector<double>>& probe_cache) {
  const std::string where = "point '" + point["id"].get<std::string>() + "'";
  const std::string key = samples_key(clock);
  Series s;
  s.raw = f.numbers(point, key, where);
  for (std::size_t i = 0; i < s.raw.size(); ++i)
    if (!(s.raw[i] > 0) || !std::isfinite(s.raw[i]))
      f.fail(fmt::format("{}: {}[{}] is not a positive time", where, key, i));
  if (probes.empty()) {
    s.normalised = s.raw;
    return s;
  }
  const std::string cache_key = fmt::format("{}:{}", clock, fmt::join(probes, "*"));
  if (!probe_cache.count(cache_key)) probe_cache[cache_key] = probe_per_round(f, probes, clock);
  const std::vector<double>& per_round = probe_cache[cache_key];
  const std::vector<double> rounds = f.numbers(point, "sample_rounds", where);
  if (rounds.size() != s.raw.size())
    f.fail(fmt::format("{}: {} {} but {} sample_rounds", where, s.raw.size(), key, rounds.size()));
  for (std::size_t i = 0; i < rounds.size(); ++i) {
    const double r = rounds[i];
    if (r < 0 || r != std::floor(r) || r >= static_cast<double>(per_round.size()))
      f.fail(fmt::format("{}: sample_rounds[{}] = {} is not one of the {} rounds the probes were timed in", where, i, r,
                         per_round.size()));
    s.normalised.push_back(s.raw[i] / per_round[static_cast<std::size_t>(r)]);
  }
  return s;
}

// Ratio of medians of a raw series present in both points (0 when either lacks it).
double raw_ratio(const json& base, const json& cur, const char* key) {
  auto values = [&](const json& p) {
    std::vector<double> v;
    if (p.contains(key) && p[key].is_array())
      for (const auto& x : p[key])
        if (x.is_number()) v.push_back(x.get<double>());
    return v;
  };
  const double b = median(values(base)), c = median(values(cur));
  return b > 0 && c > 0 ? c / b : 0;
}

std::string short_json(const json& v) {
  std::string text = v.dump();
  return text.size() > 60 ? text.substr(0, 57) + "..." : text;
}

std::string text_or(const json& obj, const char* key, const char* fallback = "?") {
  if (obj.is_object() && obj.contains(key)) return obj[key].is_string() ? obj[key].get<std::string>() : obj[key].dump();
  return fallback;
}

template <class Set>
std::string listed(const Set& items, std::size_t most = 8) {
  std::vector<std::string> shown;
  for (const auto& x : items) {
    if (shown.size() == most) {
      shown.push_back(fmt::format("... ({} more)", items.size() - most));
      break;
    }
    shown.push_back(x);
  }
  return fmt::format("{}", fmt::join(shown, ", "));
}

}  // namespace

// The RFC 6902 patch of nlohmann::json::diff, one line a leaf.
std::vector<std::string> json_differences(const json& baseline, const json& current) {
  std::vector<std::string> out;
  for (const auto& op : json::diff(baseline, current)) {
    std::string path = op["path"].get<std::string>();
    const json::json_pointer pointer(path);
    std::replace(path.begin(), path.end(), '/', '.');
    if (!path.empty() && path[0] == '.') path.erase(0, 1);
    if (path.empty()) path = "work";
    const std::string kind = op["op"].get<std::string>();
    if (kind == "replace")
      out.push_back(fmt::format("{}: {} -> {}", path, short_json(baseline.at(pointer)), short_json(op["value"])));
    else if (kind == "add")
      out.push_back(fmt::format("{}: added ({})", path, short_json(op["value"])));
    else if (kind == "remove")
      out.push_back(fmt::format("{}: removed (was {})", path, short_json(baseline.at(pointer))));
    else
      out.push_back(fmt::format("{}: {}", path, kind));
  }
  return out;
}

json load_results(const std::string& path) {
  const std::string text = read_text_file(path, "results file");
  json doc;
  try {
    doc = json::parse(text);
  } catch (const json::parse_error& e) {
    throw std::runtime_error(fmt::format("{}: not valid JSON ({})", path, e.what()));
  }
  if (!doc.is_object()) throw std::runtime_error(path + ": not a bokehbench results file (not a JSON object)");
  if (!doc.contains("schema")) {
    if (doc.contains("benchmarks"))
      throw std::runtime_error(path + ": a Google Benchmark file; compare reads the bokehbench results file beside it "
                                      "(results/<name>.json, not <name>_gbench.json)");
    throw std::runtime_error(path + ": not a bokehbench results file (no 'schema' key)");
  }
  return doc;
}

int Report::count(Verdict v) const {
  return static_cast<int>(std::count_if(points.begin(), points.end(), [&](const PointComparison& p) {
    return p.judgement.verdict == v;
  }));
}

bool Report::work_changed() const {
  return std::any_of(points.begin(), points.end(), [](const PointComparison& p) { return !p.work_changes.empty(); });
}

int Report::exit_code() const {
  if (!mismatches.empty()) return kNotComparable;
  if (count(Verdict::slower) > 0 && machine_differences.empty()) return kRegression;
  if (work_changed()) return kWorkChanged;
  return kNoRegression;
}

namespace {

// Both files of the same results schema, in the version this reads (else mismatches).
void check_schemas(const File& base, const File& cur, Report& report) {
  // What kind of file: both the same results schema, in the version this reads.
  const std::string base_schema = base.get(base.doc, "schema", "", json::value_t::string).get<std::string>();
  const std::string cur_schema = cur.get(cur.doc, "schema", "", json::value_t::string).get<std::string>();
  if (base_schema != cur_schema)
    report.mismatches.push_back(fmt::format("schema: baseline '{}', current '{}'", base_schema, cur_schema));
  const json& base_version = base.get(base.doc, "schema_version", "", json::value_t::number_integer);
  const json& cur_version = cur.get(cur.doc, "schema_version", "", json::value_t::number_integer);
  if (base_version != 2 || cur_version != 2)
    report.mismatches.push_back(fmt::format("schema_version: baseline {}, current {} (compare reads version 2: samples "
                                            "per round with the calibration probes)",
                                            base_version.dump(), cur_version.dump()));
}

// The machines, commits, statuses and configurations of the two files: information, never a verdict.
void note_machines(const File& base, const File& cur, Report& report) {
  // The device: timings of two devices are not a regression.
  const json& base_ctx = base.get(base.doc, "context", "", json::value_t::object);
  const json& cur_ctx = cur.get(cur.doc, "context", "", json::value_t::object);
  const json base_dev = base_ctx.value("device", json(nullptr)), cur_dev = cur_ctx.value("device", json(nullptr));
  // The machine: timings from two machines (or devices) say more about the machines than about the
  // code, so they are information, never a verdict (Report::machine_differences).
  auto& machine = report.machine_differences;
  if (base_dev.is_null() != cur_dev.is_null()) {
    machine.push_back(fmt::format("device: baseline {}, current {}", base_dev.is_null() ? "none" : text_or(base_dev, "name"),
                                  cur_dev.is_null() ? "none" : text_or(cur_dev, "name")));
  } else if (!base_dev.is_null()) {
    for (const char* key : {"name", "type", "vendor_id", "device_id", "driver_info"})
      if (base_dev.value(key, json()) != cur_dev.value(key, json()))
        machine.push_back(fmt::format("device {}: baseline {}, current {}", key, text_or(base_dev, key), text_or(cur_dev, key)));
  }
  for (const char* key : {"cpu_model", "cpu_cores", "lp_num_threads"})
    if (base_ctx.value(key, json()) != cur_ctx.value(key, json()))
      machine.push_back(fmt::format("{}: baseline {}, current {}", key, text_or(base_ctx, key), text_or(cur_ctx, key)));
  // A file merged from shards measured on several machines (bokehbench merge) mixes machines within itself.
  for (const auto& [which, ctx] : {std::pair<const char*, const json*>{"baseline", &base_ctx}, {"current", &cur_ctx}})
    if (ctx->contains("shard_machines") && (*ctx)["shard_machines"].size() > 1)
      machine.push_back(fmt::format("{}: merged from shards measured on {} machines ({})", which,
                                    (*ctx)["shard_machines"].size(), (*ctx)["shard_machines"].dump()));
  report.notes.push_back(fmt::format("commits: baseline {} ({}), current {} ({})", text_or(base_ctx, "git_commit"),
                                     text_or(base_ctx, "date_utc"), text_or(cur_ctx, "git_commit"),
                                     text_or(cur_ctx, "date_utc")));
  for (const auto* f : {&base, &cur}) {
    const std::string status = f->get(f->doc, "status", "", json::value_t::string).get<std::string>();
    if (status != "complete")
      report.notes.push_back(fmt::format("{} has status '{}': points with too few samples are inconclusive", f->path, status));
    const json& config = f->get(f->doc, "config", "", json::value_t::object);
    if (config.contains("injected_slowdown_pct"))
      report.notes.push_back(fmt::format("{} ran with --inject-slowdown-pct {} (a test of this comparison, not a real run)",
                                         f->path, config["injected_slowdown_pct"].dump()));
  }
  {
    json base_config = base.doc["config"], cur_config = cur.doc["config"];
    base_config.erase("injected_slowdown_pct"), cur_config.erase("injected_slowdown_pct");
    for (const auto& line : json_differences(base_config, cur_config)) report.notes.push_back("config " + line);
  }

}

// The methods and points of the two files: any that only one has, or that one skipped, is a mismatch.
void match_points(const std::map<std::string, Measured>& base_points, const std::map<std::string, Measured>& cur_points,
                  Report& report) {
  std::set<std::string> base_methods, cur_methods;
  for (const auto& [id, m] : base_points) base_methods.insert(m.method);
  for (const auto& [id, m] : cur_points) cur_methods.insert(m.method);
  std::set<std::string> only_base_methods, only_cur_methods;
  std::set_difference(base_methods.begin(), base_methods.end(), cur_methods.begin(), cur_methods.end(),
                      std::inserter(only_base_methods, only_base_methods.end()));
  std::set_difference(cur_methods.begin(), cur_methods.end(), base_methods.begin(), base_methods.end(),
                      std::inserter(only_cur_methods, only_cur_methods.end()));
  if (!only_base_methods.empty() || !only_cur_methods.empty())
    report.mismatches.push_back(fmt::format("methods: only in baseline [{}], only in current [{}]", listed(only_base_methods),
                                            listed(only_cur_methods)));
  auto method_in_both = [&](const Measured& m) { return base_methods.count(m.method) && cur_methods.count(m.method); };
  std::set<std::string> only_base, only_cur;
  for (const auto& [id, m] : base_points)
    if (!cur_points.count(id) && method_in_both(m)) only_base.insert(id);
  for (const auto& [id, m] : cur_points)
    if (!base_points.count(id) && method_in_both(m)) only_cur.insert(id);
  if (!only_base.empty())
    report.mismatches.push_back(fmt::format("points only in baseline ({}): {}", only_base.size(), listed(only_base)));
  if (!only_cur.empty())
    report.mismatches.push_back(fmt::format("points only in current ({}): {}", only_cur.size(), listed(only_cur)));
  for (const auto& [id, b] : base_points) {
    const auto it = cur_points.find(id);
    if (it == cur_points.end()) continue;
    const Measured& c = it->second;
    if (b.point && !c.point) report.mismatches.push_back(fmt::format("{}: measured in baseline, skipped in current ({})", id, c.skipped_reason));
    if (!b.point && c.point) report.mismatches.push_back(fmt::format("{}: skipped in baseline ({}), measured in current", id, b.skipped_reason));
  }
}

// The clock compared: CPU time where the device is the CPU and both files recorded it, else wall.
void choose_clock(const File& base, const File& cur, const Options& options, Report& report) {
  const json base_dev = base.doc.at("context").value("device", json(nullptr));
  if (options.times != "auto" && options.times != "wall" && options.times != "cpu")
    throw std::invalid_argument("--times is auto, wall or cpu, not '" + options.times + "'");
  const bool cpu_device = is_cpu_device(base_dev);
  const auto all_have_cpu = [](const json& doc) {
    const json& pts = doc["points"];
    return std::all_of(pts.begin(), pts.end(), [](const json& p) { return p.contains("samples_cpu_ms"); });
  };
  const bool have_cpu = all_have_cpu(base.doc) && all_have_cpu(cur.doc);
  report.clock = options.times == "auto" ? (cpu_device && have_cpu ? "cpu" : "wall") : options.times;
  if (options.times == "auto" && cpu_device && !have_cpu)
    report.notes.push_back("wall time compared: a file has no samples_cpu_ms (written before CPU time was recorded)");
  if (report.clock == "cpu" && !cpu_device)
    report.notes.push_back("CPU time on a GPU measures host overhead, not the GPU's work");

}

// One comparison per point both measured, in the baseline's order.
void compare_points(const File& base, const File& cur, const std::map<std::string, Measured>& cur_points,
                    const Options& options, Report& report) {
  std::map<std::string, std::vector<double>> base_probe_cache, cur_probe_cache;
  for (const json& bp : base.doc["points"]) {
    const std::string id = bp["id"].get<std::string>();
    const auto it = cur_points.find(id);
    if (it == cur_points.end() || !it->second.point) continue;
    const json& cp = *it->second.point;
    const std::string where = "point '" + id + "'";
    const std::string backend = base.get(bp, "backend", where, json::value_t::string).get<std::string>();
    cur.get(cp, "backend", where, json::value_t::string);
    const std::vector<std::string> probes = probes_for(options.normalise, backend);
    const Series bs = series_of(base, bp, probes, report.clock, base_probe_cache),
                 cs = series_of(cur, cp, probes, report.clock, cur_probe_cache);
    PointComparison pc;
    pc.id = id;
    pc.times = fmt::format("{} time, {}", report.clock,
                           probes.empty() ? std::string("raw") : fmt::format("normalised by {}", fmt::join(probes, "*")));
    pc.judgement = judge(bs.normalised, cs.normalised, options.rule);
    pc.baseline_samples = static_cast<int>(bs.raw.size());
    pc.current_samples = static_cast<int>(cs.raw.size());
    pc.raw_wall_ratio = raw_ratio(bp, cp, "samples_ms");
    pc.raw_cpu_ratio = raw_ratio(bp, cp, "samples_cpu_ms");
    pc.baseline_median_ms = median(base.numbers(bp, "samples_ms", where));  // required whichever time is compared
    pc.current_median_ms = median(cur.numbers(cp, "samples_ms", where));
    pc.work_changes = json_differences(base.get(bp, "work", where, json::value_t::object),
                                       cur.get(cp, "work", where, json::value_t::object));
    report.points.push_back(std::move(pc));
  }

}

// The machine factor the normalisation takes out, probe by probe (a note).
void note_machine_factor(const File& base, const File& cur, const Options& options, Report& report) {
  if (options.normalise != "none") {
    const json& bprobes = base.doc["measurement"]["probes"];
    const json& cprobes = cur.doc["measurement"].value("probes", json::object());
    std::vector<std::string> factors;
    const char* key = report.clock == "cpu" ? "cpu_ms_per_round" : "ms_per_round";
    for (const auto& [name, p] : bprobes.items())
      if (cprobes.contains(name) && p.contains(key) && cprobes[name].contains(key) && p[key].is_array() &&
          cprobes[name][key].is_array()) {
        const double work_ratio = cprobes[name].value("bytes", 0.0) + cprobes[name].value("flops", 0.0) > 0 &&
                                          p.value("bytes", 0.0) + p.value("flops", 0.0) > 0
                                      ? (p.value("bytes", 0.0) + p.value("flops", 0.0)) /
                                            (cprobes[name].value("bytes", 0.0) + cprobes[name].value("flops", 0.0))
                                      : 1.0;
        const double b = median(p[key].get<std::vector<double>>()), c = median(cprobes[name][key].get<std::vector<double>>());
        if (b > 0 && c > 0) factors.push_back(fmt::format("{} {:.3f}", name, c / b * work_ratio));
      }
    if (!factors.empty())
      report.notes.push_back(fmt::format("machine factor the normalisation takes out ({} time of the probes per unit "
                                         "of work, current / baseline): {}",
                                         report.clock, fmt::join(factors, ", ")));
  }
}

}  // namespace

Report compare_results(const json& baseline_doc, const json& current_doc, const Options& options,
                       const std::string& baseline_path, const std::string& current_path) {
  if (!(options.rule.threshold >= 0)) throw std::invalid_argument("the threshold must be >= 0");
  if (!(options.rule.confidence > 0 && options.rule.confidence < 1))
    throw std::invalid_argument("the confidence must be between 0 and 1");
  Report report;
  report.baseline_path = baseline_path;
  report.current_path = current_path;
  report.options = options;
  const File base{baseline_doc, baseline_path}, cur{current_doc, current_path};
  check_schemas(base, cur, report);
  if (!report.mismatches.empty()) return report;
  note_machines(base, cur, report);
  const auto base_points = points_of(base), cur_points = points_of(cur);
  match_points(base_points, cur_points, report);
  choose_clock(base, cur, options, report);
  compare_points(base, cur, cur_points, options, report);
  note_machine_factor(base, cur, options, report);
  return report;
}

json report_json(const Report& r) {
  json points = json::array();
  for (const auto& p : r.points) {
    const Judgement& j = p.judgement;
    json interval = j.interval.exists ? json{{"low", j.interval.low}, {"high", j.interval.high}, {"coverage", j.interval.coverage}}
                                      : json(nullptr);
    json entry = {{"id", p.id},
                  {"verdict", to_string(j.verdict)},
                  {"ratio_of_medians", j.ratio_of_medians},
                  {"interval", interval},
                  {"times", p.times},
                  {"raw_wall_ratio", p.raw_wall_ratio},
                  {"raw_cpu_ratio", p.raw_cpu_ratio},
                  {"samples", {{"baseline", p.baseline_samples}, {"current", p.current_samples}}},
                  {"median_ms", {{"baseline", p.baseline_median_ms}, {"current", p.current_median_ms}}},
                  {"work_changes", p.work_changes}};
    if (!j.why.empty()) entry["why"] = j.why;
    if (!p.paired_baseline_ms.empty())
      entry["paired_ms"] = {{"baseline", p.paired_baseline_ms}, {"current", p.paired_current_ms}};
    points.push_back(std::move(entry));
  }
  return {{"baseline", r.baseline_path},
          {"current", r.current_path},
          {"rule",
           {{"threshold", r.options.rule.threshold},
            {"confidence", r.options.rule.confidence},
            {"min_samples", r.options.rule.min_samples},
            {"normalise", r.options.normalise},
            {"times", r.options.times},
            {"clock", r.clock},
            {"statistic", r.design == "paired"
                              ? "Hodges-Lehmann estimate of current/baseline over paired rounds; interval: exact "
                                "distribution-free (Wilcoxon signed-rank inversion on the Walsh averages of the paired "
                                "log-ratios); slower/faster when the interval lies beyond the threshold, same when it "
                                "lies within"
                              : "ratio of medians current/baseline; interval: exact distribution-free (Mann-Whitney "
                                "inversion on the pairwise ratios); slower/faster when the interval lies beyond the "
                                "threshold, same when it lies within"}}},
          {"design", r.design},
          {"machine_differences", r.machine_differences},
          {"mismatches", r.mismatches},
          {"notes", r.notes},
          {"counts",
           {{"same", r.count(Verdict::same)},
            {"faster", r.count(Verdict::faster)},
            {"slower", r.count(Verdict::slower)},
            {"inconclusive", r.count(Verdict::inconclusive)},
            {"work_changed", std::count_if(r.points.begin(), r.points.end(), [](const auto& p) { return !p.work_changes.empty(); })}}},
          {"points", points},
          {"exit_code", r.exit_code()}};
}

std::string report_text(const Report& r) {
  std::string out;
  const Rule& rule = r.options.rule;
  out += fmt::format("baseline: {}\ncurrent:  {}\n", r.baseline_path, r.current_path);
  for (const auto& n : r.notes) out += "  note: " + n + "\n";
  if (!r.machine_differences.empty()) {
    out += "DIFFERENT MACHINES: the verdicts below are information, not a regression check (exit 0 whatever they say);\n"
           "compare two builds on one machine with `bokehbench ab` (or bench/ab COMMIT COMMIT)\n";
    for (const auto& m : r.machine_differences) out += "  - " + m + "\n";
  }
  if (!r.mismatches.empty()) {
    out += "NOT COMPARABLE:\n";
    for (const auto& m : r.mismatches) out += "  - " + m + "\n";
  }
  if (!r.points.empty() && r.design == "paired") {
    out += fmt::format("\ncompared: {} time{} of the two builds, timed back to back in paired rounds (which goes first "
                       "alternates); verdict from the {:g}% signed-rank interval of current/baseline against a {:g}% "
                       "threshold (min {} pairs)\n",
                       r.clock, r.clock == "cpu" ? " (process CPU time per frame; wall for a real GPU's passes)" : "",
                       100 * rule.confidence, 100 * rule.threshold, rule.min_samples);
  } else if (!r.points.empty()) {
    const std::string normalised =
        r.options.normalise == "none" ? std::string("raw")
        : r.options.normalise == "auto"
            ? std::string("normalised by the calibration probes of the same round (gpu_copy*gpu_fma for GPU points, "
                          "cpu_copy*cpu_fma for CPU points)")
            : "normalised by " + r.options.normalise;
    out += fmt::format("\ncompared: {} time{}, {}; verdict from the {:g}% interval of current/baseline against a {:g}% "
                       "threshold (min {} samples a side)\n",
                       r.clock, r.clock == "cpu" ? " (process CPU time per frame)" : "", normalised,
                       100 * rule.confidence, 100 * rule.threshold, rule.min_samples);
  }
  if (!r.points.empty()) {
    out += fmt::format("{:<13} {:>7}  {:<17} {:>8} {:>8} {:>7}  {}\n", "verdict", "ratio", "interval", "raw wall",
                       "raw cpu", r.design == "paired" ? "pairs" : "samples", "point");
    for (const auto& p : r.points) {
      const Judgement& j = p.judgement;
      const std::string interval = j.interval.exists ? fmt::format("[{:.3f}, {:.3f}]", j.interval.low, j.interval.high) : "-";
      const auto ratio = [](double x) { return x > 0 ? fmt::format("{:.3f}", x) : std::string("-"); };
      out += fmt::format("{:<13} {:>7.3f}  {:<17} {:>8} {:>8} {:>3}/{:<3}  {}{}\n", to_string(j.verdict),
                         j.ratio_of_medians, interval, ratio(p.raw_wall_ratio), ratio(p.raw_cpu_ratio),
                         p.baseline_samples, p.current_samples, p.id, j.why.empty() ? "" : " (" + j.why + ")");
      for (const auto& w : p.work_changes) out += "    ALGORITHMIC CHANGE: work." + w + "\n";
    }
  }
  if (!r.points.empty())
    out += fmt::format("\n{} points: {} same, {} faster, {} slower, {} inconclusive; {} with changed work counters\n",
                     r.points.size(), r.count(Verdict::same), r.count(Verdict::faster), r.count(Verdict::slower),
                     r.count(Verdict::inconclusive),
                     std::count_if(r.points.begin(), r.points.end(), [](const auto& p) { return !p.work_changes.empty(); }));
  switch (r.exit_code()) {
    case kNotComparable:
      out += fmt::format("result: the {} are not comparable (exit 3)\n", r.design == "paired" ? "builds" : "files");
      break;
    case kRegression:
      out += fmt::format("result: REGRESSION: {} point(s) confidently slower by more than {:g}% (exit 2)\n",
                         r.count(Verdict::slower), 100 * rule.threshold);
      break;
    case kWorkChanged: out += "result: no timing regression, but the work counters changed: an algorithmic change (exit 4)\n"; break;
    default:
      if (!r.machine_differences.empty() && r.count(Verdict::slower) > 0)
        out += fmt::format("result: {} point(s) slower on the other machine: information, not a regression (exit 0)\n",
                           r.count(Verdict::slower));
      else
        out += "result: no confident regression (exit 0)\n";
  }
  return out;
}

}  // namespace bokeh::compare
