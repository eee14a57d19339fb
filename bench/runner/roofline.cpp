#include "roofline.hpp"

#include <algorithm>
#include <map>
#include <string>
#include <tuple>
#include <vector>

#include <fmt/format.h>

namespace bokeh {

namespace {

struct Range {
  double low = 1e300, high = -1e300;
  void add(double v) { low = std::min(low, v), high = std::max(high, v); }
  std::string text(double scale, int digits, const char* unit = "") const {
    if (low > high) return "-";
    if (fmt::format("{:.{}f}", low * scale, digits) == fmt::format("{:.{}f}", high * scale, digits))
      return fmt::format("{:.{}f}{}", low * scale, digits, unit);
    return fmt::format("{:.{}f}-{:.{}f}{}", low * scale, digits, high * scale, digits, unit);
  }
};

struct PassRow {
  Range n, gb_per_s, copy, unfused, taps_per_s, fma;
  double nearest() const {  // the larger of the two fractions at the pass's best point: how near a limit it gets
    return std::max(copy.low <= copy.high ? copy.high : 0.0, fma.low <= fma.high ? fma.high : 0.0);
  }
};

}  // namespace

void add_roofline(nlohmann::json& points, const nlohmann::json& limits) {
  for (auto& point : points) {
    const std::string backend = point["backend"].get<std::string>();
    const std::string copy = backend + "_copy_gb_per_s", fma = backend + "_fma_gflop_per_s";
    const auto& passes = point["work"].value("passes", nlohmann::json::object());
    for (auto& [pass, t] : point["throughput"].items()) {
      if (limits.contains(copy) && t.contains("gb_per_s"))
        t["fraction_of_copy_bandwidth"] = t["gb_per_s"].get<double>() / limits[copy].get<double>();
      if (limits.contains(copy) && t.contains("unfused_gb_per_s"))
        t["fraction_of_copy_unfused"] = t["unfused_gb_per_s"].get<double>() / limits[copy].get<double>();
      if (limits.contains(fma) && t.contains("taps_per_s"))
        t["fraction_of_fma_taps"] = t["taps_per_s"].get<double>() / (limits[fma].get<double>() * 1e9 / kTapFlops);
      double bytes = 0;  // the pass's, or the whole frame's for a CPU reference timed whole
      for (const auto& [name, w] : passes.items())
        if (name == pass || pass == "frame") bytes += w["bytes_read"].get<double>() + w["bytes_written"].get<double>();
      const double taps = pass == "frame" ? point["work"].value("taps", 0.0) : passes.contains(pass) ? passes[pass].value("taps", 0.0) : 0.0;
      if (bytes > 0) t["taps_per_byte"] = taps / bytes;
    }
  }
}

void print_roofline(const nlohmann::json& doc) {
  const auto& limits = doc["measurement"].value("limits", nlohmann::json::object());
  using Key = std::tuple<std::string, std::string, std::string>;  // backend, method variant precision, pass
  std::map<Key, PassRow> rows;
  for (const auto& p : doc["points"]) {
    const int scale = p.value("buffer_scale", 1);
    const std::string what = fmt::format("{}{} {}{}", p["method"].get<std::string>(), p.value("variant", std::string()),
                                         p.value("precision", std::string()), scale > 1 ? fmt::format(" 1/{}", scale) : "");
    for (const auto& [pass, t] : p["throughput"].items()) {
      PassRow& row = rows[{p["backend"].get<std::string>(), what, pass}];
      row.n.add(p["N"].get<double>());
      if (t.contains("gb_per_s")) row.gb_per_s.add(t["gb_per_s"].get<double>());
      if (t.contains("taps_per_s")) row.taps_per_s.add(t["taps_per_s"].get<double>());
      if (t.contains("fraction_of_copy_bandwidth")) row.copy.add(t["fraction_of_copy_bandwidth"].get<double>());
      if (t.contains("fraction_of_copy_unfused")) row.unfused.add(t["fraction_of_copy_unfused"].get<double>());
      if (t.contains("fraction_of_fma_taps")) row.fma.add(t["fraction_of_fma_taps"].get<double>());
    }
  }
  if (rows.empty()) return;
  std::vector<std::pair<Key, PassRow>> order(rows.begin(), rows.end());
  std::stable_sort(order.begin(), order.end(), [](const auto& a, const auto& b) { return a.second.nearest() < b.second.nearest(); });
  std::vector<std::string> ceilings;
  for (const char* backend : {"gpu", "cpu"}) {
    const std::string copy = fmt::format("{}_copy_gb_per_s", backend), fma = fmt::format("{}_fma_gflop_per_s", backend);
    if (limits.contains(copy) && limits.contains(fma))
      ceilings.push_back(fmt::format("{} copy {:.2f} GB/s, FMA {:.1f} GFLOP/s = {:.2f} G taps/s", backend,
                                     limits[copy].get<double>(), limits[fma].get<double>(),
                                     limits[fma].get<double>() / kTapFlops));
  }
  fmt::print("\nRoofline per pass, furthest from its limits first (this run's probes: {}; a tap is at least one vec4 "
             "FMA; ranges over the N measured; \"unfused\": a fused pass's bytes with the layers it keeps in registers, "
             "as the unfused passes move them):\n", fmt::join(ceilings, "; "));
  fmt::print("  {:<4} {:<26} {:<16} {:>9} {:>13} {:>12} {:>17} {:>13} {:>12}\n", "on", "method precision", "pass",
             "N", "GB/s", "of copy", "of copy, unfused", "G taps/s", "of FMA");
  for (const auto& [key, row] : order) {
    const auto& [backend, what, pass] = key;
    fmt::print("  {:<4} {:<26} {:<16} {:>9} {:>13} {:>12} {:>17} {:>13} {:>12}\n", backend, what, pass,
               row.n.text(1, 0), row.gb_per_s.text(1, 2), row.copy.text(100, 0, "%"), row.unfused.text(100, 0, "%"),
               row.taps_per_s.text(1e-9, 3), row.fma.text(100, 1, "%"));
  }
}

}  // namespace bokeh
