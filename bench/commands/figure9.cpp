// `bokehbench figure9`: FLAG paper Figure 9, frame time vs gather size, naive gather vs FLAG (and
// any other method asked for), on the Vulkan device and as CPU references, measured interleaved.
//
// Its claims are figures drawn from several points: the naive/FLAG ratio at each N and the growth
// exponent of each curve. Each comes with a 95% interval from the rounds' order statistics
// (intervals.hpp), and the run measures until every one is as tight as asked (--target-ratio-pct,
// --target-exponent) or the budget is spent, then says which. Naive and FLAG at one N are visited
// back to back in every round, taking turns going first, so each round gives one paired ratio.
// Where the CPU does the work (the CPU references; the GPU backend on lavapipe) the figures are in
// process CPU time, as `ab` compares there; on a real GPU in wall-clock time (cpu_time_leads).
#include <algorithm>
#include <map>
#include <set>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "commands.hpp"
#include "cpu_baseline.hpp"
#include "gather_pattern.hpp"
#include "intervals.hpp"
#include "method.hpp"
#include "parallel.hpp"
#include "report.hpp"
#include "scene.hpp"
#include "stats.hpp"
#include "store.hpp"
#include "roofline.hpp"
#include "sweep.hpp"

namespace bokeh {

namespace {

struct Figure9Options {
  AxisFlags axes;
  SweepFlags sweep;
  MethodOptionFlags method_options;
  double target_ratio_pct = 5;   // each naive/FLAG ratio's 95% interval within +-this % of it
  double target_exponent = 0.05;  // each growth exponent's 95% interval within +-this
  std::vector<std::string> sweep_choices;  // method options measured at every one of their choices
  std::string cpu_baseline = "filter2d";    // filter2d: OpenCV's cv::filter2D beside FLAG (cpu_baseline.hpp); none
};

// Whether a backend's figures are taken in process CPU time: where the CPU does the work (the CPU
// references, and the GPU backend on a CPU device such as lavapipe) that is the work done, which a
// process competing for the cores inflates far less than wall-clock time. Re-derived from the
// samples of four default runs of 5b9ceb2 on a 2-core VM (two alone, two at once), the 18 figures
// agreed between the six pairs of runs 76 times in CPU time and 64 in wall-clock time (the two
// loaded runs: 16 and 11 of 18), and 38 against 25 settled at the targets. On a real GPU the
// process's CPU time is host overhead: wall-clock there. (`ab` and `compare` choose their clock by the
// same is_cpu_device.)
bool cpu_time_leads(const std::string& backend, const nlohmann::json& device) {
  return backend == "cpu" || is_cpu_device(device);
}

const char* time_name(bool cpu_time) { return cpu_time ? kProcessCpuTime : kWallClockTime; }

// One measured point's samples by round: what every figure below is drawn from.
struct RoundPoint {
  std::string method, variant, backend;  // variant: options off their defaults (sweep.cpp), "" for none
  int n = 0;
  // A CPU baseline (method: its name, e.g. opencv_filter2d), no method: its figures are taken in the time
  // of the GPU points it is set beside (cpu_time_leads of the GPU backend), so a ratio has one time.
  bool baseline = false;
  bool cpu_time_leads = false;                  // its figures are in cpu_ms (cpu_time_leads())
  RoundValues wall_ms, cpu_ms;                   // the frame's wall-clock time; the process CPU time per frame
  std::map<std::string, RoundValues> pass_ms;   // GPU: per pass (Vulkan timestamps)
  std::string precision;                        // of its intermediates ("" for a baseline)
};

using PrecisionsHeld = std::map<std::string, std::set<std::string>>;  // each method's precisions in a run

// A run over several precisions of a method draws each as a curve of its own: the precision joins the
// point's variant ("/precision:f32"), but for the one the method lists first among them (its default
// where run), which keeps the plain variant, the curve naive / FLAG pairs. Without it the curves mixed
// the precisions point by point (and two sizes gave a larger half of one N, which no fit takes).
std::string figure_variant(const std::string& method, const std::string& precision, const std::string& variant,
                           const PrecisionsHeld& held) {
  const auto run = held.find(method);
  if (run == held.end() || run->second.size() < 2) return variant;
  // A results file may name a package this process has not loaded: then the first held, alphabetically.
  std::string plain = *run->second.begin();
  for (const Method* m : known_methods())
    if (m->name == method) {
      const auto first = std::find_if(m->precisions.begin(), m->precisions.end(),
                                      [&](const std::string& x) { return run->second.count(x) > 0; });
      if (first != m->precisions.end()) plain = *first;
    }
  return precision == plain ? variant : variant + "/precision:" + precision;
}

PrecisionsHeld precisions_held(const std::vector<SweepPoint>& points) {
  PrecisionsHeld held;
  for (const auto& p : points) held[p.method->name].insert(p.options.precision);
  return held;
}

// A results document's points, then its baselines (figure9's --cpu-baseline).
std::vector<RoundPoint> round_points(const nlohmann::json& doc, const nlohmann::json& device) {
  PrecisionsHeld held;
  for (const auto& p : doc["points"]) held[p["method"]].insert(p["precision"].get<std::string>());
  std::vector<RoundPoint> out;
  for (const auto& p : doc["points"]) {
    RoundPoint r{p["method"], figure_variant(p["method"], p["precision"], p.value("variant", ""), held), p["backend"],
                 p["N"].get<int>(), false,
                 cpu_time_leads(p["backend"], device), round_values(p), round_values(p, "samples_cpu_ms"), {}};
    for (const auto& [pass, values] : p["samples_pass_ms"].items())
      for (std::size_t s = 0; s < values.size(); ++s) r.pass_ms[pass][p["sample_rounds"][s].get<int>()] = values[s].get<double>();
    r.precision = p["precision"];
    out.push_back(std::move(r));
  }
  for (const auto& b : doc.value("baselines", nlohmann::json::array()))
    out.push_back({b["baseline"], "", b["backend"], b["N"].get<int>(), true, cpu_time_leads("gpu", device),
                   round_values(b), round_values(b, "samples_cpu_ms"), {}});
  return out;
}

std::vector<RoundPoint> round_points(const std::vector<SweepPoint>& points, const runner::RunRecord& record,
                                     const nlohmann::json& device) {
  const PrecisionsHeld held = precisions_held(points);
  std::vector<RoundPoint> out;
  for (std::size_t i = 0; i < points.size(); ++i) {
    const runner::PointRecord& rec = record.points[i];
    if (rec.samples.empty() || !rec.skipped.empty()) continue;
    const SweepPoint& p = points[i];
    RoundPoint r{p.method->name, figure_variant(p.method->name, p.options.precision, p.variant, held), p.backend,
                 p.options.pattern.size_n,
                 false, cpu_time_leads(p.backend, device), {}, {}, {}};
    for (std::size_t s = 0; s < rec.samples.size(); ++s) {
      r.wall_ms[rec.sample_round[s]] = rec.samples[s].frame_ms;
      r.cpu_ms[rec.sample_round[s]] = rec.samples[s].cpu_ms;
    }
    r.precision = p.options.precision;
    out.push_back(std::move(r));
  }
  return out;
}

// lead: each point in its backend's time (cpu_time_leads); wall: wall-clock time for every point.
enum class Metric { lead, wall };

// The figures of one metric with their intervals: per method, variant and backend (registry order,
// GPU first) the medians (with their points' median relative IQR) and the growth exponents over all
// sizes and over the larger half (where fixed costs such as the CoC pass no longer dominate; per pass
// too, on the GPU), and naive/FLAG at each N; `unsettled` lists the ratios and larger-half exponents
// wider than the targets. The CPU baselines' curves and FLAG (GPU) / baseline at each N beside them:
// reported with their intervals, never a target the run measures until.
struct Figures {
  nlohmann::json series = nlohmann::json::array(), naive_over_flag = nlohmann::json::array();
  nlohmann::json baseline_series = nlohmann::json::array(), flag_over_baseline = nlohmann::json::array();
  std::vector<std::string> unsettled;
  std::set<std::string> needed;  // point_key() of every point an unsettled figure is drawn from
  nlohmann::json between_processes;  // widen_by_processes(); null for a run of one process
};

// A figure9 point's identity among the figures' points (one scene and frame size a run).
std::string point_key(const std::string& method, const std::string& variant, const std::string& backend, int n) {
  return fmt::format("{}|{}|{}|{}", method, variant, backend, n);
}

const RoundValues& values_of(const RoundPoint& p, Metric metric) {
  return metric == Metric::lead && p.cpu_time_leads ? p.cpu_ms : p.wall_ms;
}
const char* time_of(const RoundPoint& p, Metric metric) { return time_name(metric == Metric::lead && p.cpu_time_leads); }

// The cores a point kept busy: its process CPU time over its wall-clock time, medians over its rounds.
// lavapipe spreads FLAG over its threads where OpenCV's DFT path keeps to about one core, so a host's
// slow phase moves the two sides of FLAG / baseline differently (results/README.md).
double cores_busy(const RoundPoint& p) {
  std::vector<double> cpu, wall;
  for (const auto& [round, ms] : p.cpu_ms) cpu.push_back(ms);
  for (const auto& [round, ms] : p.wall_ms) wall.push_back(ms);
  return cpu.empty() || wall.empty() ? 0.0 : runner::quantile(cpu, 0.5) / runner::quantile(wall, 0.5);
}

// The growth exponent of `curve` (one point per n) over its points from `from` on: fitted to each
// round's own curve, then the median over rounds. A round's points are measured within seconds of
// each other, so a slow phase of the machine (this VM ran 1.3-1.5x slower for 12 of 27 rounds)
// scales a whole round's curve and leaves its exponent; a fit of per-point medians over all rounds
// mixes the phases, point by point, and measured 1.30 [1.15, 1.99] for naive on lavapipe where the
// per-round fits gave 1.76 [1.70, 1.82] (quartiles). Over the rounds that hold the whole curve
// (points leave the rounds once their figures have settled, runner::Hooks::points_needed).
Interval exponent(const std::vector<const RoundValues*>& curve, const std::vector<double>& n, std::size_t from) {
  const std::vector<double> x(n.begin() + static_cast<std::ptrdiff_t>(from), n.end());
  std::vector<double> per_round;
  for (const auto& [round, unused] : *curve[from]) {
    std::vector<double> y;
    for (std::size_t i = from; i < curve.size(); ++i)
      if (auto it = curve[i]->find(round); it != curve[i]->end() && it->second > 0) y.push_back(it->second);
    if (y.size() == x.size()) per_round.push_back(fit_power_law(x, y).exponent);
  }
  return median_interval(std::move(per_round));
}

// One curve (a method's variant on a backend, points in N order): medians and exponents.
nlohmann::json curve_json(const std::vector<const RoundPoint*>& pts, Metric metric, bool headlines_only) {
  std::vector<double> n, medians, low, high, iqr;
  std::vector<const RoundValues*> curve;
  for (const auto* p : pts) {
    const RoundValues& v = values_of(*p, metric);
    n.push_back(p->n);
    curve.push_back(&v);
    std::vector<double> samples;
    for (const auto& [round, ms] : v) samples.push_back(ms);
    iqr.push_back(runner::distribution(samples).relative_iqr());
    const Interval median = median_interval(v);
    medians.push_back(median.estimate);
    low.push_back(median.low);
    high.push_back(median.high);
  }
  nlohmann::json fits = nlohmann::json::object();
  const std::size_t half = n.size() / 2;
  for (auto [name, from] : {std::pair{"all_sizes", std::size_t{0}}, std::pair{"larger_half", half}}) {
    if (n.size() - from < 2 || (headlines_only && from == 0)) continue;
    const Interval b = exponent(curve, n, from);
    const auto at = static_cast<std::ptrdiff_t>(from);
    const PowerLawFit fit = fit_power_law({n.begin() + at, n.end()}, {medians.begin() + at, medians.end()});
    // exponent: the median of the per-round fits (exponent()); coefficient and r^2: the medians' fit.
    fits[name] = {{"exponent", b.estimate}, {"low", b.low},       {"high", b.high},
                  {"coefficient_ms", fit.coefficient}, {"r_squared", fit.r_squared}, {"points", fit.points},
                  {"N", std::vector<double>(n.begin() + at, n.end())}};
  }
  nlohmann::json pass_fits = nlohmann::json::object();
  if (metric == Metric::lead && !headlines_only && n.size() - half >= 2)  // timestamps: one kind of time
    for (const auto& [pass, unused] : pts.front()->pass_ms) {
      std::vector<const RoundValues*> pass_curve;
      for (const auto* p : pts)
        if (auto it = p->pass_ms.find(pass); it != p->pass_ms.end()) pass_curve.push_back(&it->second);
      if (pass_curve.size() == pts.size()) pass_fits[pass] = interval_json(exponent(pass_curve, n, half));
    }
  std::sort(iqr.begin(), iqr.end());
  return {{"N", n}, {"median_ms", medians}, {"median_ms_low", low}, {"median_ms_high", high},
          {"median_relative_iqr", iqr[iqr.size() / 2]}, {"fits", fits}, {"pass_fits_larger_half", pass_fits}};
}

// `points` with only the rounds process `process` measured (round_process: each round's process).
std::vector<RoundPoint> rounds_of_process(const std::vector<RoundPoint>& points, const std::vector<int>& round_process,
                                          int process) {
  const auto keep = [&](const RoundValues& values) {
    RoundValues out;
    for (const auto& [round, x] : values)
      if (round < static_cast<int>(round_process.size()) && round_process[round] == process) out[round] = x;
    return out;
  };
  std::vector<RoundPoint> out;
  for (const RoundPoint& p : points) {
    RoundPoint q = p;
    q.wall_ms = keep(p.wall_ms);
    q.cpu_ms = keep(p.cpu_ms);
    for (auto& [pass, values] : q.pass_ms) values = keep(values);
    if (!q.wall_ms.empty()) out.push_back(std::move(q));
  }
  return out;
}

// A figure with an interval, by name, where `figures` holds it: a ratio (in logs, so that its spread
// is relative) or an exponent.
struct FigureAt {
  std::string backend;
  bool ratio = false, headline = false;  // headline: naive/FLAG or a larger-half exponent
  nlohmann::json* at = nullptr;          // estimate (under `key`), low, high
  const char* key = "exponent";          // naive_over_flag, flag_over_baseline or exponent
  double estimate() const { return (*at)[key].get<double>(); }
  double scaled(double x) const { return ratio ? std::log(x) : x; }
  double unscaled(double x) const { return ratio ? std::exp(x) : x; }
};

std::map<std::string, FigureAt> figures_at(Figures& figures) {
  std::map<std::string, FigureAt> out;
  for (auto& r : figures.naive_over_flag)
    out[fmt::format("naive/FLAG {} N={}", r["backend"].get<std::string>(), r["N"].get<int>())] = {
        r["backend"], true, true, &r, "naive_over_flag"};
  // Widened with the rest but not pooled into the spread: no headline, so a run's spread stays what it was.
  for (auto& r : figures.flag_over_baseline)
    out[fmt::format("FLAG/{} {} N={}", r["baseline"].get<std::string>(), r["backend"].get<std::string>(), r["N"].get<int>())] = {
        r["backend"], true, false, &r, "flag_over_baseline"};
  for (auto& curve : figures.series)
    for (const char* fit : {"larger_half", "all_sizes"})
      if (curve["fits"].contains(fit))
        out[fmt::format("{}{} {} {}", curve["method"].get<std::string>(), curve["variant"].get<std::string>(),
                        curve["backend"].get<std::string>(), fit)] = {curve["backend"], false, fit == std::string("larger_half"),
                                                                      &curve["fits"][fit]};
  return out;
}

Figures figures(const std::vector<RoundPoint>& points, Metric metric, double target_ratio, double target_exponent,
                bool headlines_only = false, const std::vector<int>& round_process = {});

// A run measured by several processes (processes.hpp): each figure's interval widened by how far the
// processes' own estimates of it (each from its rounds alone) spread, against the standard errors
// their intervals imply (half-width / 1.96). The ratio of the two, squared, is pooled over a backend's
// headline figures (ratios and larger-half exponents; they share the processes, so the offset is
// judged on many figures, not one), with degrees of freedom the figures times (processes - 1). Each
// figure's interval then has each side at least t * lambda * its standard error over the processes
// (mean of their variances / processes), t Student's 97.5% quantile: what a run-level offset the
// processes drew adds, measured in this run. lambda near 1: the processes agreed as their rounds
// predicted (the interval grows by t / 1.96 at most); above: they differed by more. Returns the pooled
// spread per backend.
nlohmann::json widen_by_processes(Figures& whole_run, const std::vector<RoundPoint>& points,
                                  const std::vector<int>& round_process, Metric metric, bool headlines_only) {
  const int processes = round_process.empty() ? 0 : *std::max_element(round_process.begin(), round_process.end()) + 1;
  if (processes < 2) return nlohmann::json();
  std::vector<Figures> per_process;
  std::vector<std::map<std::string, FigureAt>> per_process_at;
  per_process.reserve(static_cast<std::size_t>(processes));
  for (int k = 0; k < processes; ++k) {
    per_process.push_back(figures(rounds_of_process(points, round_process, k), metric, 1, 1, headlines_only));
    per_process_at.push_back(figures_at(per_process.back()));
  }
  struct Spread {
    double weighted_z2 = 0;
    int figures = 0, degrees_of_freedom = 0;
  };
  struct Estimates {
    std::vector<double> estimates;  // scaled
    double mean_variance = 0;
  };
  std::map<std::string, Spread> by_backend;
  std::map<std::string, Estimates> by_figure;
  for (auto& [name, whole] : figures_at(whole_run)) {
    Estimates e;
    for (auto& at : per_process_at) {
      const auto it = at.find(name);
      if (it == at.end()) continue;
      const FigureAt& f = it->second;
      const double se = (f.scaled((*f.at)["high"].get<double>()) - f.scaled((*f.at)["low"].get<double>())) / (2 * 1.96);
      if (!(se > 0) || !std::isfinite(se)) continue;
      e.estimates.push_back(f.scaled(f.estimate()));
      e.mean_variance += se * se;
    }
    const auto n = static_cast<double>(e.estimates.size());
    if (n < 2) continue;
    e.mean_variance /= n;
    if (whole.headline) {
      double mean = 0, ss = 0;
      for (double x : e.estimates) mean += x / n;
      for (double x : e.estimates) ss += (x - mean) * (x - mean);
      Spread& s = by_backend[whole.backend];
      s.weighted_z2 += ss / e.mean_variance;  // (n - 1) * sample variance / expected variance
      s.degrees_of_freedom += static_cast<int>(n) - 1;
      ++s.figures;
    }
    by_figure[name] = std::move(e);
  }
  nlohmann::json out = nlohmann::json::object();
  for (auto& [name, whole] : figures_at(whole_run)) {
    const auto e = by_figure.find(name);
    const auto s = by_backend.find(whole.backend);
    if (e == by_figure.end() || s == by_backend.end() || !(whole.estimate() > 0 || !whole.ratio)) continue;
    const double lambda = std::sqrt(s->second.weighted_z2 / s->second.degrees_of_freedom);
    const double half_width = student_t_975(s->second.degrees_of_freedom) * lambda *
                              std::sqrt(e->second.mean_variance / static_cast<double>(e->second.estimates.size()));
    nlohmann::json& f = *whole.at;
    const double centre = whole.scaled(whole.estimate());
    f["low"] = std::min(f["low"].get<double>(), whole.unscaled(centre - half_width));
    f["high"] = std::max(f["high"].get<double>(), whole.unscaled(centre + half_width));
    std::vector<double> estimates;
    for (double x : e->second.estimates) estimates.push_back(whole.unscaled(x));
    f["process_estimates"] = estimates;
  }
  for (const auto& [backend, s] : by_backend)
    out[backend] = {{"figures", s.figures},
                    {"degrees_of_freedom", s.degrees_of_freedom},
                    {"spread_over_rounds", std::sqrt(s.weighted_z2 / s.degrees_of_freedom)},
                    {"t", student_t_975(s.degrees_of_freedom)}};
  return out;
}

// The figures of one metric with their intervals (see Figures); with `round_process` (a run of
// several processes) widened by the spread between them (widen_by_processes). `headlines_only`: the
// ratios and larger-half exponents alone (what the stopping rule reads).
Figures figures(const std::vector<RoundPoint>& points, Metric metric, double target_ratio, double target_exponent,
                bool headlines_only, const std::vector<int>& round_process) {
  Figures out;
  // The curve of the points `in` selects, in N order, with their backend and time; null when none.
  const auto curve_of = [&](const auto& in) {
    std::vector<const RoundPoint*> pts;
    for (const auto& p : points)
      if (in(p)) pts.push_back(&p);
    if (pts.empty()) return nlohmann::json();
    std::sort(pts.begin(), pts.end(), [](auto* a, auto* b) { return a->n < b->n; });
    nlohmann::json curve = curve_json(pts, metric, headlines_only);
    curve.update({{"backend", pts.front()->backend}, {"time", time_of(*pts.front(), metric)}});
    if (!pts.front()->precision.empty()) curve["precision"] = pts.front()->precision;  // one a curve
    return curve;
  };
  std::set<std::string> variants;
  for (const auto& p : points) variants.insert(p.variant);
  for (const Method* method : known_methods())
    for (const std::string& variant : variants)
      for (const char* backend : {"gpu", "cpu"}) {
        nlohmann::json curve = curve_of([&](const RoundPoint& p) {
          return !p.baseline && p.method == method->name && p.variant == variant && p.backend == backend;
        });
        if (curve.is_null()) continue;
        curve.update({{"method", method->name}, {"variant", variant}});
        out.series.push_back(std::move(curve));
      }
  // Each CPU baseline's curve, in the time of the GPU points it is set beside.
  std::set<std::string> baselines;
  for (const auto& p : points)
    if (p.baseline) baselines.insert(p.method);
  for (const std::string& name : baselines) {
    nlohmann::json curve = curve_of([&](const RoundPoint& p) { return p.baseline && p.method == name; });
    curve["baseline"] = name;
    out.baseline_series.push_back(std::move(curve));
  }
  // The paper's comparison: both at their defaults; and FLAG on the GPU against each CPU baseline at its N.
  // Each over the rounds that hold both (a point leaves the rounds once its figures have settled).
  for (const auto& a : points) {
    if (a.baseline || a.method != "naive" || !a.variant.empty()) continue;
    for (const auto& b : points) {
      if (b.baseline || b.method != "flag" || !b.variant.empty() || b.backend != a.backend || b.n != a.n) continue;
      const Interval r = paired_ratio_interval(values_of(a, metric), values_of(b, metric)).value_or(Interval{});
      out.naive_over_flag.push_back({{"N", a.n}, {"backend", a.backend}, {"time", time_of(a, metric)},
                                     {"naive_over_flag", r.estimate}, {"low", r.low}, {"high", r.high}});
    }
  }
  for (const auto& a : points) {
    if (a.baseline || a.method != "flag" || !a.variant.empty() || a.backend != "gpu") continue;
    for (const auto& b : points) {
      if (!b.baseline || b.n != a.n) continue;
      const Interval r = paired_ratio_interval(values_of(a, metric), values_of(b, metric)).value_or(Interval{});
      out.flag_over_baseline.push_back({{"N", a.n}, {"backend", a.backend}, {"baseline", b.method},
                                        {"time", time_of(a, metric)}, {"flag_over_baseline", r.estimate},
                                        {"low", r.low}, {"high", r.high}, {"flag_cores_busy", cores_busy(a)},
                                        {"baseline_cores_busy", cores_busy(b)}});
    }
  }
  // In N order whatever the order of the points (merged shards list theirs shard by shard).
  std::sort(out.flag_over_baseline.begin(), out.flag_over_baseline.end(), [](const auto& x, const auto& y) {
    return std::pair{x["baseline"].template get<std::string>(), x["N"].template get<int>()} <
           std::pair{y["baseline"].template get<std::string>(), y["N"].template get<int>()};
  });
  out.between_processes = widen_by_processes(out, points, round_process, metric, headlines_only);
  // Each figure's repeat-run interval, and which are wider than their targets (and the points they need).
  for (auto& curve : out.series)
    for (auto& [name, f] : curve["fits"].items()) {
      const Interval repeat = repeat_run({f["exponent"], f["low"], f["high"]});
      f["repeat_low"] = repeat.low;
      f["repeat_high"] = repeat.high;
      const double half_width = (f["high"].get<double>() - f["low"].get<double>()) / 2;
      if (name != "larger_half" || half_width <= target_exponent) continue;
      out.unsettled.push_back(fmt::format("{}{} {} exponent {:.2f} +-{:.2f}", curve["method"].get<std::string>(),
                                          curve["variant"].get<std::string>(), curve["backend"].get<std::string>(),
                                          f["exponent"].get<double>(), half_width));
      for (int n : f["N"].get<std::vector<int>>())
        out.needed.insert(point_key(curve["method"], curve["variant"], curve["backend"], n));
    }
  for (auto& r : out.flag_over_baseline) {  // reported, not a target
    const Interval repeat = repeat_run({r["flag_over_baseline"], r["low"], r["high"]});
    r.update({{"repeat_low", repeat.low}, {"repeat_high", repeat.high}});
  }
  for (auto& r : out.naive_over_flag) {
    const Interval interval{r["naive_over_flag"], r["low"], r["high"]};
    const Interval repeat = repeat_run(interval);
    const bool settled = interval.relative_half_width() <= target_ratio;
    r.update({{"repeat_low", repeat.low}, {"repeat_high", repeat.high}, {"settled", settled}});
    if (settled) continue;
    out.unsettled.push_back(fmt::format("naive/FLAG {} N={} {:.2f} +-{:.1f}%", r["backend"].get<std::string>(),
                                        r["N"].get<int>(), interval.estimate, 100 * interval.relative_half_width()));
    for (const char* method : {"naive", "flag"})
      out.needed.insert(point_key(method, "", r["backend"], r["N"]));
  }
  return out;
}

// The frame clips the pattern (disc_share_in_frame): at 800x600, k = 2, 10% of the largest disc's
// samples fall outside the frame at N = 81 and 18% at N = 153, so a method whose cost is its taps
// grows ~0.15 slower over the larger half than the same method with no frame edge. Each larger-half
// fit gets its exponent without that ("larger_half_unclipped": the fit of t(N) / share(N), the
// exponent minus the share's own), what the paper's N^2 is about. FLAG's passes clip along one axis
// each, less than the 2D pattern, so for FLAG this overstates the correction (its raw fit is the one
// to read).
void add_unclipped_fits(nlohmann::json& doc) {
  const auto& config = doc["config"];
  const int width_px = config["width_px"], height_px = config["height_px"], spacing_px = config["spacing_px"];
  auto shares_at = [&](const std::vector<double>& n) {
    std::vector<double> shares;
    for (double x : n) shares.push_back(disc_share_in_frame({static_cast<int>(x), spacing_px}, width_px, height_px));
    return shares;
  };
  auto exponent_of_share = [&](const std::vector<double>& n) { return fit_power_law(n, shares_at(n)).exponent; };
  for (nlohmann::json* series : {&doc["series"], &doc["headlines"]["wall_time"]["series"]})
    for (auto& curve : *series) {
      auto& fits = curve["fits"];
      if (!fits.contains("larger_half")) continue;
      const auto& fit = fits["larger_half"];
      const double clipping = exponent_of_share(fit["N"].get<std::vector<double>>());
      nlohmann::json unclipped = {{"clipping_exponent", clipping}};
      for (const char* key : {"exponent", "low", "high", "repeat_low", "repeat_high"})
        unclipped[key] = fit[key].get<double>() - clipping;
      fits["larger_half_unclipped"] = std::move(unclipped);
    }
  const std::vector<int> sizes = config["sizes"];
  const std::vector<double> n(sizes.begin(), sizes.end());
  doc["frame_clipping"] = {
      {"N", sizes},
      {"share_in_frame", shares_at(n)},
      {"why", "the share of the pattern's largest disc that lands inside the frame, over all its pixels: every "
              "gather skips samples outside the frame, so a tap-bound method's larger-half exponent comes out "
              "below its exponent without frame edges (fits.larger_half_unclipped) by this share's exponent"}};
  if (const std::vector<double> larger(n.begin() + static_cast<std::ptrdiff_t>(n.size() / 2), n.end()); larger.size() >= 2)
    doc["frame_clipping"]["larger_half_exponent"] = exponent_of_share(larger);
}

// The document's figures, each backend's in its time (cpu_time_leads), and the same in wall-clock time
// (what a user waits for). The probes' drift says how steady the machine was.
void derive(nlohmann::json& doc, double target_ratio, double target_exponent) {
  const std::vector<RoundPoint> points = round_points(doc, doc.at("context").value("device", nlohmann::json()));
  const std::vector<int> round_process = doc["measurement"].value("round_process", std::vector<int>{});
  const Figures lead = figures(points, Metric::lead, target_ratio, target_exponent, false, round_process);
  const Figures wall = figures(points, Metric::wall, target_ratio, target_exponent, false, round_process);
  doc["series"] = lead.series;
  doc["naive_over_flag"] = lead.naive_over_flag;
  doc["headlines"] = {
      {"interval", "95%, distribution-free interval of a median from the rounds' order statistics (exact for "
                   "independent rounds); ratios are the median over rounds of naive / FLAG measured back to back in "
                   "the same round, exponents the median over rounds of each round's own fit"},
      {"repeat_interval", "repeat_low/repeat_high: where a repeat run on this machine would put its estimate, at 95% "
                          "(the interval widened by sqrt(2)); a repeat run's estimate falls in the plain 95% interval "
                          "only about 83% of the time. Where this machine's earlier runs of the same points (the "
                          "results store; measurement.run_to_run: the spread about each commit's mean, pooled, from "
                          "min_degrees_of_freedom on, the figure's own or its family's pooled over a backend's figures of one "
                          "kind, whichever reaches wider: run_to_run_from) spread wider than this run's interval, each "
                          "side is sqrt(2) * run_to_run_t * run_to_run_sd instead (t: Student's 97.5% quantile for its "
                          "degrees of freedom; "
                          "history::widen_repeat_intervals): a run's own rounds cannot show the offset between runs"},
      {"targets", {{"ratio_relative_half_width", target_ratio}, {"exponent_half_width", target_exponent}}},
      {"settled", lead.unsettled.empty()},
      {"unsettled", lead.unsettled},
      {"stop_reason", doc["measurement"]["stop_reason"]},
      {"probe_drift", probe_drift(doc["measurement"])},
      {"wall_time", {{"series", wall.series}, {"naive_over_flag", wall.naive_over_flag}, {"unsettled", wall.unsettled}}}};
  if (doc.contains("baselines")) {  // --cpu-baseline: measured, or skipped with the reason (skipped_baselines)
    doc["baseline_series"] = lead.baseline_series;
    doc["flag_over_baseline"] = lead.flag_over_baseline;
    doc["headlines"]["wall_time"]["baseline_series"] = wall.baseline_series;
    doc["headlines"]["wall_time"]["flag_over_baseline"] = wall.flag_over_baseline;
  }
  if (!lead.between_processes.is_null())
    doc["headlines"]["between_processes"] = {
        {"why", "the run was measured by several processes one after another (measurement.round_process): each "
                "figure's interval has each side at least t * spread_over_rounds * its standard error over the "
                "processes, spread_over_rounds the processes' estimates' spread against what their own intervals "
                "imply, pooled over a backend's headline figures (Student's t for its degrees of freedom): a run-level "
                "offset that rounds within one process share and cannot show (processes.hpp)"},
        {"backends", lead.between_processes}};
  add_unclipped_fits(doc);
  history::widen_repeat_intervals(doc);
}

// "1.23 [1.20, 1.26]": an exponent with the 95% interval in `i` (its low and high).
std::string fit_text(double estimate, const nlohmann::json& i) {
  return fmt::format("{:.2f} [{:.2f}, {:.2f}]", estimate, i["low"].get<double>(), i["high"].get<double>());
}

// What the repeat-run intervals above rest on: this run's rounds alone, or also the spread of the
// machine's earlier runs of this configuration.
void print_repeat_basis(const nlohmann::json& measurement) {
  if (!measurement.contains("run_to_run")) {
    fmt::print("a repeat run: from this run's rounds alone (no results store to measure how far runs differ)\n");
    return;
  }
  const nlohmann::json& spread = measurement["run_to_run"];
  const int needed = spread.value("min_degrees_of_freedom", history::kRunToRunMinDegreesOfFreedom);
  nlohmann::json most = {{"degrees_of_freedom", 0}};  // the figures share their runs; the best-measured one
  for (const auto& figure : spread.value("figures", nlohmann::json::object()))
    if (figure["degrees_of_freedom"] > most["degrees_of_freedom"]) most = figure;
  std::vector<std::string> families;
  const nlohmann::json by_family = spread.value("families", nlohmann::json::object());
  for (const auto& [family, f] : by_family.items())
    if (f["degrees_of_freedom"].get<int>() >= needed)
      families.push_back(fmt::format("{} {:.2g}{} ({} degrees of freedom)", family, f["sd"].get<double>(),
                                     family.rfind("naive_over_flag", 0) == 0 ? " in logs" : "",
                                     f["degrees_of_freedom"].get<int>()));
  const int degrees_of_freedom = most["degrees_of_freedom"];
  if (degrees_of_freedom >= needed || !families.empty()) {
    fmt::print("a repeat run: where this machine's earlier runs of this configuration ({} in the results store) spread "
               "their estimates wider than this run's interval, the repeat-run interval is sqrt(2) * t of their "
               "standard deviation about each commit's mean (t: Student's 97.5% for its degrees of freedom: fewer, "
               "wider), each figure's own ({} degrees of freedom at most) or its family's pooled, whichever is "
               "wider: {}\n",
               spread.value("earlier_runs", 0), degrees_of_freedom, families.empty() ? "none" : fmt::format("{}", fmt::join(families, "; ")));
    return;
  }
  fmt::print("a repeat run: from this run's rounds alone (earlier runs of this configuration in the results store: {}; "
             "degrees of freedom of their spread about each commit's mean: {} of the {} needed, as from 2 runs of one "
             "commit pooled over a family of figures, to measure how far runs differ). Runs on a shared machine can "
             "differ by more than their rounds show: expect some repeat-run estimates outside these intervals\n",
             spread.value("earlier_runs", 0), degrees_of_freedom, needed);
}

// FLAG on the device over each CPU baseline at each N (--cpu-baseline), from same-round pairs as
// naive / FLAG, with the baseline's own frame time; or why the baseline was not measured.
void print_baselines(const nlohmann::json& doc) {
  std::set<std::string> reasons;
  for (const auto& b : doc.value("skipped_baselines", nlohmann::json::array()))
    reasons.insert(fmt::format("{}: {}", b.value("label", b["baseline"].get<std::string>()), b["reason"].get<std::string>()));
  for (const auto& reason : reasons) fmt::print("CPU baseline skipped, {}\n", reason);
  if (!doc.contains("flag_over_baseline") || doc["baselines"].empty()) return;
  const nlohmann::json& device = doc["context"]["device"];
  const std::string on = device.is_object() ? device.value("name", "the GPU") : "the GPU";
  const auto& wall = doc["headlines"]["wall_time"]["flag_over_baseline"];
  for (std::size_t i = 0; i < doc["flag_over_baseline"].size(); ++i) {
    const auto& r = doc["flag_over_baseline"][i];
    const int n = r["N"].get<int>();
    const auto b = std::find_if(doc["baselines"].begin(), doc["baselines"].end(),
                                [&](const nlohmann::json& x) { return x["baseline"] == r["baseline"] && x["N"] == n; });
    const auto curve = std::find_if(doc["baseline_series"].begin(), doc["baseline_series"].end(),
                                    [&](const nlohmann::json& c) { return c["baseline"] == r["baseline"]; });
    if (b == doc["baselines"].end() || curve == doc["baseline_series"].end()) continue;
    const auto& ns = (*curve)["N"];
    const auto at = static_cast<std::size_t>(std::find(ns.begin(), ns.end(), n) - ns.begin());
    fmt::print("FLAG on {} / {} (CPU, {} threads) at N={:<3}: {:.2f}x [{:.2f}, {:.2f}]  a repeat run: [{:.2f}, {:.2f}]  "
               "({} {:.2f} ms [{:.2f}, {:.2f}] in {})",
               on, (*b)["label"].get<std::string>(), (*b)["threads"].get<int>(), n,
               r["flag_over_baseline"].get<double>(), r["low"].get<double>(), r["high"].get<double>(),
               r["repeat_low"].get<double>(), r["repeat_high"].get<double>(), (*b)["label"].get<std::string>(),
               (*curve)["median_ms"][at].get<double>(), (*curve)["median_ms_low"][at].get<double>(),
               (*curve)["median_ms_high"][at].get<double>(), r["time"].get<std::string>());
    if (const auto& w = wall[i]; r["time"] == time_name(true))
      fmt::print("  wall-clock: {:.2f}x [{:.2f}, {:.2f}]", w["flag_over_baseline"].get<double>(), w["low"].get<double>(),
                 w["high"].get<double>());
    if (r.contains("flag_cores_busy"))
      fmt::print("  cores busy: FLAG {:.2f}, {} {:.2f}", r["flag_cores_busy"].get<double>(),
                 (*b)["label"].get<std::string>(), r["baseline_cores_busy"].get<double>());
    fmt::print("\n");
  }
  fmt::print("  (above 1: FLAG is slower than the baseline, which filters the colour with one fixed disc, no CoC; cores "
             "busy: process CPU time over wall-clock time, medians over the rounds)\n");
}

// How far the run's processes put the figures apart, against what their rounds imply.
void print_between_processes(const nlohmann::json& headlines) {
  if (!headlines.contains("between_processes")) {
    fmt::print("one process measured every round: its intervals cannot show an offset between processes (runs), "
               "which --processes 2 or more measures\n");
    return;
  }
  std::vector<std::string> spreads;
  for (const auto& [backend, s] : headlines["between_processes"]["backends"].items())
    spreads.push_back(fmt::format("{} {:.2f} ({} figures, {} degrees of freedom, t = {:.2f})", backend,
                                  s["spread_over_rounds"].get<double>(), s["figures"].get<int>(),
                                  s["degrees_of_freedom"].get<int>(), s["t"].get<double>()));
  if (spreads.empty()) {  // e.g. --methods flag at two sizes: no naive/FLAG ratio, no larger-half fit
    fmt::print("between processes: no headline figure (naive/FLAG, a larger-half exponent of 2 or more sizes) to "
               "measure their spread on, so no interval is widened by it\n");
    return;
  }
  fmt::print("between processes: their estimates spread {} times what their own rounds imply; every interval above "
             "has each side at least t times that times its standard error over the processes (above 1: an offset "
             "between processes that one process's rounds do not show)\n",
             fmt::join(spreads, ", "));
}

void print_summary(const nlohmann::json& doc) {
  std::map<std::string, std::set<std::string>> backends;  // the time figures are in -> the backends in it
  for (const auto& series : doc["series"]) backends[series.value("time", time_name(false))].insert(series["backend"]);
  std::vector<std::string> times;
  for (const auto& [time, in] : backends) times.push_back(fmt::format("{} ({})", time, fmt::join(in, ", ")));
  fmt::print("\nfigures in {}", fmt::join(times, "; "));
  if (backends.count(time_name(true)))
    fmt::print(": the work done on the cores, which a competing process inflates less than wall-clock time (each "
               "ratio's wall-clock figure follows it; headlines.wall_time has them all)");
  fmt::print("\n{:<10} {:<4} {:>22} {:>22} {:>22}   (growth exponent b of t ~ N^b, 95% intervals)\n", "method",
             "on", "larger half of N", "same, unclipped", "all N");
  for (const auto& series : doc["series"]) {
    const auto& f = series["fits"];
    auto exponent = [&](const char* which) {
      return f.contains(which) ? fit_text(f[which]["exponent"].get<double>(), f[which]) : std::string("-");
    };
    fmt::print("{:<10} {:<4} {:>22} {:>22} {:>22}\n",
               series["method"].get<std::string>() + series["variant"].get<std::string>(),
               series["backend"].get<std::string>(), exponent("larger_half"), exponent("larger_half_unclipped"),
               exponent("all_sizes"));
    for (const auto& [pass, b] : series["pass_fits_larger_half"].items())
      fmt::print("{:>15} pass {:<12} {:>22}\n", "", pass, fit_text(b["estimate"].get<double>(), b));
  }
  if (const auto& c = doc["frame_clipping"]; c.contains("larger_half_exponent"))
    fmt::print("unclipped: the frame clips the pattern (share of its disc inside: {:.2f} at N={} .. {:.2f} at N={}, "
               "exponent {:+.2f} over the larger half); a tap-bound method without frame edges grows that much "
               "faster (FLAG's passes clip less: overstated there)\n",
               c["share_in_frame"].front().get<double>(), c["N"].front().get<int>(),
               c["share_in_frame"].back().get<double>(), c["N"].back().get<int>(),
               c["larger_half_exponent"].get<double>());
  const auto& wall_ratios = doc["headlines"]["wall_time"]["naive_over_flag"];
  for (std::size_t i = 0; i < doc["naive_over_flag"].size(); ++i) {
    const auto& r = doc["naive_over_flag"][i];
    fmt::print("naive / FLAG at N={:<3} ({}): {:.2f}x [{:.2f}, {:.2f}]  a repeat run: [{:.2f}, {:.2f}]",
               r["N"].get<int>(), r["backend"].get<std::string>(), r["naive_over_flag"].get<double>(),
               r["low"].get<double>(), r["high"].get<double>(), r["repeat_low"].get<double>(),
               r["repeat_high"].get<double>());
    if (const auto& w = wall_ratios[i]; r.value("time", "") == time_name(true))
      fmt::print("  wall-clock: {:.2f}x [{:.2f}, {:.2f}]", w["naive_over_flag"].get<double>(), w["low"].get<double>(),
                 w["high"].get<double>());
    fmt::print("\n");
  }
  print_baselines(doc);
  print_between_processes(doc["headlines"]);
  print_repeat_basis(doc["measurement"]);
  // The ratios move with the machine's memory speed (results/README.md, "Do two runs agree?"): say what it was.
  if (const auto& limits = doc["measurement"].value("limits", nlohmann::json::object());
      limits.contains("gpu_copy_gb_per_s") || limits.contains("cpu_copy_gb_per_s")) {
    std::vector<std::string> rates;
    for (const auto& [probe, name] : {std::pair{"gpu_copy_gb_per_s", "GPU"}, std::pair{"cpu_copy_gb_per_s", "CPU"}})
      if (limits.contains(probe)) rates.push_back(fmt::format("{} copy {:.1f} GB/s", name, limits[probe].get<double>()));
    fmt::print("memory in this run: {} (each probe's median over the rounds). FLAG's layers are memory traffic where "
               "naive's gather mostly hits cache, so a run in a slower memory phase can give lower naive/FLAG ratios: "
               "compare runs at like rates\n",
               fmt::join(rates, ", "));
  }
  const auto& h = doc["headlines"];
  const auto& t = h["targets"];
  const std::string targets = fmt::format("every ratio within +-{:.0f}%, every larger-half exponent within +-{:.2f}",
                                          100 * t["ratio_relative_half_width"].get<double>(),
                                          t["exponent_half_width"].get<double>());
  const std::string stop = h["stop_reason"].get<std::string>();
  if (h["settled"].get<bool>()) {
    fmt::print("settled after {} rounds: {} ({})\n", doc["measurement"]["rounds"].get<int>(), targets, stop);
    return;
  }
  const std::string drift = probe_drift_text(h["probe_drift"]);
  // The rounds stop when the figures so far settle (a later process judging the earlier processes'
  // rounds with its own); the whole run's can still come out wider (rounds measured after a point left).
  const bool widened = runner::stopped_settled(stop);
  fmt::print("NOT SETTLED ({} after {} rounds): the machine was too noisy for these figures at the targets ({}):\n",
             widened ? "the rounds stopped when their figures settled; the whole run's, widened by the spread between "
                       "its processes, did not"
                     : stop,
             doc["measurement"]["rounds"].get<int>(), targets);
  for (const auto& u : h["unsettled"]) fmt::print("  {}\n", u.get<std::string>());
  fmt::print("  probes drifted (max - min over median, per round): {}; a longer --budget-s or a quieter machine "
             "narrows them\n", drift.empty() ? "not measured" : drift);
}

// One OpenCV filter2D baseline (cpu_baseline.hpp) per scene, frame size and pattern the sweep's GPU points
// have (the comparison is FLAG on the device), visited with the GPU points of its N: taken from the points
// this shard measures, so a shard's baselines are those its FLAG points are compared with. Skipped with the
// reason in a build without OpenCV.
std::vector<SweepSettings::Baseline> filter2d_baselines(const std::vector<SweepPoint>& points, const SweepSettings& s) {
  const int threads = s.cpu_threads > 0 ? s.cpu_threads : default_cpu_threads();  // as the CPU references
  std::vector<SweepSettings::Baseline> out;
  std::set<std::string> ids;
  for (const auto& p : points) {
    if (p.backend != "gpu") continue;
    const GatherPattern& pattern = p.options.pattern;
    SweepSettings::Baseline b;
    b.id = fmt::format("{}/cpu/{}/{}/N:{}/k:{}", baseline::kFilter2dName, p.scene, p.resolution.text(), pattern.size_n,
                       pattern.spacing_px);
    if (!ids.insert(b.id).second) continue;
    const int side_px = baseline::disc_kernel_side_px(pattern);
    b.identity = {{"id", b.id},
                  {"baseline", baseline::kFilter2dName},
                  {"label", "OpenCV filter2D"},
                  {"description", "cv::filter2D of the scene's colour (RGB f32) with one fixed kernel, the pattern's "
                                  "largest disc: the taps FLAG's gather takes at its largest radius, 1/area each, laid "
                                  "out as one kernel_px x kernel_px kernel; no CoC, so no error is measured. Border: "
                                  "constant 0, weights not renormalised (the exact reference's convention)"},
                  {"backend", "cpu"},
                  {"scene", p.scene},
                  {"width_px", p.resolution.width_px},
                  {"height_px", p.resolution.height_px},
                  {"N", pattern.size_n},
                  {"k", pattern.spacing_px},
                  {"max_radius_px", pattern.max_radius_px()},
                  {"kernel_px", side_px},
                  {"kernel_taps", discrete_disc_area(pattern.max_radius_px(), pattern)},
                  {"threads", threads},
                  {"opencv", baseline::opencv_version()}};
    b.scene = p.scene;
    b.resolution = p.resolution;
    b.skip = baseline::unavailable_reason();
    b.visit_together = s.visit_together(p);
    b.visit_block = s.visit_block(p);
    b.prepare = [pattern, threads](const Scene& scene) { return baseline::filter2d_target(scene.color, pattern, threads); };
    out.push_back(std::move(b));
  }
  return out;
}

void figure9(Figure9Options& o) {
  o.axes.resolve(&o.sweep);
  if (o.axes.quick && o.sweep.processes_option->count() == 0) o.sweep.processes = 1;  // a check of the mechanics
  if (o.axes.methods.empty()) o.axes.methods = {"naive", "flag"};  // the paper's figure
  if (o.axes.methods == std::vector<std::string>{"all"}) o.axes.methods = default_sweep_methods();
  if (!(o.target_ratio_pct > 0) || !(o.target_exponent > 0))
    throw std::invalid_argument("--target-ratio-pct and --target-exponent must be > 0");
  Axes axes;
  axes.methods = o.axes.methods;
  axes.backends = o.axes.backends;
  axes.scenes = o.axes.scenes;
  axes.resolutions = o.axes.frame_sizes();
  axes.patterns = o.axes.patterns();
  axes.precisions = o.axes.precisions;
  axes.option_values = o.method_options.values_for(axes.methods);
  axes.sweep_choices = o.sweep_choices;
  axes.apertures = o.axes.aperture_shapes();  // one: the figures pair points by method and N alone
  std::vector<int> sizes;
  for (const auto& p : axes.patterns) {
    // The figures pair points and fit curves by N (the paper's axis): two spacings of one N would share a
    // point of every curve.
    if (std::find(sizes.begin(), sizes.end(), p.size_n) != sizes.end())
      throw std::invalid_argument(fmt::format("--sizes: N = {} is given with two spacings; figure9 draws frame time "
                                              "against N, so give each N once (run other spacings apart)",
                                              p.size_n));
    sizes.push_back(p.size_n);
  }
  const double target_ratio = o.target_ratio_pct / 100, target_exponent = o.target_exponent;

  SweepSettings s = o.sweep.settings("figure9", "plot_figure9.py");
  s.policy.max_samples = 100;  // the headline targets and the budget end the run, not a point's own IQR
  s.config = {{"scene", axes.scenes.front()},
              {"width_px", axes.resolutions.front().width_px},
              {"height_px", axes.resolutions.front().height_px},
              {"spacing_px", o.axes.spacing_px},
              {"sizes", sizes},
              {"patterns", o.axes.sizes},
              {"methods", axes.methods},
              {"backends", axes.backends},
              {"precisions", axes.precisions},
              {"aperture", o.axes.apertures.front()},
              {"quick", o.axes.quick},
              {"target_ratio_pct", o.target_ratio_pct},
              {"cpu_baseline", o.cpu_baseline},
              {"target_exponent", o.target_exponent},
              {"scene_coc", "lens f-stop set per N so the scene's largest CoC radius equals the pattern's max radius"},
              {"error", "each point's output against the exact scatter references (energy_sum: the plain sum naive and "
                        "FLAG approximate; depth_ordered: composited front to back) of the same scene and CoC"}};
  o.sweep.apply_shard(axes);
  const std::vector<SweepPoint> points = expand(axes);
  // The methods at one N (and backend) side by side in every round: their ratio is paired.
  s.visit_together = [](const SweepPoint& p) {
    return fmt::format("{}/{}/{}/{}/{}", p.backend, p.scene, p.resolution.text(), p.options.pattern.size_n, p.max_coc_px);
  };
  // Every N of one backend one after another: a round's curve, to which its exponent is fitted, is then
  // measured within seconds rather than across the whole round, which on a drifting VM spans phases.
  s.visit_block = [](const SweepPoint& p) { return fmt::format("{}/{}/{}", p.backend, p.scene, p.resolution.text()); };
  // A point leaves the rounds once every ratio and exponent it feeds is within its target: naive's
  // points (the costliest) settle first, and the budget goes to the figures still too wide; the run
  // ends when every figure is (no point needed).
  // Not before 10 rounds: a figure stopped the first time its interval looks tight is claimed tighter
  // than it is, the more so the fewer rounds it has (measured with the bootstrap intervals used before:
  // leaving from 5 rounds on, two default runs agreed on 14 of 18 figures and their 95% intervals
  // covered each other for 10 of 18). In a run of several processes, a later one sees the rounds of
  // those before it too (SweepSettings::run_out_dir), and the figures widened by their spread, as the
  // run's summary will give them.
  if (o.cpu_baseline == "filter2d") s.baselines = filter2d_baselines(points, s);
  // A baseline is measured as long as a GPU point at its N is (its ratio is not a target of its own), so
  // that FLAG's rounds all have it beside them.
  std::vector<int> baseline_n;
  for (const auto& b : s.baselines) baseline_n.push_back(b.identity["N"].get<int>());
  s.points_needed = [&points, baseline_n, target_ratio, target_exponent](const runner::RunRecord& record,
                                                                         const nlohmann::json& context) {
    if (record.round_order.size() < 10) return std::vector<bool>(points.size() + baseline_n.size(), true);
    const std::set<std::string> needed =
        figures(round_points(points, record, context.value("device", nlohmann::json())), Metric::lead, target_ratio,
                target_exponent, true, record.round_process)
            .needed;
    const PrecisionsHeld held = precisions_held(points);
    std::vector<bool> out;
    std::set<int> gpu_needed;
    for (const auto& p : points) {
      const std::string variant = figure_variant(p.method->name, p.options.precision, p.variant, held);
      out.push_back(needed.count(point_key(p.method->name, variant, p.backend, p.options.pattern.size_n)) > 0);
      if (out.back() && p.backend == "gpu") gpu_needed.insert(p.options.pattern.size_n);
    }
    for (int n : baseline_n) out.push_back(gpu_needed.count(n) > 0);
    return out;
  };
  s.derive = derive_figure9;  // reads the targets from config (as merge does)
  s.summary = [](const nlohmann::json& doc) {
    print_summary(doc);
    print_roofline(doc);
  };
  run_sweep(points, s);
}

}  // namespace

void derive_figure9(nlohmann::json& doc) {
  const auto& config = doc.at("config");
  derive(doc, config.at("target_ratio_pct").get<double>() / 100, config.at("target_exponent").get<double>());
}

void add_figure9_command(CLI::App& app) {
  auto o = std::make_shared<Figure9Options>();
  auto* cmd = app.add_subcommand("figure9", "Reproduce FLAG paper Figure 9: frame time vs gather size, naive vs FLAG");
  AxisFlags& a = o->axes;
  // At k = 2, as the paper, from its small sizes to N = 153 (a 152 px largest CoC), where naive's quadratic
  // growth has left FLAG's linear one far behind on lavapipe too (at N = 41 the two are still close there).
  a.sizes = {"9", "33", "57", "81", "105", "129", "153"};
  a.resolutions = {"800x600"};
  a.scenes = {"hoops"};
  a.backends = {"gpu", "cpu"};
  a.add_to(cmd, {Axis::sizes, Axis::methods, Axis::backends, Axis::precisions},
           {Axis::resolutions, Axis::scenes, Axis::apertures});
  o->method_options.add_to(cmd);
  // Three processes: a first run on a fresh machine then carries the offset between runs (processes.hpp),
  // and one process in an odd draw is a third of the rounds, which a median outvotes (with two, half).
  o->sweep.processes = 3;
  o->sweep.add_to(cmd, 300);
  cmd->add_option("--target-ratio-pct", o->target_ratio_pct,
                  "Measure until each naive/FLAG ratio's 95% interval is within +-this % (or the budget is spent)")
      ->check(finite_number())
      ->capture_default_str();
  cmd->add_option("--target-exponent", o->target_exponent,
                  "Measure until each growth exponent's 95% interval (larger half of N) is within +-this")
      ->check(finite_number())
      ->capture_default_str();
  cmd->add_option("--cpu-baseline", o->cpu_baseline,
                  "A CPU filter timed beside FLAG in the same rounds, at each N of the GPU points: filter2d, OpenCV's "
                  "cv::filter2D with the pattern's largest disc (no CoC; skipped, saying so, in a build without "
                  "OpenCV), or none")
      ->check(CLI::IsMember({"filter2d", "none"}))
      ->capture_default_str();
  cmd->add_option("--sweep-choices", o->sweep_choices,
                  "Method options (e.g. horizontal_bins) measured at every one of their choices, interleaved with the "
                  "rest: each variant is a curve of its own; naive / FLAG pairs the defaults");
  a.add_quick(cmd, "Small sweep for CI and tests (200x150, N = 5, 9, 13, 20 s)",
              {{Axis::sizes, {"5", "9", "13"}}, {Axis::resolutions, {"200x150"}}}, 20);
  cmd->callback([o] { figure9(*o); });
}

}  // namespace bokeh
