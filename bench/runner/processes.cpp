#include "processes.hpp"

#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <stdexcept>
#include <thread>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "report.hpp"

extern char** environ;

namespace bokeh::processes {

namespace {

// Runs this executable with `args` and waits; an interruption of this process is passed on to it
// once (a signal sent to this process alone, e.g. by `timeout`, would otherwise leave it running).
// Returns a description of how it ended ("" when it exited with status 0).
std::string run_and_wait(const std::vector<std::string>& args) {
  std::vector<std::string> words = args;
  words.front() = std::filesystem::read_symlink("/proc/self/exe").string();
  std::vector<char*> argv;
  for (auto& w : words) argv.push_back(w.data());
  argv.push_back(nullptr);
  pid_t pid = 0;
  if (const int err = posix_spawn(&pid, argv.front(), nullptr, nullptr, argv.data(), environ); err != 0)
    throw std::runtime_error(fmt::format("cannot start {} ({})", words.front(), std::strerror(err)));
  bool passed_on = false;
  int status = 0;
  for (;;) {
    const pid_t done = waitpid(pid, &status, WNOHANG);
    if (done == pid) break;
    if (done < 0) throw std::runtime_error(fmt::format("lost the process {} ({})", pid, std::strerror(errno)));
    if (runner::interrupted() && !passed_on) kill(pid, SIGINT), passed_on = true;
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  if (WIFEXITED(status)) return WEXITSTATUS(status) == 0 ? "" : fmt::format("exited with status {}", WEXITSTATUS(status));
  return fmt::format("was killed by signal {}", WTERMSIG(status));
}

nlohmann::json read_json(const std::filesystem::path& path) {
  std::ifstream in(path);
  return nlohmann::json::parse(in);
}

// One process's results document as a record of the run's points (index_of: each id's index), its
// rounds numbered from 0 (runner::followed_by puts them after the rounds before).
runner::RunRecord record_of(const nlohmann::json& doc, const std::map<std::string, std::size_t>& index_of) {
  runner::RunRecord rec;
  rec.points.resize(index_of.size());
  const auto& m = doc.at("measurement");
  for (const auto& ids : m.at("round_order")) {
    std::vector<std::size_t> order;
    for (const auto& id : ids) order.push_back(index_of.at(id.get<std::string>()));
    rec.round_order.push_back(std::move(order));
  }
  const nlohmann::json probes = m.value("probes", nlohmann::json::object());
  for (const auto& [name, probe] : probes.items()) {
    rec.probe_ms[name] = probe.at("ms_per_round").get<std::vector<double>>();
    rec.probe_cpu_ms[name] = probe.at("cpu_ms_per_round").get<std::vector<double>>();
  }
  // The sweep's points, then its baselines (SweepSettings::Baseline: the same samples, no passes).
  const nlohmann::json none = nlohmann::json::array();
  for (const char* measured : {"points", "baselines"})
    for (const auto& p : doc.value(measured, none)) {
      runner::PointRecord& r = rec.points[index_of.at(p.at("id").get<std::string>())];
      const auto& frame = p.at("samples_ms");
      const nlohmann::json passes = p.value("samples_pass_ms", nlohmann::json::object());
      for (std::size_t s = 0; s < frame.size(); ++s) {
        runner::Sample sample{frame[s].get<double>(), {}, p.at("samples_cpu_ms")[s].get<double>()};
        for (const auto& [pass, values] : passes.items()) sample.pass_ms[pass] = values[s].get<double>();
        r.samples.push_back(std::move(sample));
        r.sample_round.push_back(p.at("sample_rounds")[s].get<int>());
      }
      r.warm_up_ms = p.at("warm_up_ms").get<std::vector<double>>();
      r.frames_per_sample = p.at("frames_per_sample").get<int>();
      r.wall_s = p.value("measure_wall_s", 0.0);
      r.settled = p.value("settled", false);
    }
  for (const char* skipped : {"skipped", "skipped_baselines"})
    for (const auto& p : doc.value(skipped, none))
      rec.points[index_of.at(p.at("id").get<std::string>())].skipped = p.value("reason", "skipped");
  return rec;
}

// Appends one process's results document to `joined`: its rounds after those already there.
void append(Joined& joined, const std::map<std::string, std::size_t>& index_of, const nlohmann::json& doc) {
  joined.record = runner::followed_by(std::move(joined.record), record_of(doc, index_of));
  for (const auto& p : doc.at("points"))
    if (auto& first = joined.points[index_of.at(p.at("id").get<std::string>())]; first.is_null()) first = p;
}

// No rounds yet, for the points `ids`; index_of: each id's index.
Joined nothing_joined(const std::vector<std::string>& ids, std::map<std::string, std::size_t>& index_of) {
  Joined joined;
  joined.points.resize(ids.size());
  joined.record.points.resize(ids.size());
  for (std::size_t i = 0; i < ids.size(); ++i) joined.record.points[i].name = ids[i], index_of[ids[i]] = i;
  return joined;
}

// Process k's results file in its part_dir: the complete one, else the partial one (it was interrupted).
std::filesystem::path written_by(const std::string& out_dir, const std::string& name, int k) {
  const std::filesystem::path dir = part_dir(out_dir, name, k);
  const std::filesystem::path complete = dir / (name + ".json");
  return std::filesystem::exists(complete) ? complete : dir / (name + ".partial.json");
}

}  // namespace

std::string part_dir(const std::string& out_dir, const std::string& name, int index) {
  return (std::filesystem::path(out_dir) / (name + ".processes") / std::to_string(index)).string();
}

Joined join_earlier(const std::vector<std::string>& ids, const std::string& out_dir, const std::string& name,
                    int before) {
  std::map<std::string, std::size_t> index_of;
  Joined joined = nothing_joined(ids, index_of);
  for (int k = 1; k <= before; ++k) {
    const std::filesystem::path written = written_by(out_dir, name, k);
    if (!std::filesystem::exists(written))
      throw std::runtime_error(fmt::format("process {} of this run wrote no results ({})", k, written.string()));
    append(joined, index_of, read_json(written));
  }
  return joined;
}

Joined run(const std::vector<std::string>& ids, const SweepSettings& s) {
  std::map<std::string, std::size_t> index_of;
  Joined joined = nothing_joined(ids, index_of);
  const auto start = std::chrono::steady_clock::now();
  std::vector<std::string> reasons;
  std::string failure;
  for (int k = 1; k <= s.processes && failure.empty(); ++k) {
    if (runner::interrupted()) {
      failure = "interrupted";
      break;
    }
    const std::filesystem::path dir = part_dir(s.out_dir, s.name, k);
    std::filesystem::remove_all(dir);
    fmt::print("\n== process {} of {} (its rounds: {:.0f} s of the budget; results into {}) ==\n", k, s.processes,
               s.policy.budget_s / s.processes, dir.string());
    std::fflush(stdout);
    std::vector<std::string> args = command_line_words();
    args.insert(args.end(), {"--process", fmt::format("{}/{}", k, s.processes)});
    const std::string ended = run_and_wait(args);
    const std::filesystem::path written = written_by(s.out_dir, s.name, k);
    if (!std::filesystem::exists(written)) {
      const std::string what = fmt::format("process {} of {} {} and wrote no results (its messages are above)", k,
                                           s.processes, ended.empty() ? "ended" : ended);
      if (k == 1) throw std::runtime_error(what);
      failure = what;
      break;
    }
    const nlohmann::json doc = read_json(written);
    append(joined, index_of, doc);
    reasons.push_back(doc["measurement"].value("stop_reason", "interrupted"));
    fmt::print("process {} of {}: {} rounds, {}\n", k, s.processes, doc["measurement"].value("rounds", 0), reasons.back());
    if (!ended.empty() || doc.value("status", "") != "complete")
      failure = runner::interrupted() ? "interrupted"
                                       : fmt::format("process {} of {} {}", k, s.processes,
                                                     ended.empty() ? "did not complete" : ended);
  }
  runner::RunRecord& rec = joined.record;
  rec.status = failure.empty() ? "complete" : "interrupted";
  // The run's reason is one of the runner's: the last process's, which judged the figures on every
  // process's rounds (SweepSettings::run_out_dir).
  rec.stop_reason = failure.empty() ? reasons.back() : "interrupted";
  rec.elapsed_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (failure.empty()) std::filesystem::remove_all(std::filesystem::path(s.out_dir) / (s.name + ".processes"));
  fmt::print("\n== {} processes, {} rounds in all{} ==\n", reasons.size(), rec.round_order.size(),
             failure.empty() ? "" : ": " + failure);
  return joined;
}

}  // namespace bokeh::processes
