// `bokehbench stability`: where each registered method x precision stays correct, on the Vulkan
// device and as its CPU reference, at the extremes of radius, intensity, depth and image width; the
// first failure seen and how it fails (NaN, Inf, saturation, underflow, energy, shape), with the safe
// range of every axis. Each case is judged against closed forms and the exact scatter reference
// (kernels/core/exact_scatter.hpp), never against the method itself:
//   point-light cases: one light of intensity I at the centre of a black frame whose depth is
//     constant, so every pixel has the same CoC radius r (equation (1) in double precision, clamped to
//     the pattern's largest radius). The exact scatter of that light is a disc of radius r holding
//     energy I. Checked: every value finite; the energy (sum of RGB / 3) equals the reference's within
//     the method's storage bound; the light's second moment about the centre (its rms distance)
//     matches the exact disc's (a disc of the right size, whatever its edge profile); and, on the
//     intensity axes, linearity: output / I equals the output at I = 1 of the same configuration.
//   width cases: a uniform image (every pixel 1) at a constant radius stays 1 away from the borders,
//     over rows up to 16384 px (long accumulations).
// Methods come from the registry (registered_methods()), so a new method is covered unchanged.
#include <algorithm>
#include <chrono>
#include <filesystem>
#include <cmath>
#include <limits>
#include <map>
#include <optional>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "coc.hpp"
#include "commands.hpp"
#include "exact_scatter.hpp"
#include "method.hpp"
#include "parallel.hpp"
#include "report.hpp"
#include "run.hpp"
#include "store.hpp"
#include "sweep.hpp"

namespace bokeh {

namespace {

constexpr double kFocus_m = 3.0;
constexpr float kFloatMax = std::numeric_limits<float>::max();

struct StabilityOptions {
  std::string out_path = "results/stability.json", device;
  AxisFlags axes;  // methods (default: every registered method) and backends
  bool quick = false;
  int cpu_threads = 0;
  std::string store;      // --store URL; empty: history.sqlite beside --out
  bool no_store = false;  // --no-store
};

// One case: what the scene is and what the truth says.
struct Case {
  std::string axis, label;
  std::optional<double> value;  // the axis value (px, radiance, metres, px); none for infinity
  bool nominal = false;         // the case every safe range grows from
  enum class Kind { point, uniform } kind = Kind::point;
  int width_px = 0, height_px = 0;
  GatherPattern pattern;
  double intensity = 1;   // point light radiance (every channel)
  double depth_m = 10;    // constant over the frame
  double radius_px = 0;   // the CoC radius wanted at depth_m (before the pattern's clamp)
  bool check_linearity = false;
  std::string expect_error;  // non-empty: the run must refuse the input with this text
};

// A frame big enough that a light at its centre stays inside for every method's kernel (the
// circular kernels' taps reach about 1.3 times their disc radius).
int frame_side(double max_radius_px) { return 2 * static_cast<int>(std::ceil(1.5 * max_radius_px)) + 17; }

// The pattern whose largest radius is ceil(r) px (at least 1): k = 1 up to 100 px, k = 2 beyond.
GatherPattern pattern_for(double radius_px) {
  const int m = std::max(1, static_cast<int>(std::ceil(radius_px)));
  if (m <= 100) return {2 * m + 1, 1};
  return {m + 1, 2};  // k (N - 1) / 2 = m for even m
}

Case point_case(const std::string& axis, const std::string& label, std::optional<double> value, double radius_px,
                const GatherPattern& pattern, double intensity = 1) {
  Case c;
  c.axis = axis, c.label = label, c.value = value;
  c.pattern = pattern;
  c.width_px = c.height_px = frame_side(pattern.max_radius_px());
  c.radius_px = radius_px;
  c.depth_m = radius_px > 0 ? 10.0 : kFocus_m;  // radius 0 exactly: the focus distance
  c.intensity = intensity;
  return c;
}

std::vector<Case> make_cases(bool quick) {
  std::vector<Case> cases;
  const GatherPattern nominal = pattern_for(4);  // 9x1: largest radius 4 px
  // Radius: each case at its own pattern's largest radius (every method blurs fully there), then beyond it.
  std::vector<double> radii = {0, 0.3, 4, 16};
  if (!quick) radii = {0, 0.3, 1, 4, 16, 40, 64, 100, 128};
  for (double r : radii) {
    Case c = point_case("radius", r == 0.3 ? "0.3 (sub-pixel)" : fmt::format("{:g}", r), r, r, pattern_for(r));
    c.nominal = r == 4;
    cases.push_back(c);
  }
  cases.push_back(point_case("radius", "1000 (clamped to 4)", 1000, 1000, nominal));
  // Intensity, blurred (radius 4) and in focus (radius 0, where a layer holds the light as it is):
  // from below f32's normal floor through f16's subnormal and normal floors to f16's largest value and
  // f32's range.
  const std::vector<std::pair<double, std::string>> intensities = {
      {1e-38, "1e-38 (below f32's normal floor)"},
      {std::ldexp(1.0, -24), "5.96e-8 (f16 smallest subnormal)"},
      {std::ldexp(1.0, -14), "6.10e-5 (f16 smallest normal)"},
      {1e-4, "1e-4"},
      {1e-2, "1e-2"},
      {1, "1"},
      {100, "100"},
      {1e4, "1e4"},
      {65504, "65504 (f16 largest)"},
      {1e5, "1e5"},
      {1e10, "1e10"},
      {3e38, "3e38 (near f32 largest)"}};
  for (const char* axis : {"intensity", "intensity_in_focus"})
    for (const auto& [value, label] : intensities) {
      if (quick && (value == 1e-4 || value == 1e-2 || value == 100 || value == 1e4 || value == 1e10)) continue;
      const bool blurred = std::string(axis) == "intensity";
      Case c = point_case(axis, label, value, blurred ? 4 : 0, nominal, value);
      c.check_linearity = true;
      c.nominal = value == 1;
      cases.push_back(c);
    }
  // Depth: a light at constant depth D; its radius is equation (1) at D, clamped to 4 px.
  const std::vector<std::pair<double, std::string>> depths = {
      {std::numeric_limits<float>::denorm_min(), "1.4e-45 (smallest float)"},
      {1e-6, "1e-6"},
      {0.5, "0.5"},
      {kFocus_m, "3 (focus distance)"},
      {30, "30"},
      {1e6, "1e6"},
      {kFloatMax, "3.4e38 (largest float)"}};
  for (const auto& [depth, label] : depths) {
    Case c = point_case("depth", label, depth, -1, nominal);
    c.depth_m = depth;
    c.nominal = depth == kFocus_m;
    cases.push_back(c);
  }
  Case inf = point_case("depth", "inf", std::nullopt, -1, nominal);
  inf.depth_m = std::numeric_limits<double>::infinity();
  inf.expect_error = "depths must be finite and > 0";
  cases.push_back(inf);
  // Width: a uniform image at radius 4, rows up to 16384 px.
  std::vector<int> widths = {64, 3840};
  if (!quick) widths = {64, 1024, 3840, 16384};
  for (int w : widths) {
    Case c;
    c.axis = "width", c.label = fmt::format("{}", w), c.value = w;
    c.kind = Case::Kind::uniform;
    c.pattern = nominal;
    c.width_px = w, c.height_px = frame_side(nominal.max_radius_px()) + 8;
    c.radius_px = 4;
    c.nominal = w == 64;
    cases.push_back(c);
  }
  return cases;
}

// The case's scene: colour, depth and a lens whose radius at the case's depth is radius_px.
struct CaseScene {
  Image color, depth_m;
  Lens lens;
  double expected_radius_px = 0;  // equation (1) in double, clamped to the pattern's largest radius
};

CaseScene make_case_scene(const Case& c) {
  CaseScene s;
  const int w = c.width_px, h = c.height_px;
  s.color = Image(w, h, 3, c.kind == Case::Kind::uniform ? 1.0f : 0.0f);
  if (c.kind == Case::Kind::point)
    for (int ch = 0; ch < 3; ++ch) s.color.px(w / 2, h / 2)[ch] = static_cast<float>(c.intensity);
  s.depth_m = Image(w, h, 1, static_cast<float>(c.depth_m));
  s.lens.focus_distance_m = kFocus_m;
  // The radius scales with the image width: fit on a row as wide as the frame.
  if (c.radius_px >= 0) {
    // The f-stop that puts radius_px at depth_m (a pinhole when it is 0).
    s.lens = with_max_coc_radius(s.lens, Image(w, 1, 1, static_cast<float>(c.depth_m)), c.radius_px);
  } else {
    // Depth cases keep one lens: 4 px at 0.5 m, so far depths stay below the clamp (0.8 px at infinity).
    s.lens = with_max_coc_radius(s.lens, Image(w, 1, 1, 0.5f), 4.0);
  }
  if (std::isfinite(c.depth_m))
    s.expected_radius_px = std::min<double>(coc_radius_px(s.lens, c.depth_m, w), c.pattern.max_radius_px());
  return s;
}

struct Outcome {
  std::string status = "ok";  // ok, fail, rejected (refused as it should be), skipped
  std::string kind, detail;   // the failure
  // The disc's size against the exact one: a property of the method's design (e.g. a kernel's ripple)
  // rather than of its numerics, so it is reported beside the status and has its own range.
  std::optional<bool> disc_ok;
  std::string disc_detail;
  nlohmann::json measured = nlohmann::json::object(), bounds = nlohmann::json::object();
  Image output;
};

double energy(const Image& img) {
  double sum = 0;
  for (std::size_t i = 0; i < img.pixel_count(); ++i)
    for (int ch = 0; ch < 3; ++ch) sum += img.pixels[i * img.channels + ch];
  return sum / 3.0;
}

// sqrt(sum E d^2 / sum E): the light's rms distance from the centre pixel (signed sums: ringing
// kernels' negative lobes count as they are).
double rms_radius(const std::vector<double>& rgb, int w, int h) {
  double e = 0, e_d2 = 0;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const std::size_t i = (static_cast<std::size_t>(y) * w + x) * 3;
      const double v = (rgb[i] + rgb[i + 1] + rgb[i + 2]) / 3.0;
      const double dx = x - w / 2, dy = y - h / 2;
      e += v, e_d2 += v * (dx * dx + dy * dy);
    }
  return e != 0 ? std::sqrt(std::max(0.0, e_d2 / e)) : 0.0;
}

std::vector<double> to_double(const Image& img) {
  std::vector<double> out(img.pixel_count() * 3);
  for (std::size_t i = 0; i < img.pixel_count(); ++i)
    for (int ch = 0; ch < 3; ++ch) out[i * 3 + ch] = img.pixels[i * img.channels + ch];
  return out;
}

void fail(Outcome& out, const std::string& kind, const std::string& detail) {
  if (out.status != "fail") out.status = "fail", out.kind = kind, out.detail = detail;
}

// Runs one case and judges it. `unit` is the same configuration's output at intensity 1 (the
// linearity reference), if any.
Outcome run_case(const Case& c, const Method& m, const FilterOptions& base, vk::Context* ctx, int threads,
                 const Image* unit) {
  Outcome out;
  FilterOptions o = base;
  o.pattern = c.pattern;
  FramePlan plan;
  if (const std::string why = plan_frame(ctx, m, o, c.width_px, c.height_px, 0, plan); !why.empty()) {
    out.status = "skipped", out.detail = why;
    return out;
  }
  const CaseScene s = make_case_scene(c);
  try {
    out.output = ctx ? run_gpu(*ctx, m, s.color, s.depth_m, s.lens, o) : run_cpu(m, s.color, s.depth_m, s.lens, o, threads);
  } catch (const std::exception& e) {
    if (!c.expect_error.empty() && std::string(e.what()).find(c.expect_error) != std::string::npos) {
      out.status = "rejected", out.detail = e.what();
    } else {
      fail(out, "error", e.what());
    }
    return out;
  }
  if (!c.expect_error.empty()) {
    fail(out, "accepted", "the input should have been refused (" + c.expect_error + ")");
    return out;
  }
  std::size_t nans = 0, infs = 0;
  for (float v : out.output.pixels) nans += std::isnan(v), infs += std::isinf(v);
  out.measured["nan_values"] = nans;
  out.measured["inf_values"] = infs;
  if (nans) fail(out, "nan", fmt::format("{} NaN values", nans));
  if (infs) fail(out, "inf", fmt::format("{} infinite values", infs));
  const double storage = m.storage_tolerance(o);
  if (c.kind == Case::Kind::uniform) {
    // Away from the borders by more than any kernel's reach, a uniform 1 stays 1.
    const int margin = static_cast<int>(std::ceil(1.5 * c.pattern.max_radius_px())) + 1;
    double worst = 0;
    for (int y = margin; y < c.height_px - margin; ++y)
      for (int x = margin; x < c.width_px - margin; ++x)
        for (int ch = 0; ch < 3; ++ch) worst = std::max(worst, std::abs(double(out.output.px(x, y)[ch]) - 1.0));
    const double bound = 2 * storage + 1e-5;
    out.measured["max_interior_error"] = worst;
    out.bounds["max_interior_error"] = bound;
    if (!(worst <= bound)) fail(out, "energy", fmt::format("a uniform 1 comes out off by {:.3g} (bound {:.3g})", worst, bound));
    return out;
  }
  // The truth: the exact scatter of the light at the expected radius, in double precision.
  const Image radius(c.width_px, c.height_px, 1, static_cast<float>(s.expected_radius_px));
  const std::vector<double> exact =
      exact_scatter_double(s.color, radius, Image(), ScatterComposite::energy_sum, threads);
  double exact_energy = 0;
  for (double v : exact) exact_energy += v / 3.0;
  const double got = energy(out.output);
  const double energy_error = exact_energy > 0 ? std::abs(got / exact_energy - 1.0) : std::abs(got);
  const double energy_bound = 2 * storage + 1e-4;
  const double exact_rms = rms_radius(exact, c.width_px, c.height_px);
  const double rms = std::isfinite(got) ? rms_radius(to_double(out.output), c.width_px, c.height_px) : 0.0;
  const double shape_bound = 0.15 * exact_rms + 0.5;
  out.measured.update({{"radius_px", s.expected_radius_px},
                       {"energy", std::isfinite(got) ? nlohmann::json(got) : nlohmann::json(nullptr)},
                       {"exact_energy", exact_energy},
                       {"relative_energy_error", std::isfinite(energy_error) ? nlohmann::json(energy_error) : nlohmann::json(nullptr)},
                       {"rms_radius_px", rms},
                       {"exact_rms_radius_px", exact_rms}});
  out.bounds.update({{"relative_energy_error", energy_bound}, {"rms_radius_px", shape_bound}});
  if (out.status == "fail") return out;
  if (!(energy_error <= energy_bound)) {
    const bool lost = got < exact_energy;
    const std::string kind = !lost ? "energy" : c.intensity > 1 ? "saturation" : c.intensity < 1 ? "underflow" : "energy";
    fail(out, kind, fmt::format("energy {:.6g} of {:.6g} ({:+.3g}%, bound {:.3g}%)", got, exact_energy,
                                100 * (got / exact_energy - 1), 100 * energy_bound));
  }
  out.disc_ok = std::abs(rms - exact_rms) <= shape_bound;
  out.disc_detail = fmt::format("rms radius {:.3g} px, the exact disc's {:.3g} px (bound +-{:.3g})", rms, exact_rms,
                                shape_bound);
  if (c.check_linearity && unit) {
    // Linear in the input: output / I is the I = 1 output, up to the storage's rounding of each.
    double worst = 0, peak = 0;
    for (std::size_t i = 0; i < unit->pixels.size(); ++i) {
      peak = std::max(peak, std::abs(double(unit->pixels[i])));
      worst = std::max(worst, std::abs(double(out.output.pixels[i]) / c.intensity - unit->pixels[i]));
    }
    // 1e-4: f32 rounding, amplified by the cancellation of kernels with large weights (circular6).
    const double bound = (2 * storage + 1e-4) * peak;
    out.measured["linearity_error"] = peak > 0 ? worst / peak : worst;
    out.bounds["linearity_error"] = 2 * storage + 1e-4;
    if (!(worst <= bound))
      fail(out, c.intensity > 1 ? "saturation" : "underflow",
           fmt::format("output / I differs from the I = 1 output by {:.3g} of its peak (bound {:.3g})",
                       peak > 0 ? worst / peak : worst, 2 * storage + 1e-4));
  }
  return out;
}

nlohmann::json value_json(const std::optional<double>& v) { return v ? nlohmann::json(*v) : nlohmann::json(nullptr); }

// The contiguous run of passing cases around the axis's nominal one, and what stops it each side.
// disc: judge the disc's size (disc_ok) instead of the numerics (status).
nlohmann::json safe_range_json(const std::vector<const Case*>& cases, const std::vector<const Outcome*>& outcomes,
                               bool disc = false) {
  std::size_t nominal = 0;
  for (std::size_t i = 0; i < cases.size(); ++i)
    if (cases[i]->nominal) nominal = i;
  auto passes = [&](std::size_t i) {
    return disc ? outcomes[i]->disc_ok.value_or(false) : outcomes[i]->status == "ok";
  };
  auto failure = [&](std::size_t i) -> nlohmann::json {
    const Outcome& o = *outcomes[i];
    if (disc)
      return {{"label", cases[i]->label}, {"value", value_json(cases[i]->value)}, {"status", o.status},
              {"kind", o.disc_ok ? nlohmann::json("shape") : nlohmann::json(nullptr)},
              {"detail", o.disc_ok ? o.disc_detail : o.detail}};
    return {{"label", cases[i]->label}, {"value", value_json(cases[i]->value)}, {"status", o.status},
            {"kind", o.kind.empty() ? nlohmann::json(nullptr) : nlohmann::json(o.kind)}, {"detail", o.detail}};
  };
  nlohmann::json range = {{"low", nullptr}, {"high", nullptr}, {"below", nullptr}, {"above", nullptr}};
  if (!passes(nominal)) {
    range["below"] = range["above"] = failure(nominal);
    return range;
  }
  std::size_t lo = nominal, hi = nominal;
  while (lo > 0 && passes(lo - 1)) --lo;
  while (hi + 1 < cases.size() && passes(hi + 1)) ++hi;
  range["low"] = cases[lo]->label;
  range["high"] = cases[hi]->label;
  if (lo > 0) range["below"] = failure(lo - 1);
  if (hi + 1 < cases.size()) range["above"] = failure(hi + 1);
  return range;
}

const std::vector<std::string> kAxes = {"radius", "intensity", "intensity_in_focus", "depth", "width"};

// "low..high" with each label up to its first space (the table stays narrow; the JSON has them whole).
std::string range_text(const nlohmann::json& r) {
  if (r["low"].is_null()) return "fails";
  auto head = [](const nlohmann::json& label) {
    const std::string s = label.get<std::string>();
    return s.substr(0, s.find(' '));
  };
  return r["low"] == r["high"] ? head(r["low"]) : head(r["low"]) + ".." + head(r["high"]);
}

// One method x precision x backend over every case: outcomes, safe ranges per axis, first failure
// (printed as one line of the table).
nlohmann::json stability_of(const SweepPoint& point, const std::vector<Case>& cases, vk::Context* ctx, int threads) {
  const Method* m = point.method;
  const std::string& precision = point.options.precision;
  const std::string& backend = point.backend;
  const FilterOptions& base = point.options;
  vk::Context* device = backend == "gpu" ? ctx : nullptr;
  nlohmann::json config = {{"method", m->name}, {"precision", precision}, {"backend", backend}};
  const double limit = m->input_limit ? m->input_limit(base) : static_cast<double>(kFloatMax);
  config["input_limit"] = limit;
  if (device)
    if (std::string missing = device->unmet(m->needs(base)); !missing.empty()) {
      config["skipped"] = fmt::format("{} needs {}, which {} lacks", m->name, missing, device->info().name);
      fmt::print("  {:<12} {:<18} {:<4} skipped: {}\n", m->name, precision, backend, config["skipped"].get<std::string>());
      return config;
    }
  config["skipped"] = nullptr;
  std::vector<Outcome> outcomes(cases.size());
  // The I = 1 outputs first: the linearity reference of each intensity axis.
  std::map<std::string, Image> unit;
  for (std::size_t i = 0; i < cases.size(); ++i)
    if (cases[i].check_linearity && cases[i].nominal) {
      outcomes[i] = run_case(cases[i], *m, base, device, threads, nullptr);
      unit[cases[i].axis] = outcomes[i].output;
    }
  for (std::size_t i = 0; i < cases.size(); ++i) {
    if (cases[i].check_linearity && cases[i].nominal) continue;
    const auto u = unit.find(cases[i].axis);
    outcomes[i] = run_case(cases[i], *m, base, device, threads,
                           u != unit.end() && !u->second.pixels.empty() ? &u->second : nullptr);
  }
  nlohmann::json case_json = nlohmann::json::array(), ranges = nlohmann::json::object();
  nlohmann::json first_failure = nullptr;
  bool limit_holds = true;
  for (std::size_t i = 0; i < cases.size(); ++i) {
    const Case& c = cases[i];
    const Outcome& out = outcomes[i];
    case_json.push_back({{"axis", c.axis},
                         {"label", c.label},
                         {"value", value_json(c.value)},
                         {"nominal", c.nominal},
                         {"width_px", c.width_px},
                         {"height_px", c.height_px},
                         {"N", c.pattern.size_n},
                         {"k", c.pattern.spacing_px},
                         {"status", out.status},
                         {"kind", out.kind.empty() ? nlohmann::json(nullptr) : nlohmann::json(out.kind)},
                         {"detail", out.detail},
                         {"disc_ok", out.disc_ok ? nlohmann::json(*out.disc_ok) : nlohmann::json(nullptr)},
                         {"disc_detail", out.disc_detail},
                         {"measured", out.measured},
                         {"bounds", out.bounds}});
    if (out.status == "fail" && first_failure.is_null())
      first_failure = {{"axis", c.axis}, {"label", c.label}, {"kind", out.kind}, {"detail", out.detail}};
    // The declared input limit: no overflow or saturation at or below it.
    if (c.axis.rfind("intensity", 0) == 0 && c.intensity <= limit &&
        (out.kind == "nan" || out.kind == "inf" || out.kind == "saturation"))
      limit_holds = false;
  }
  for (const auto& axis : kAxes) {
    std::vector<const Case*> axis_cases;
    std::vector<const Outcome*> axis_outcomes;
    for (std::size_t i = 0; i < cases.size(); ++i)
      if (cases[i].axis == axis) axis_cases.push_back(&cases[i]), axis_outcomes.push_back(&outcomes[i]);
    ranges[axis] = safe_range_json(axis_cases, axis_outcomes);
    if (axis == "radius") ranges["disc"] = safe_range_json(axis_cases, axis_outcomes, /*disc=*/true);
  }
  config["input_limit_holds"] = limit_holds;
  config["cases"] = case_json;
  config["safe_ranges"] = ranges;
  config["first_failure"] = first_failure;
  std::string line = fmt::format("  {:<12} {:<18} {:<4}", m->name, precision, backend);
  for (const auto& axis : kAxes) line += fmt::format(" {:<16}", range_text(ranges[axis]));
  line += fmt::format(" {:<10}", range_text(ranges["disc"]));
  fmt::print("{} {}\n", line,
             first_failure.is_null()
                 ? std::string("no failure")
                 : fmt::format("first failure: {} {} ({})", first_failure["axis"].get<std::string>(),
                               first_failure["label"].get<std::string>(), first_failure["kind"].get<std::string>()));
  std::fflush(stdout);
  return config;
}

// What each check of a case holds a method to (the results' "checks" block).
nlohmann::json stability_checks() {
  return {{"point_light", "one light of intensity I at the centre of a black frame of constant depth: every pixel has "
                          "the CoC radius of equation (1) at that depth (double precision), clamped to the pattern's "
                          "largest radius; truth = exact_scatter (energy_sum) of the light at that radius"},
          {"finite", "no NaN or Inf value (kinds nan, inf)"},
          {"energy", "|sum(output) / sum(exact) - 1| <= 2 storage_tolerance + 1e-4 (kinds saturation when energy is lost "
                     "above I = 1, underflow below it, energy otherwise); storage_tolerance bounds each value relative "
                     "to the largest, so bracketed formats, whose rounding follows a row's or channel's range, can "
                     "exceed it over a large disc"},
          {"disc", "the light's rms distance from the centre within 15% + 0.5 px of the exact disc's (disc_ok): the "
                   "method's design (a kernel's ripple, a Gaussian) rather than its numerics, so it has its own range "
                   "(safe_ranges.disc, radius axis) and does not count as a failure"},
          {"linearity", "intensity axes: max |output / I - output at I = 1| <= (2 storage_tolerance + 1e-4) x the latter's "
                        "peak (kinds saturation above I = 1, underflow below; 1e-4: f32 rounding amplified by kernels "
                        "with large cancelling weights)"},
          {"uniform", "width axis: every pixel 1, radius 4 px: pixels farther than 1.5 x 4 + 1 px from the border stay "
                      "1 within 2 storage_tolerance + 1e-5 (kind energy)"},
          {"rejected", "bad input refused with a clear error, as it should be (depth inf)"},
          {"safe_range", "per axis, the contiguous passing cases around the nominal one (radius 4, I = 1, the focus "
                         "distance, 64 px), with the first failure each side"},
          {"input_limit", "Method::input_limit (f32's largest value when undeclared); input_limit_holds: no nan, inf "
                          "or saturation on the intensity axes at or below it"}};
}

void stability(StabilityOptions& o) {
  o.axes.resolve();
  const auto start = std::chrono::steady_clock::now();
  check_writable_file(o.out_path);
  // Every method x backend x precision it accepts, at the nominal pattern (the runner's product).
  Axes product;
  if (o.axes.methods.empty())
    for (const Method& m : registered_methods()) product.methods.push_back(m.name);
  else
    product.methods = o.axes.methods;
  product.backends = o.axes.backends;
  product.precisions = {"all"};
  product.patterns = {pattern_for(4)};
  const std::vector<SweepPoint> configurations_to_run = expand(product);
  const int threads = o.cpu_threads > 0 ? o.cpu_threads : default_cpu_threads();
  std::optional<vk::Context> ctx;
  if (const auto wanted = gpu_requirements(configurations_to_run)) ctx.emplace(o.device, *wanted);
  const std::vector<Case> cases = make_cases(o.quick);
  fmt::print("stability: {} methods, {} cases each, backends {}, device {}\n", product.methods.size(), cases.size(),
             fmt::join(o.axes.backends, " "), ctx ? ctx->info().name : "none");

  nlohmann::json configurations = nlohmann::json::array();
  for (const SweepPoint& point : configurations_to_run)
    configurations.push_back(stability_of(point, cases, ctx ? &*ctx : nullptr, threads));

  nlohmann::json axes = nlohmann::json::object();
  for (const auto& axis : kAxes) {
    axes[axis] = nlohmann::json::array();
    for (const Case& c : cases)
      if (c.axis == axis) axes[axis].push_back({{"label", c.label}, {"value", value_json(c.value)}, {"nominal", c.nominal}});
  }
  const nlohmann::json body = {
      {"config", {{"quick", o.quick}, {"backends", o.axes.backends}, {"methods", o.axes.methods}}},
      {"axes", axes},
      {"checks", stability_checks()},
      {"configurations", configurations},
      {"elapsed_s", std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count()}};
  const nlohmann::json context = run_context(ctx ? &ctx->info() : nullptr);
  write_results(o.out_path, "bokehbench.stability", context, body);
  // Into the results store like every sweep: its safe ranges as headline figures (store.hpp).
  if (!o.no_store) {
    nlohmann::json doc = body;
    doc["schema"] = "bokehbench.stability";
    doc["context"] = context;
    const std::string out_dir = std::filesystem::path(o.out_path).parent_path().string();
    history::append_run(o.store.empty() ? history::default_store_url(out_dir.empty() ? "." : out_dir) : o.store, doc,
                        command_line());
  }
  fmt::print("columns: radius px | intensity (r = 4 px) | intensity in focus | depth m | width px: where the numerics "
             "hold, around the nominal case (\"fails\": already there); disc: radii whose disc has the exact size\n"
             "wrote {} ({:.0f} s)\n",
             o.out_path, body["elapsed_s"].get<double>());
}

}  // namespace

void add_stability_command(CLI::App& app) {
  auto o = std::make_shared<StabilityOptions>();
  auto* cmd = app.add_subcommand(
      "stability", "Safe ranges of radius, intensity, depth and width for every method x precision, GPU and CPU");
  cmd->add_option("--out", o->out_path, "Results JSON")->capture_default_str();
  o->axes.backends = {"gpu", "cpu"};
  o->axes.add_to(cmd, {Axis::methods, Axis::backends}, {});
  cmd->add_option("--device", o->device, "Vulkan device index or name part (default: a GPU if present, else lavapipe)");
  cmd->add_option("--cpu-threads", o->cpu_threads, "Threads for the CPU references (default: every core)")
      ->check(CLI::Range(1, 1024));
  cmd->add_flag("--quick", o->quick, "Radii up to 16 px and widths 64 and 3840 only (CI)");
  cmd->add_option("--store", o->store,
                  "Results store the run is appended to: a file (SQLite) or postgresql://user@host/db (default: "
                  "history.sqlite beside --out)");
  cmd->add_flag("--no-store", o->no_store, "Append the run to no results store");
  cmd->callback([o] { stability(*o); });
}

}  // namespace bokeh
