#include "sweep.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <optional>
#include <set>
#include <sstream>

#include <benchmark/benchmark.h>
#include <fmt/format.h>
#include <fmt/ranges.h>

#include "accuracy.hpp"
#include "calibration.hpp"
#include "coc.hpp"
#include "intervals.hpp"
#include "parallel.hpp"
#include "report.hpp"
#include "paired.hpp"
#include "processes.hpp"
#include "roofline.hpp"
#include "run.hpp"
#include "store.hpp"
#include "targets.hpp"

namespace bokeh {

namespace {

// "AxB" with two positive integers (a resolution WIDTHxHEIGHT, a pattern NxK). Throws
// std::invalid_argument naming `what` and showing `example` for anything else.
std::pair<int, int> parse_int_pair(const std::string& text, const std::string& what, const std::string& example) {
  const auto bad = [&] { return std::invalid_argument(what + " '" + text + "' is not of the form " + example); };
  const auto x = text.find('x');
  if (x == std::string::npos) throw bad();
  auto number = [&](const std::string& part) {
    if (part.empty() || part.size() > 6 || part.find_first_not_of("0123456789") != std::string::npos) throw bad();
    return std::stoi(part);
  };
  return {number(text.substr(0, x)), number(text.substr(x + 1))};
}

}  // namespace

std::string Resolution::text() const { return fmt::format("{}x{}", width_px, height_px); }

Resolution parse_resolution(const std::string& text) {
  const auto [width, height] = parse_int_pair(text, "resolution", "WIDTHxHEIGHT (e.g. 1920x1080)");
  if (width < 16 || height < 16 || width > 16384 || height > 16384)
    throw std::invalid_argument("resolution '" + text + "' outside 16..16384 px per side");
  return {width, height};
}

GatherPattern parse_pattern(const std::string& text) {
  const auto [size_n, spacing_px] = parse_int_pair(text, "pattern", "NxK (e.g. 41x2)");
  const GatherPattern p{size_n, spacing_px};
  validate(p);
  return p;
}

std::string duration_text(double s) {
  if (s < 90) return fmt::format("{:.0f} s", s);
  return fmt::format("{}m{:02d}s", static_cast<int>(s) / 60, static_cast<int>(s) % 60);
}

namespace {

template <class T>
std::vector<T> accepted(const std::vector<T>& wanted, const std::vector<T>& offered, const T& fallback) {
  std::vector<T> out;
  for (const T& v : wanted)
    if (std::find(offered.begin(), offered.end(), v) != offered.end()) out.push_back(v);
  if (out.empty()) out.push_back(fallback);
  return out;
}

// Every combination of a method's options: fixed where the command sets them, swept over their
// `tradeoff` values where asked, else the default.
std::vector<std::map<std::string, double>> option_sets(const Method& m, const Axes& axes) {
  std::vector<std::map<std::string, double>> sets = {{}};
  for (const auto& spec : m.options) {
    std::vector<double> values = {spec.default_value};
    const auto& swept = axes.sweep_choices;
    if (auto it = axes.option_values.find(spec.key); it != axes.option_values.end()) {
      values = {it->second};
    } else if (!spec.choices.empty() && std::find(swept.begin(), swept.end(), spec.key) != swept.end()) {
      values.clear();
      for (std::size_t c = 0; c < spec.choices.size(); ++c) values.push_back(static_cast<double>(c));
    } else if (axes.sweep_options && !spec.tradeoff.empty()) {
      values = spec.tradeoff;
    }
    std::vector<std::map<std::string, double>> next;
    for (const auto& set : sets)
      for (double v : values) {
        auto s = set;
        s[spec.key] = v;
        next.push_back(std::move(s));
      }
    sets = std::move(next);
  }
  return sets;
}

// The method's options that differ from their defaults, as "/key:value" each ("" when none).
std::string variant_of(const SweepPoint& p) {
  std::string variant;
  for (const auto& spec : p.method->options) {
    const double v = p.options.number(spec.key);
    if (v != spec.default_value) variant += fmt::format("/{}:{}", spec.key, spec.to_json(v).dump());
  }
  return variant;
}

std::string point_id(const SweepPoint& p) {
  const FilterOptions& o = p.options;
  std::string id = fmt::format("{}/{}/{}/{}/N:{}/k:{}/{}", p.method->name, p.backend, p.scene, p.resolution.text(),
                               o.pattern.size_n, o.pattern.spacing_px, o.precision);
  if (o.buffer_scale != 1) id += fmt::format("/scale:1-{}", o.buffer_scale);
  if (p.max_coc_px != o.pattern.max_radius_px()) id += fmt::format("/coc:{}", p.max_coc_px);
  if (!o.aperture.is_disc()) id += "/aperture:" + o.aperture.name();  // disc points keep their ids
  return id + p.variant;
}

}  // namespace

std::pair<int, int> parse_shard(const std::string& text, const std::string& flag) {
  const auto bad = [&] {
    return std::invalid_argument(flag + " '" + text + "' is not of the form i/n with 1 <= i <= n (e.g. 2/3: the second of three)");
  };
  const auto slash = text.find('/');
  if (slash == std::string::npos) throw bad();
  auto number = [&](const std::string& part) {
    if (part.empty() || part.size() > 6 || part.find_first_not_of("0123456789") != std::string::npos) throw bad();
    return std::stoi(part);
  };
  const int index = number(text.substr(0, slash)), count = number(text.substr(slash + 1));
  if (count < 1 || index < 1 || index > count) throw bad();
  return {index, count};
}

namespace {

// A scheduler variable's value, "" when unset or empty: from env_or_null (the tests' environment) or the process's.
std::string scheduler_env(const char* name, const std::function<const char*(const char*)>& env_or_null) {
  const char* v = env_or_null ? env_or_null(name) : std::getenv(name);
  return v ? v : "";
}

}  // namespace

std::string resolve_auto_shard(const std::string& text, const std::function<const char*(const char*)>& env_or_null) {
  // A variable's whole value as a non-negative integer, or a message naming it.
  const auto integer = [&](const char* name) -> std::optional<long> {
    const std::string value = scheduler_env(name, env_or_null);
    if (value.empty()) return std::nullopt;
    if (value.size() > 9 || value.find_first_not_of("0123456789") != std::string::npos)
      throw std::invalid_argument(fmt::format("{}: {}='{}' is not a non-negative integer", text, name, value));
    return std::stol(value);
  };
  std::optional<long> given;  // auto/N
  if (text != "auto") {
    const std::string n = text.substr(std::min(text.size(), std::size_t{5}));
    if (text.rfind("auto/", 0) != 0 || n.empty() || n.size() > 6 || n.find_first_not_of("0123456789") != std::string::npos ||
        std::stol(n) < 1)
      throw std::invalid_argument(fmt::format("'{}': give i/n, auto (a Slurm array) or auto/N (N shards: a "
                                              "Kubernetes indexed Job's completions)",
                                              text));
    given = std::stol(n);
  }
  const auto slurm = integer("SLURM_ARRAY_TASK_ID");
  const auto kubernetes = integer("JOB_COMPLETION_INDEX");
  if (slurm && kubernetes)
    throw std::invalid_argument(fmt::format("{}: both SLURM_ARRAY_TASK_ID (Slurm) and JOB_COMPLETION_INDEX "
                                            "(Kubernetes) are set; give --shard i/n",
                                            text));
  long index = 0, count = 0;
  if (slurm) {
    const long min = integer("SLURM_ARRAY_TASK_MIN").value_or(1);
    const auto listed = integer("SLURM_ARRAY_TASK_COUNT"), max = integer("SLURM_ARRAY_TASK_MAX");
    const auto step = integer("SLURM_ARRAY_TASK_STEP");
    // Task ids min..max, each a shard: a stepped (1-9:2) or listed (1,3,7) array's ids are not that.
    if ((step && *step != 1) || (listed && max && *listed != *max - min + 1))
      throw std::invalid_argument(fmt::format("{}: the Slurm array's task ids are not the consecutive {}..{} "
                                              "(SLURM_ARRAY_TASK_COUNT={}, SLURM_ARRAY_TASK_STEP={}); give --shard i/n",
                                              text, min, max.value_or(-1), listed.value_or(-1), step.value_or(1)));
    index = *slurm - min + 1;
    count = listed ? *listed : max ? *max - min + 1 : 0;
    if (count == 0 && !given)
      throw std::invalid_argument(fmt::format("{}: SLURM_ARRAY_TASK_ID={} but neither SLURM_ARRAY_TASK_COUNT nor "
                                              "SLURM_ARRAY_TASK_MAX is set; give --shard auto/N",
                                              text, *slurm));
    if (count != 0 && given && *given != count)
      throw std::invalid_argument(fmt::format("{}: the Slurm array has {} tasks (SLURM_ARRAY_TASK_COUNT or MAX), "
                                              "not {}",
                                              text, count, *given));
    if (count == 0) count = *given;
    if (index < 1 || index > count)
      throw std::invalid_argument(fmt::format("{}: SLURM_ARRAY_TASK_ID={} with SLURM_ARRAY_TASK_MIN={} is task {} "
                                              "of {}, not a shard of {}",
                                              text, *slurm, min, index, count, count));
  } else if (kubernetes) {
    if (!given)
      throw std::invalid_argument(fmt::format("auto: JOB_COMPLETION_INDEX={} (a Kubernetes indexed Job) gives no "
                                              "count; give --shard auto/N, N the Job's completions",
                                              *kubernetes));
    index = *kubernetes + 1, count = *given;
    if (index > count)
      throw std::invalid_argument(fmt::format("{}: JOB_COMPLETION_INDEX={} (0-based) is not a shard of {}", text,
                                              *kubernetes, count));
  } else {
    throw std::invalid_argument(fmt::format("{}: no scheduler index found: looked for SLURM_ARRAY_TASK_ID (a Slurm "
                                            "array task) and JOB_COMPLETION_INDEX (a Kubernetes indexed Job); outside a "
                                            "scheduler give --shard i/n",
                                            text));
  }
  return fmt::format("{}/{}", index, count);
}

std::string scheduler_sweep_id(const std::function<const char*(const char*)>& env_or_null) {
  if (const std::string id = scheduler_env("BOKEH_SWEEP_ID", env_or_null); !id.empty()) return id;
  if (const std::string job = scheduler_env("SLURM_ARRAY_JOB_ID", env_or_null); !job.empty()) return "slurm:" + job;
  return "";
}

std::string shard_key(const std::string& id, const std::string& method, const std::string& variant) {
  std::string key = id.substr(0, id.size() - variant.size());
  return key.rfind(method + "/", 0) == 0 ? key.substr(method.size() + 1) : key;
}

namespace {
// Keeps shard `index` of `count`: the distinct shard keys, in the order expand() meets them, are dealt
// out in turn (key g goes to shard g % count + 1), so shards get near-equal shares and together
// every point exactly once.
std::vector<SweepPoint> keep_shard(std::vector<SweepPoint> points, int index, int count) {
  if (count <= 1) return points;
  std::map<std::string, std::size_t> keys;
  std::vector<SweepPoint> kept;
  for (auto& p : points) {
    const std::size_t g = keys.emplace(shard_key(p.id, p.method->name, p.variant), keys.size()).first->second;
    if (static_cast<int>(g % count) + 1 == index) kept.push_back(std::move(p));
  }
  return kept;
}
}  // namespace

std::vector<SweepPoint> expand(const Axes& axes) {
  if (axes.shard_count < 1 || axes.shard_index < 1 || axes.shard_index > axes.shard_count)
    throw std::invalid_argument(fmt::format("shard {}/{}: needs 1 <= i <= n", axes.shard_index, axes.shard_count));
  std::vector<SweepPoint> points;
  const std::vector<std::optional<double>> cocs =
      axes.max_coc_px.empty() ? std::vector<std::optional<double>>{std::nullopt}
                              : std::vector<std::optional<double>>(axes.max_coc_px.begin(), axes.max_coc_px.end());
  const std::vector<Aperture> apertures = axes.apertures.empty() ? std::vector<Aperture>{Aperture{}} : axes.apertures;
  for (const auto& coc : cocs) {
    if (coc && !(*coc > 0 && std::isfinite(*coc)))
      throw std::invalid_argument(fmt::format("--max-coc {} must be a number of pixels > 0", *coc));
    for (const auto& aperture : apertures)
    for (const auto& scene : axes.scenes)
      for (const auto& res : axes.resolutions)
        for (const auto& name : axes.methods) {
          const Method& m = find_method(name);
          std::vector<std::string> precisions =
              axes.precisions.empty() ? std::vector<std::string>{m.precisions.front()}
              : axes.precisions == std::vector<std::string>{"all"} ? m.precisions
                                                                   : accepted(axes.precisions, m.precisions, m.precisions.front());
          std::vector<int> scales = axes.scales.empty()                ? std::vector<int>{1}
                                    : axes.scales == std::vector<int>{0} ? m.buffer_scales
                                                                         : accepted(axes.scales, m.buffer_scales, 1);
          for (const auto& backend : axes.backends)
            for (const auto& precision : precisions)
              for (int scale : scales)
                for (const auto& values : option_sets(m, axes)) {
                  std::set<float> radii;  // methods that only see the largest radius: one point per radius
                  for (const auto& pattern : axes.patterns) {
                    if (!m.samples_pattern && !radii.insert(pattern.max_radius_px()).second) continue;
                    SweepPoint p;
                    p.method = &m;
                    p.backend = backend;
                    p.scene = scene;
                    p.resolution = res;
                    p.options = m.defaults(pattern);
                    p.options.precision = precision;
                    p.options.buffer_scale = scale;
                    p.options.values = values;
                    p.options.aperture = aperture;
                    p.max_coc_px = coc.value_or(pattern.max_radius_px());
                    p.variant = variant_of(p);
                    p.id = point_id(p);
                    points.push_back(std::move(p));
                  }
                }
        }
  }
  return keep_shard(std::move(points), axes.shard_index, axes.shard_count);
}

std::optional<vk::DeviceRequirements> gpu_requirements(const std::vector<SweepPoint>& points) {
  std::optional<vk::DeviceRequirements> wanted;
  for (const auto& p : points)
    if (p.backend == "gpu") {
      if (!wanted) wanted.emplace();
      wanted->add(p.method->needs(p.options));
    }
  return wanted;
}

namespace {

nlohmann::json distribution_json(const runner::Distribution& d) {
  return {{"median", d.median}, {"q1", d.q1}, {"q3", d.q3},         {"min", d.min},
          {"max", d.max},       {"mean", d.mean}, {"stddev", d.stddev}};
}


// What one point knows beyond its samples.
struct PointInfo {
  double f_stop = 0;
  nlohmann::json memory, work, error;
  nlohmann::json counters = nlohmann::json::object();  // GPU: per pass, commands and shader invocations
  nlohmann::json stats = nlohmann::json::object();     // what the method found in the scene (GpuFilter::stats)
};

// What names a point: its axes' values.
nlohmann::json identity_json(const SweepPoint& p) {
  const FilterOptions& o = p.options;
  nlohmann::json identity = {{"id", p.id},
          {"method", p.method->name},
          {"backend", p.backend},
          {"scene", p.scene},
          {"width_px", p.resolution.width_px},
          {"height_px", p.resolution.height_px},
          {"N", o.pattern.size_n},
          {"k", o.pattern.spacing_px},
          {"max_radius_px", o.pattern.max_radius_px()},
          {"precision", o.precision},
          {"buffer_scale", o.buffer_scale},
          {"options", p.method->options_json(o)},
          {"variant", p.variant},
          {"max_coc_px", p.max_coc_px},
          {"aperture", aperture_json(o.aperture)}};
  if (!p.method->package.is_null()) identity["package"] = p.method->package;  // name, content hash, folder
  return identity;
}

// What a results entry of a point (point_json) knows beyond its samples: how a run measured by
// several processes takes it from the process that measured it.
PointInfo info_of(const nlohmann::json& point) {
  return {point.value("f_stop", 0.0), point.at("memory"), point.at("work"), point.at("error"),
          point.value("counters", nlohmann::json::object()), point.value("stats", nlohmann::json::object())};
}

// What a measured point or baseline's samples say, in the fields both have.
nlohmann::json samples_json(const runner::PointRecord& rec) {
  const std::vector<double> frame = rec.frame_ms();
  const runner::Distribution d = runner::distribution(frame);
  return {{"frame_ms", distribution_json(d)},
          {"relative_iqr", d.relative_iqr()},
          {"samples_ms", frame},
          {"samples_cpu_ms", rec.cpu_ms()},
          {"sample_rounds", rec.sample_round},
          {"frames_per_sample", rec.frames_per_sample},
          {"warm_up_ms", rec.warm_up_ms},
          {"settled", rec.settled},
          {"measure_wall_s", rec.wall_s}};
}

// Taps and bytes a second of the passes' declared work (work.hpp) over their time; a fused pass's
// speed counted as the unfused passes' bytes too (unfused_gb_per_s), where it keeps some.
nlohmann::json pass_throughput(const std::vector<nlohmann::json>& passes, double ms) {
  double taps = 0, bytes = 0, kept = 0;
  for (const auto& w : passes)
    taps += w["taps"].get<double>(), bytes += w["bytes_read"].get<double>() + w["bytes_written"].get<double>(),
        kept += w.value("bytes_kept", 0.0);
  nlohmann::json t = {{"taps_per_s", taps / (ms * 1e-3)}, {"gb_per_s", bytes / (ms * 1e6)}};
  if (kept > 0) t["unfused_gb_per_s"] = (bytes + kept) / (ms * 1e6);
  return t;
}

// The one serialisation of a measured point.
nlohmann::json point_json(const SweepPoint& p, const runner::PointRecord& rec, const PointInfo& info) {
  nlohmann::json out = identity_json(p);
  out.update(samples_json(rec));
  std::map<std::string, std::vector<double>> pass_values;
  for (const auto& s : rec.samples)
    for (const auto& [pass, ms] : s.pass_ms) pass_values[pass].push_back(ms);
  nlohmann::json pass_ms = nlohmann::json::object(), throughput = nlohmann::json::object();
  for (const auto& [pass, values] : pass_values) {
    const double median = runner::quantile(values, 0.5);
    pass_ms[pass] = median;
    if (info.work.contains("passes") && info.work["passes"].contains(pass) && median > 0)
      throughput[pass] = pass_throughput({info.work["passes"][pass]}, median);
  }
  const double median_ms = out["frame_ms"]["median"].get<double>();
  if (p.backend == "cpu" && median_ms > 0) {  // the CPU reference is timed whole
    std::vector<nlohmann::json> passes;
    for (const auto& [pass, w] : info.work["passes"].items()) passes.push_back(w);
    throughput["frame"] = pass_throughput(passes, median_ms);
  }
  out.update({          {"f_stop", info.f_stop},
          {"pass_ms", pass_ms},
          {"samples_pass_ms", pass_values},
          {"work", info.work},
          {"counters", info.counters},
          {"throughput", throughput},
          {"memory", info.memory},
          {"stats", info.stats},
          {"error", info.error}});
  return out;
}

// Google Benchmark's JSON of the measured points: every sample replayed as one repetition of manual
// time, so gbench computes its statistics and compare.py can pair two runs by the stable names.
std::string gbench_json(const std::string& sweep, const std::vector<SweepPoint>& points, const runner::RunRecord& record) {
  static bool initialized = false;
  if (!initialized) {
    static char name[] = "bokehbench";  // gbench keeps argv[0] for its context
    static char* argv[] = {name, nullptr};
    int argc = 1;
    benchmark::Initialize(&argc, argv);
    initialized = true;
  }
  benchmark::ClearRegisteredBenchmarks();
  std::vector<std::size_t> next(points.size(), 0);
  for (std::size_t i = 0; i < points.size(); ++i) {
    const auto& rec = record.points[i];
    if (rec.samples.empty()) continue;
    auto* b = benchmark::RegisterBenchmark((sweep + "/" + points[i].id).c_str(), [&, i](benchmark::State& state) {
      const runner::Sample& s = rec.samples[next[i]++ % rec.samples.size()];
      for (auto _ : state) state.SetIterationTime(s.frame_ms * 1e-3);
      for (const auto& [pass, ms] : s.pass_ms) state.counters[pass + "_ms"] = ms;
      state.counters["frames_per_sample"] = rec.frames_per_sample;
    });
    b->Unit(benchmark::kMillisecond)->Iterations(1)->Repetitions(static_cast<int>(rec.samples.size()))->UseManualTime();
    b->ComputeStatistics("min", [](const std::vector<double>& v) { return *std::min_element(v.begin(), v.end()); })
        ->ComputeStatistics("max", [](const std::vector<double>& v) { return *std::max_element(v.begin(), v.end()); })
        ->ComputeStatistics("q1", [](const std::vector<double>& v) { return runner::quantile(v, 0.25); })
        ->ComputeStatistics("q3", [](const std::vector<double>& v) { return runner::quantile(v, 0.75); });
  }
  // gbench names a run NAME/iterations:1/repeats:R; R is how many samples this run took, so without
  // both the names stay the same from run to run and compare.py pairs them.
  struct StableNames : benchmark::JSONReporter {
    void ReportRuns(const std::vector<Run>& runs) override {
      std::vector<Run> renamed = runs;
      for (Run& r : renamed) r.run_name.iterations.clear(), r.run_name.repetitions.clear();
      JSONReporter::ReportRuns(renamed);
    }
  };
  std::ostringstream out;
  StableNames reporter;
  reporter.SetOutputStream(&out);
  reporter.SetErrorStream(&out);
  benchmark::RunSpecifiedBenchmarks(&reporter);
  benchmark::ClearRegisteredBenchmarks();
  return out.str();
}

nlohmann::json methods_json(const std::vector<SweepPoint>& points) {
  nlohmann::json out = nlohmann::json::array();
  for (const Method* method : known_methods()) {
    const Method& m = *method;
    if (std::none_of(points.begin(), points.end(), [&](const SweepPoint& p) { return p.method == &m; })) continue;
    nlohmann::json options = nlohmann::json::array();
    for (const auto& s : m.options) options.push_back({{"key", s.key}, {"help", s.help}, {"default", s.to_json(s.default_value)}});
    out.push_back({{"name", m.name},
                   {"description", m.description},
                   {"precisions", m.precisions},
                   {"buffer_scales", m.buffer_scales},
                   {"options", options}});
    if (!m.package.is_null()) out.back()["package"] = m.package;
  }
  return out;
}

// Each point's error against the exact references of its scene, frame size and CoC (made once and
// shared by the points that need them, cached on disk), and against the sweep's extra reference.
class AccuracyOfPoints {
 public:
  AccuracyOfPoints(const std::vector<SweepPoint>& points, SweepTargets& targets, const SweepSettings& s)
      : points_(points), targets_(targets), settings_(s), cache_(s.reference_cache) {}

  nlohmann::json error(std::size_t i, const Image& output) {
    const SweepPoint& p = points_[i];
    const Scene& scene = targets_.scene(p);
    const Lens lens = targets_.lens(p);
    const float clamp = p.options.pattern.max_radius_px();
    const std::string key =
        fmt::format("{}/{}/{}/{}/{}", p.scene, p.resolution.text(), p.max_coc_px, clamp, p.options.aperture.name());
    auto it = exact_.find(key);
    if (it == exact_.end()) it = exact_.emplace(key, exact_references(scene, lens, clamp, cache_)).first;
    nlohmann::json error = error_json(output, it->second);
    if (settings_.extra_reference)
      if (auto ref = settings_.extra_reference(p, scene, lens)) {
        auto e = extra_.find(ref->key);
        if (e == extra_.end()) e = extra_.emplace(ref->key, ref->make()).first;
        error["vs_" + ref->field] = metrics_json(compare_images(output, e->second));
      }
    return error;
  }

 private:
  const std::vector<SweepPoint>& points_;
  SweepTargets& targets_;
  const SweepSettings& settings_;
  ExactReferenceCache cache_;
  std::map<std::string, ExactReferences> exact_;
  std::map<std::string, Image> extra_;
};

// The probes of the machine's limits: on the device when there is one, on the CPU when a point runs there.
std::vector<CalibrationKernel> calibration_kernels(vk::Context* ctx, bool any_cpu, int cpu_threads) {
  std::vector<CalibrationKernel> calibration;
  if (ctx)
    for (auto& k : gpu_calibration(*ctx)) calibration.push_back(std::move(k));
  if (any_cpu)
    for (auto& k : cpu_calibration(cpu_threads)) calibration.push_back(std::move(k));
  return calibration;
}

// The probes' times per round and the limits they give; each pass against them (roofline.hpp).
void add_probes_and_limits(nlohmann::json& measurement, nlohmann::json& measured_points,
                           const std::vector<CalibrationKernel>& calibration, const runner::RunRecord& rec) {
  nlohmann::json probes = nlohmann::json::object(), limits = nlohmann::json::object();
  for (const auto& k : calibration) {
    const auto it = rec.probe_ms.find(k.name);
    if (it == rec.probe_ms.end() || it->second.empty()) continue;
    const runner::Distribution d = runner::distribution(it->second);
    probes[k.name] = {{"ms_per_round", it->second},
                      {"cpu_ms_per_round", rec.probe_cpu_ms.at(k.name)},
                      {"ms", distribution_json(d)},
                      {"drift", d.median > 0 ? (d.max - d.min) / d.median : 0.0},
                      {"bytes", k.bytes},
                      {"flops", k.flops}};
    if (k.bytes > 0) limits[k.name + "_gb_per_s"] = k.bytes / (d.median * 1e6);
    if (k.flops > 0) limits[k.name + "_gflop_per_s"] = k.flops / (d.median * 1e6);
  }
  add_roofline(measured_points, limits);
  measurement["probes"] = probes;
  measurement["limits"] = limits;
}

// The results document of a run so far (complete, or partial at a checkpoint or an interruption).
nlohmann::json sweep_document(const std::vector<SweepPoint>& points, const std::vector<PointInfo>& info,
                              const runner::RunRecord& rec, const std::vector<CalibrationKernel>& calibration,
                              const SweepSettings& s, const runner::Policy& policy, double elapsed_s) {
  nlohmann::json measured = nlohmann::json::array(), skipped = nlohmann::json::array();
  for (std::size_t i = 0; i < points.size(); ++i) {
    const auto& r = rec.points[i];
    if (!r.skipped.empty()) {
      nlohmann::json entry = identity_json(points[i]);
      entry.update({{"reason", r.skipped}, {"memory", info[i].memory}});
      skipped.push_back(std::move(entry));
    } else if (!r.samples.empty()) {
      measured.push_back(point_json(points[i], r, info[i]));
    }
  }
  // The baselines are the runner's points after the sweep's (run_sweep).
  nlohmann::json baselines = nlohmann::json::array(), skipped_baselines = nlohmann::json::array();
  for (std::size_t b = 0; b < s.baselines.size(); ++b) {
    const auto& r = rec.points[points.size() + b];
    nlohmann::json entry = s.baselines[b].identity;
    if (!r.skipped.empty()) {
      entry["reason"] = r.skipped;
      skipped_baselines.push_back(std::move(entry));
    } else if (!r.samples.empty()) {
      entry.update(samples_json(r));
      baselines.push_back(std::move(entry));
    }
  }
  nlohmann::json order = nlohmann::json::array();
  for (const auto& round : rec.round_order) {
    nlohmann::json ids = nlohmann::json::array();
    for (std::size_t i : round) ids.push_back(i < points.size() ? points[i].id : s.baselines.at(i - points.size()).id);
    order.push_back(ids);
  }
  nlohmann::json measurement = {
      {"interleaved", "every round visits every unfinished point once, in a shuffled order (seeded; points the "
                      "command compares with each other back to back, taking turns going first, and the points of a curve "
                      "it fits one after another in a shuffled order); each visit takes "
                      "one sample of frames_per_sample frames"},
      {"seed", s.policy.seed},
      {"budget_s", s.policy.budget_s},
      {"min_samples", s.policy.min_samples},
      {"max_samples", s.policy.max_samples},
      {"settled_relative_iqr", s.policy.settled_relative_iqr},
      {"sample_min_ms", s.policy.sample_min_ms},
      {"lead_in_ms", policy.lead_in_ms},
      {"extra_work_fraction", policy.extra_work_fraction},
      {"rounds", rec.round_order.size()},
      {"processes", s.processes},
      {"replicas", s.policy.replicas},
      {"stop_reason", rec.stop_reason},
      {"round_order", order},
      {"timing", "gpu: Vulkan timestamps around each pass of one submission of frames_per_sample frames (per-frame "
                 "means), after warm-up; cpu: wall clock of the CPU reference, CoC pass included; "
                 "samples_cpu_ms: the process CPU time (all threads) per frame over the same sample"}};
  if (!rec.round_process.empty()) measurement["round_process"] = rec.round_process;
  add_probes_and_limits(measurement, measured, calibration, rec);
  nlohmann::json config = s.config;
  if (s.shard_count > 1) config["shard"] = fmt::format("{}/{}", s.shard_index, s.shard_count);
  if (policy.extra_work_fraction > 0)  // a test of `compare`, never a real run: say so where it shows
    config["injected_slowdown_pct"] = std::lround(policy.extra_work_fraction * 100);
  nlohmann::json doc = {{"status", rec.status},    {"config", config},     {"methods", methods_json(points)},
                        {"measurement", measurement}, {"points", measured}, {"skipped", skipped},
                        {"elapsed_s", elapsed_s}};
  if (!s.baselines.empty()) doc.update({{"baselines", baselines}, {"skipped_baselines", skipped_baselines}});
  return doc;
}

// One line per first visit, then one per round, each with the time left.
std::function<void(const runner::Progress&, const runner::PointRecord&)> progress_printer(std::size_t measurable) {
  return [measurable, printed_round = -1](const runner::Progress& pr, const runner::PointRecord& rec) mutable {
    if (pr.round == 0) {
      std::string what = rec.skipped.empty()
                             ? fmt::format("{:10.3f} ms ({} frames/sample)", rec.samples.back().frame_ms, rec.frames_per_sample)
                             : "skipped: " + rec.skipped;
      fmt::print("[{:>3}/{}] {:<58} {}  ~{} left\n", pr.visits_done, measurable, rec.name, what,
                 duration_text(pr.eta_s));
    } else if (pr.round != printed_round) {
      fmt::print("round {}: {} of {} points still measuring, {} elapsed, ~{} left\n", pr.round + 1, pr.points_active,
                 measurable, duration_text(pr.elapsed_s), duration_text(pr.eta_s));
    }
    printed_round = pr.round;
    std::fflush(stdout);
  };
}

// Where a sweep's files go: NAME.json when complete, NAME.partial.json before (and after an
// interruption, beside a complete file of an earlier run, never over it); the same for _gbench.
struct SweepFiles {
  std::string final_json, partial_json, gbench, gbench_partial;
  SweepFiles(const std::string& out_dir, const std::string& name) {
    const std::filesystem::path dir(out_dir);
    final_json = (dir / (name + ".json")).string();
    partial_json = (dir / (name + ".partial.json")).string();
    gbench = (dir / (name + "_gbench.json")).string();
    gbench_partial = (dir / (name + "_gbench.partial.json")).string();
  }
};

// The run into the results store, after its JSON file is written (the file is the run's output; the
// store its history). A store that cannot take it fails the command, naming the store.
void append_to_store(const SweepSettings& s, const nlohmann::json& context, const nlohmann::json& body) {
  if (s.store_url.empty()) return;
  nlohmann::json doc = body;
  doc["schema"] = "bokehbench." + s.name;
  doc["context"] = context;
  history::append_run(s.store_url, doc, command_line());
}

// The machine's state during the run against its earlier runs in the store (history::machine_state),
// and how far its repeat runs of this configuration put each headline figure
// (history::run_to_run_spread, which derive reads), before this run is appended; with no store, or
// none yet, there is nothing to compare with.
void add_machine_state(const SweepSettings& s, const nlohmann::json& context, nlohmann::json& doc) {
  if (s.store_url.empty() || !doc.contains("measurement")) return;
  nlohmann::json& measurement = doc["measurement"];
  try {
    auto store = history::Store::open(s.store_url, false);
    measurement["machine_state"] = history::machine_state(*store, {{"context", context}, {"measurement", measurement}});
    measurement["run_to_run"] = history::run_to_run_spread(*store, {{"context", context}, {"points", doc["points"]}}, s.name);
  } catch (const std::exception& e) {
    measurement["machine_state"] = measurement["run_to_run"] = {{"earlier_runs", 0}, {"note", e.what()}};
  }
}

}  // namespace

nlohmann::json probe_drift(const nlohmann::json& measurement) {
  nlohmann::json drift = nlohmann::json::object();
  if (measurement.contains("probes"))
    for (const auto& [name, probe] : measurement["probes"].items()) drift[name] = probe["drift"];
  return drift;
}

std::string probe_drift_text(const nlohmann::json& drift) {
  std::string text;
  for (const auto& [name, d] : drift.items())
    text += fmt::format("{}{} {:.0f}%", text.empty() ? "" : ", ", name, 100 * d.get<double>());
  return text;
}

namespace {

// How noisy the run was, whatever the command: the probes' drift over the rounds ((max - min) /
// median) and the half-width of the points' 95% median intervals, relative to the median. Above 10%
// for the median point, two points 10% apart are not told apart, and the summary says so.
constexpr double kNoisyHalfWidth = 0.10;

void add_noise(nlohmann::json& doc) {
  std::vector<double> half_widths;
  std::string widest_id;
  double widest = 0;
  for (const auto& p : doc["points"]) {
    if (!p.contains("frame_ms_interval")) continue;
    const auto& t = p["frame_ms_interval"];
    const double estimate = t["estimate"].get<double>();
    if (!(estimate > 0)) continue;
    const double w = (t["high"].get<double>() - t["low"].get<double>()) / 2 / estimate;
    half_widths.push_back(w);
    if (w >= widest) widest = w, widest_id = p["id"].get<std::string>();
  }
  nlohmann::json noise = {{"probe_drift", probe_drift(doc["measurement"])}, {"points", half_widths.size()}, {"noisy_above", kNoisyHalfWidth}};
  if (!half_widths.empty()) {
    noise["median_relative_half_width"] = runner::quantile(half_widths, 0.5);
    noise["widest"] = {{"id", widest_id}, {"relative_half_width", widest}};
    noise["noisy"] = noise["median_relative_half_width"].get<double>() > kNoisyHalfWidth;
  }
  doc["measurement"]["noise"] = noise;
}

void print_noise(const nlohmann::json& measurement) {
  if (!measurement.contains("noise") || !measurement["noise"].contains("noisy")) return;
  const auto& n = measurement["noise"];
  const std::string drift = probe_drift_text(n["probe_drift"]);
  fmt::print("{}: the points' 95% intervals are +-{:.1f}% of the median for the median point, +-{:.1f}% at the widest "
             "({}); the probes drifted {} over the rounds{}\n",
             n["noisy"].get<bool>() ? "NOISY RUN" : "noise", 100 * n["median_relative_half_width"].get<double>(),
             100 * n["widest"]["relative_half_width"].get<double>(), n["widest"]["id"].get<std::string>(),
             drift.empty() ? "none measured" : drift,
             n["noisy"].get<bool>()
                 ? fmt::format(": two points whose medians differ by less than about {:.0f}% are not told apart by "
                               "their medians here (ratios paired within rounds cancel the drift a round shares and "
                               "have intervals of their own)",
                               200 * n["median_relative_half_width"].get<double>())
                 : "");
}

void print_machine_state(const nlohmann::json& measurement) {
  if (!measurement.contains("machine_state")) return;
  const auto& m = measurement["machine_state"];
  if (m["earlier_runs"].get<int>() == 0) {
    fmt::print("machine state: no earlier run of this machine in the results store to compare its probes with\n");
    return;
  }
  std::string probes;
  for (const auto& [name, p] : m["probes"].items())
    probes += fmt::format("{}{} {:.2f}x", probes.empty() ? "" : ", ", name, p["ratio"].get<double>());
  const std::string against = fmt::format("this machine's median over its last {} runs in the store", m["earlier_runs"].get<int>());
  if (m["unusual"].empty()) {
    fmt::print("machine state: probes' times {} of {}{}\n", probes, against,
               m["earlier_runs"].get<int>() < m["min_earlier_runs"].get<int>()
                   ? fmt::format(" (too few to call a phase unusual: {} needed)", m["min_earlier_runs"].get<int>())
                   : "");
    return;
  }
  fmt::print("UNUSUAL MACHINE STATE: probes' times {} of {} ({} beyond {:.1f}x): the machine was in another phase "
             "than its usual one, and figures measured in it may differ from other runs' by more than their "
             "intervals, which cover only this run's rounds\n",
             probes, against, fmt::join(m["unusual"].get<std::vector<std::string>>(), ", "),
             m["unusual_ratio"].get<double>());
}

}  // namespace

nlohmann::json run_sweep(const std::vector<SweepPoint>& points, const SweepSettings& s) {
  if (s.serve) {  // a paired comparison's worker (bokehbench ab): it times samples on request, writes nothing
    paired::serve(points, s);
    return nlohmann::json::object();
  }
  const auto wall_start = std::chrono::steady_clock::now();
  auto elapsed_s = [&] { return std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count(); };
  // Where the results go is checked before anything is measured.
  check_writable_dir(s.out_dir);
  remove_stale_temporaries(s.out_dir);
  if (s.plot && !s.plot_script.empty()) check_writable_dir(s.plots_dir);
  const SweepFiles files(s.out_dir, s.name);
  SweepTargets targets(points, s.device, s.cpu_threads, s.max_buffer_mb, s.frame_budget_s);
  vk::Context* ctx = targets.context();
  if (ctx) ctx->watchdog_floor_s = s.watchdog_s;
  const bool any_cpu = std::any_of(points.begin(), points.end(), [](const SweepPoint& p) { return p.backend == "cpu"; });
  nlohmann::json context = run_context(ctx ? &ctx->info() : nullptr);
  // A shard's run says which scheduler job it belongs to: the store then tells a shard given twice in
  // one job from the same shard of a later job (history::sweep_identity_of).
  if (s.shard_count > 1)
    if (const std::string id = scheduler_sweep_id(); !id.empty()) context["sweep_id"] = id;
  runner::Policy policy = s.policy;
  // Unless given: a GPU (not lavapipe) drops its clocks while the CPU references and other points run,
  // so each sample gets an untimed lead-in of a quarter sample first; lavapipe none.
  if (policy.lead_in_ms < 0) policy.lead_in_ms = ctx && !ctx->info().is_software() ? policy.sample_min_ms / 4 : 0;

  // Plan: what cannot run is known before anything is allocated.
  std::vector<std::string> names, skip;
  std::vector<PointInfo> info(points.size());
  for (std::size_t i = 0; i < points.size(); ++i) {
    names.push_back(points[i].id);
    skip.push_back(targets.plans()[i].skip);
    info[i].work = targets.plans()[i].work;
    info[i].memory = targets.plans()[i].memory;
  }
  for (const auto& b : s.baselines) {  // the runner's points after the sweep's
    names.push_back(b.id);
    skip.push_back(b.skip);
  }
  const std::size_t measurable = std::count(skip.begin(), skip.end(), "");
  AccuracyOfPoints accuracy(points, targets, s);
  std::vector<CalibrationKernel> calibration = calibration_kernels(ctx, any_cpu, targets.cpu_threads());

  runner::Hooks hooks;
  hooks.prepare = [&](std::size_t i) -> std::unique_ptr<runner::Target> {
    if (i >= points.size()) {
      const SweepSettings::Baseline& b = s.baselines.at(i - points.size());
      return b.prepare(targets.scene(b.scene, b.resolution));
    }
    info[i].f_stop = targets.lens(points[i]).f_stop;
    return targets.prepare(i);
  };
  hooks.first_ready = [&](std::size_t i, runner::Target& t) {
    if (auto* g = dynamic_cast<GpuTarget*>(&t)) {
      for (const auto& pass : g->counted_frame()) {
        info[i].counters[pass.pass] = {{"commands", pass.commands}};
        if (pass.invocations >= 0) info[i].counters[pass.pass]["compute_invocations"] = pass.invocations;
      }
      // What the filter allocated for this scene (bytes above is the model, which budgets use).
      info[i].memory["allocated_bytes"] = g->intermediate_bytes();
      info[i].stats = g->stats();
      const Image output = g->output();
      // A built-in's non-finite values are a finding (an f16 overflow), counted with the error; a
      // package's are a fault of the package: its point is skipped, saying so.
      if (const std::size_t bad = count_non_finite(output); bad > 0 && !points[i].method->package.is_null())
        throw std::runtime_error(fmt::format("package {} wrote {} non-finite values (NaN or infinite) of {} in its "
                                             "output: a package's output must be finite",
                                             points[i].method->name, bad, output.pixels.size()));
      info[i].error = accuracy.error(i, output);
    }
    if (auto* c = dynamic_cast<CpuTarget*>(&t)) {
      info[i].stats = c->stats();
      info[i].error = accuracy.error(i, c->output());
    }
  };
  for (auto& k : calibration) hooks.probes.emplace_back(k.name, std::move(k.target));
  auto last_write = std::chrono::steady_clock::now() - std::chrono::hours(1);
  hooks.checkpoint = [&](const runner::RunRecord& rec) {
    if (std::chrono::steady_clock::now() - last_write < std::chrono::seconds(2)) return;
    write_results(files.partial_json, "bokehbench." + s.name, context,
                  sweep_document(points, info, rec, calibration, s, policy, elapsed_s()));
    last_write = std::chrono::steady_clock::now();
  };
  hooks.progress = progress_printer(measurable);
  if (s.visit_together) {
    std::map<std::string, std::size_t> groups;
    for (const auto& p : points) hooks.visit_group.push_back(groups.emplace(s.visit_together(p), groups.size()).first->second);
    for (const auto& b : s.baselines) hooks.visit_group.push_back(groups.emplace(b.visit_together, groups.size()).first->second);
  }
  if (s.visit_block) {
    std::map<std::string, std::size_t> blocks;
    for (const auto& p : points) hooks.visit_block.push_back(blocks.emplace(s.visit_block(p), blocks.size()).first->second);
    for (const auto& b : s.baselines) hooks.visit_block.push_back(blocks.emplace(b.visit_block, blocks.size()).first->second);
  }
  if (s.points_needed) {
    // A later process of several judges the run's figures, the earlier processes' rounds and its own:
    // its own alone (a third of them) would rarely reach the rounds or the width a figure settles at.
    const runner::RunRecord earlier =
        s.process_index > 1 ? processes::join_earlier(names, s.run_out_dir, s.name, s.process_index - 1).record
                            : runner::RunRecord{};
    hooks.points_needed = [&s, &context, earlier](const runner::RunRecord& record) {
      return s.points_needed(s.process_index > 1 ? runner::followed_by(earlier, record) : record, context);
    };
  }

  fmt::print("{}: {} points{} ({} measurable), device {}, LP_NUM_THREADS={}, budget {} s{}\n", s.name, names.size(),
             s.baselines.empty() ? "" : fmt::format(", {} of them CPU baselines", s.baselines.size()), measurable,
             ctx ? ctx->info().name : "none (CPU only)", context["lp_num_threads"].get<std::string>(), s.policy.budget_s,
             s.processes > 1 ? fmt::format(" over {} processes one after another", s.processes)
             : s.process_index > 0 ? fmt::format(" (process {}, --process)", s.process_index) : "");
  // Each reason once, then the points it skips (the results' `skipped` list has each with its reason):
  // an option swept over choices that some precisions or scales cannot run skips a family of points.
  std::vector<std::pair<std::string, std::vector<std::string>>> skipped_by_reason;  // in order of appearance
  for (std::size_t i = 0; i < names.size(); ++i) {
    if (skip[i].empty()) continue;
    auto it = std::find_if(skipped_by_reason.begin(), skipped_by_reason.end(),
                           [&](const auto& r) { return r.first == skip[i]; });
    if (it == skipped_by_reason.end()) it = skipped_by_reason.insert(it, {skip[i], {}});
    it->second.push_back(names[i]);
  }
  for (const auto& [reason, ids] : skipped_by_reason)
    if (ids.size() == 1)
      fmt::print("  skipped {}: {}\n", ids.front(), reason);
    else
      fmt::print("  skipped {} points: {}\n    {}\n", ids.size(), reason, fmt::join(ids, "\n    "));

  runner::RunRecord record;
  {
    runner::InterruptScope interrupts;
    if (s.processes > 1) {
      processes::Joined joined = processes::run(names, s);
      record = std::move(joined.record);
      for (std::size_t i = 0; i < points.size(); ++i)
        if (const auto& p = joined.points[i]; !p.is_null()) info[i] = info_of(p);
    } else {
      record = runner::run(names, skip, policy, hooks);
    }
  }
  context["power_state"]["end"] = power_state(ctx ? &ctx->info() : nullptr);
  nlohmann::json doc = sweep_document(points, info, record, calibration, s, policy, elapsed_s());
  doc["context"] = context;  // derive reads the device, as merge does from a file
  const bool complete = record.status == "complete";
  try {
    add_median_intervals(doc);
    add_noise(doc);
    add_machine_state(s, context, doc);
    if (s.derive) s.derive(doc);
  } catch (const std::exception& e) {
    // The rounds are measured: keep them, without the figures that failed, before saying why.
    write_results(files.partial_json, "bokehbench." + s.name, context, doc);
    throw std::runtime_error(fmt::format("{} (after measuring {} rounds, which are in {})", e.what(),
                                         record.round_order.size(), files.partial_json));
  }
  // gbench's own statistics and names, for compare.py.
  // Nothing measured yet (interrupted during the first visit, or every point skipped): gbench would
  // write only "Failed to match any benchmarks", so write an empty but valid document instead.
  const bool any_samples = std::any_of(record.points.begin(), record.points.end(),
                                      [](const runner::PointRecord& r) { return !r.samples.empty(); });
  const std::string gbench =
      any_samples ? gbench_json(s.name, points, record)
                  : nlohmann::json({{"context", context}, {"benchmarks", nlohmann::json::array()}}).dump(2) + "\n";
  write_text_atomically(complete ? files.gbench : files.gbench_partial, gbench);
  if (!complete) {
    write_results(files.partial_json, "bokehbench." + s.name, context, doc);
    append_to_store(s, context, doc);
    throw std::runtime_error(fmt::format("interrupted after {} rounds: what was measured is in {} (earlier complete "
                                         "results, if any, are untouched)",
                                         record.round_order.size(), files.partial_json));
  }
  write_results(files.final_json, "bokehbench." + s.name, context, doc);
  append_to_store(s, context, doc);
  std::filesystem::remove(files.partial_json);
  std::filesystem::remove(files.gbench_partial);
  if (s.process_index == 0) {  // one process of several: the run that joins them reads the figures
    if (s.summary) s.summary(doc);
    print_noise(doc["measurement"]);
    print_machine_state(doc["measurement"]);
  }
  fmt::print("wrote {} and {} ({})\n", files.final_json, files.gbench, duration_text(elapsed_s()));
  if (s.plot && !s.plot_script.empty())
    run_plot_script(s.plot_script, files.final_json, (std::filesystem::path(s.plots_dir) / s.name).string());
  return doc;
}

}  // namespace bokeh
