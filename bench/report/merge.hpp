#pragma once
// Joins the shards of one sweep (the results files of `--shard i/n` runs, from one machine or many)
// into one results document that `compare` reads like any other.
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace bokeh {

// docs[i] was read from names[i]. Throws std::runtime_error naming the file and the problem unless they
// are every shard (1..n, once each) of one sweep: the same schema and version, the same config apart from
// config.shard, no point measured twice. The result has every shard's points and skipped points, the first
// shard's context and measurement, `shards` (each shard's file, machine, status, points, context and
// measurement), status complete only when every shard is, and no derived figures (a command's fits and
// ratios are drawn from all points together: the merge command recomputes them with the command's own
// code, commands.hpp derive_*, and says in `merged_note` and `derived_recomputed` whether it did). Shards measured on different
// machines are named in context.shard_machines, which compare reports as a machine difference.
nlohmann::json merge_shards(const std::vector<nlohmann::json>& docs, const std::vector<std::string>& names);

}  // namespace bokeh
