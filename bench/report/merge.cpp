#include "merge.hpp"

#include <algorithm>
#include <set>
#include <stdexcept>

#include <fmt/format.h>

#include "store.hpp"

namespace bokeh {

namespace {
// "i/n", 1 <= i <= n (what --shard writes into config.shard).
std::pair<int, int> shard_of(const std::string& text) {
  const auto slash = text.find('/');
  if (slash == std::string::npos || slash == 0 || slash + 1 >= text.size() ||
      text.find_first_not_of("0123456789/") != std::string::npos)
    throw std::invalid_argument(text);
  const int index = std::stoi(text.substr(0, slash)), count = std::stoi(text.substr(slash + 1));
  if (count < 1 || index < 1 || index > count || count > 100000) throw std::invalid_argument(text);
  return {index, count};
}
}  // namespace

nlohmann::json merge_shards(const std::vector<nlohmann::json>& docs, const std::vector<std::string>& names) {
  if (docs.empty()) throw std::runtime_error("merge: no results files given");
  // What every sweep document has (sweep.schema.json); the rest is derived from all points together.
  static const std::set<std::string> kept = {"schema", "schema_version", "context", "status", "config",
                                             "methods", "measurement", "points", "skipped", "elapsed_s"};
  nlohmann::json out;
  std::vector<bool> seen;
  std::set<std::string> ids, machines, baseline_ids;
  nlohmann::json baselines = nlohmann::json::object();
  nlohmann::json shards = nlohmann::json::array(), points = nlohmann::json::array(), skipped = nlohmann::json::array();
  bool complete = true;
  double elapsed_s = 0;
  for (std::size_t f = 0; f < docs.size(); ++f) {
    const nlohmann::json& doc = docs[f];
    const std::string& name = names.at(f);
    for (const char* key : {"schema", "schema_version", "context", "config", "points"})
      if (!doc.contains(key)) throw std::runtime_error(fmt::format("merge: {} is not a sweep results file (no '{}')", name, key));
    nlohmann::json config = doc["config"];
    const std::string shard = config.value("shard", "1/1");
    config.erase("shard");
    std::pair<int, int> index;
    try {
      index = shard_of(shard);
    } catch (const std::invalid_argument&) {
      throw std::runtime_error(fmt::format("merge: {}: config.shard '{}' is not i/n", name, shard));
    }
    if (f == 0) {
      for (const auto& [key, value] : doc.items())
        if (kept.count(key)) out[key] = value;
      out["config"] = config;
      seen.assign(index.second, false);
    } else {
      if (doc["schema"] != out["schema"] || doc["schema_version"] != out["schema_version"])
        throw std::runtime_error(fmt::format("merge: {} is {} version {}, {} is {} version {}", name, doc["schema"].dump(),
                                             doc["schema_version"].dump(), names[0], out["schema"].dump(),
                                             out["schema_version"].dump()));
      if (static_cast<int>(seen.size()) != index.second)
        throw std::runtime_error(fmt::format("merge: {} is shard {} but {} is one of {}", name, shard, names[0], seen.size()));
      for (const auto& [key, value] : config.items())
        if (!out["config"].contains(key) || out["config"][key] != value)
          throw std::runtime_error(fmt::format("merge: {} differs from {} in config.{}: not shards of one sweep", name,
                                               names[0], key));
      if (config.size() != out["config"].size())
        throw std::runtime_error(fmt::format("merge: {} and {} have different config keys: not shards of one sweep", name, names[0]));
    }
    if (seen[index.first - 1]) throw std::runtime_error(fmt::format("merge: shard {} given twice ({})", shard, name));
    seen[index.first - 1] = true;
    for (const auto& p : doc["points"]) {
      const std::string id = p.value("id", "");
      if (!ids.insert(id).second) throw std::runtime_error(fmt::format("merge: point {} is in more than one file ({})", id, name));
      points.push_back(p);
    }
    if (doc.contains("skipped"))
      for (const auto& p : doc["skipped"]) skipped.push_back(p);
    // CPU baselines (figure9 --cpu-baseline), each from the shard that measured the GPU points of its N; one
    // whose N's GPU points two shards share (e.g. split by precision) is kept from the first.
    for (const char* key : {"baselines", "skipped_baselines"})
      if (doc.contains(key))
        for (const auto& b : doc[key])
          if (baseline_ids.insert(b.value("id", "")).second) baselines[key].push_back(b);
    const std::string machine = history::machine_key(doc["context"]);
    machines.insert(machine);
    const std::string status = doc.value("status", "complete");
    complete = complete && status == "complete";
    elapsed_s = std::max(elapsed_s, doc.value("elapsed_s", 0.0));
    shards.push_back({{"shard", shard},
                      {"file", name},
                      {"machine", machine},
                      {"status", status},
                      {"points", doc["points"].size()},
                      {"context", doc["context"]},
                      {"measurement", doc.value("measurement", nlohmann::json::object())}});
  }
  for (std::size_t i = 0; i < seen.size(); ++i)
    if (!seen[i]) throw std::runtime_error(fmt::format("merge: shard {}/{} is missing", i + 1, seen.size()));
  // round_process maps a shard's round numbers to its processes (--processes). Shards whose rounds were
  // split otherwise have no one map: the merged run keeps none rather than shard 1's, which would assign
  // the other shards' samples to the wrong processes.
  const nlohmann::json first_map = out["measurement"].value("round_process", nlohmann::json());
  if (!std::all_of(shards.begin(), shards.end(), [&](const nlohmann::json& s) {
        return s["measurement"].value("round_process", nlohmann::json()) == first_map;
      }))
    out["measurement"].erase("round_process");
  out["points"] = points;
  out["skipped"] = skipped;
  for (const char* key : {"baselines", "skipped_baselines"})
    if (std::any_of(docs.begin(), docs.end(), [&](const nlohmann::json& d) { return d.contains(key); }))
      out[key] = baselines.value(key, nlohmann::json::array());
  out["status"] = complete ? "complete" : "partial";
  out["elapsed_s"] = elapsed_s;  // the shards ran side by side: the longest
  out["shards"] = shards;
  if (machines.size() > 1) out["context"]["shard_machines"] = std::vector<std::string>(machines.begin(), machines.end());
  out["merged_note"] = fmt::format("{} shards joined by `bokehbench merge`; context and measurement are shard {}'s (each "
                                   "shard's are under shards); the command's derived figures (fits, ratios, fronts) are "
                                   "not recomputed here",
                                   docs.size(), shards[0]["shard"].get<std::string>());
  return out;
}

}  // namespace bokeh
