#include "paired.hpp"

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <iostream>
#include <sstream>
#include <list>
#include <map>
#include <memory>
#include <random>
#include <set>
#include <stdexcept>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "method.hpp"
#include "package.hpp"
#include "report.hpp"
#include "targets.hpp"

extern char** environ;

namespace bokeh::paired {

using json = nlohmann::json;

// ---- The worker ----

void serve(const std::vector<SweepPoint>& points, const SweepSettings& s) {
  // The coordinator decides when to stop (it closes our stdin): a Ctrl-C meant for it must not end
  // us mid-reply.
  std::signal(SIGINT, SIG_IGN);
  // Replies go to the stdout we were started with; anything else printed goes to stderr.
  const int reply_fd = dup(STDOUT_FILENO);
  if (reply_fd < 0 || dup2(STDERR_FILENO, STDOUT_FILENO) < 0) throw std::runtime_error("--serve: cannot set up stdout");
  std::FILE* reply = fdopen(reply_fd, "w");
  const auto send = [&](const json& j) {
    const std::string line = j.dump() + "\n";
    std::fwrite(line.data(), 1, line.size(), reply);
    std::fflush(reply);
  };

  SweepTargets targets(points, s.device, s.cpu_threads, s.max_buffer_mb);
  vk::Context* ctx = targets.context();
  if (ctx) ctx->watchdog_floor_s = s.watchdog_s;
  json hello_points = json::array();
  for (std::size_t i = 0; i < points.size(); ++i)
    hello_points.push_back({{"id", points[i].id},
                            {"method", points[i].method->name},
                            {"backend", points[i].backend},
                            {"skip", targets.plans()[i].skip},
                            {"work", targets.plans()[i].work}});
  send({{"hello", {{"protocol", kProtocol}, {"context", run_context(ctx ? &ctx->info() : nullptr)}, {"points", hello_points}}}});

  // A GPU that idled while the other build ran lowers its clocks: each sample gets untimed frames first.
  const double lead_in_ms = ctx && !ctx->info().is_software() ? s.policy.sample_min_ms / 4 : 0;
  std::map<std::size_t, std::unique_ptr<runner::Target>> live;
  std::map<std::size_t, double> last_frame_ms;
  std::list<std::size_t> recency;  // least recent first
  // The point's target, made ready when it is not live (first use, or freed to save memory): `warm`
  // warms it up itself; a sample of a target made again warms it first (compile caches are warm by then).
  const auto target = [&](std::size_t i, bool warm_if_made) -> runner::Target& {
    auto it = live.find(i);
    if (it == live.end()) {
      it = live.emplace(i, targets.prepare(i)).first;
      if (warm_if_made) it->second->warm_up();
    }
    recency.remove(i);
    recency.push_back(i);
    std::uint64_t resident = 0;
    for (const auto& [k, t] : live) resident += t->resident_bytes();
    while (resident > s.policy.resident_limit_bytes && recency.size() > 1) {
      const std::size_t victim = recency.front();
      resident -= live[victim]->resident_bytes();
      live.erase(victim);
      recency.pop_front();
    }
    return *live.at(i);
  };

  for (std::string line; std::getline(std::cin, line);) {
    std::size_t i = 0;
    try {
      const json request = json::parse(line);
      const std::string op = request.at("op").get<std::string>();
      if (op == "quit") break;
      i = request.at("point").get<std::size_t>();
      if (i >= points.size()) throw std::out_of_range(fmt::format("no point {}", i));
      if (!targets.plans()[i].skip.empty()) throw std::runtime_error(targets.plans()[i].skip);
      runner::Target& t = target(i, op != "warm");
      if (op == "warm") {
        runner::PointRecord record;
        last_frame_ms[i] = runner::warm_up(t, s.policy, record);
        send({{"frame_ms", last_frame_ms[i]}});
      } else if (op == "sample") {
        const int frames = request.at("frames").get<int>();
        if (frames < 1) throw std::invalid_argument("frames must be at least 1");
        if (lead_in_ms > 0)
          t.measure(std::clamp(static_cast<int>(std::ceil(lead_in_ms / std::max(last_frame_ms[i], 1e-3))), 1,
                               s.policy.max_frames_per_sample));
        const runner::Sample sample = runner::timed(t, frames, frames);
        last_frame_ms[i] = sample.frame_ms;
        send({{"frame_ms", sample.frame_ms}, {"cpu_ms", sample.cpu_ms}});
      } else {
        throw std::invalid_argument("unknown op '" + op + "'");
      }
    } catch (const std::exception& e) {
      live.erase(i);
      recency.remove(i);
      send({{"error", e.what()}});
    }
  }
  std::fclose(reply);
}

// ---- The coordinator ----

std::string bokehbench_in(const std::string& given, const std::string& role) {
  const std::filesystem::path p(given);
  if (std::filesystem::is_directory(p)) {
    if (!std::filesystem::exists(p / "bokehbench"))
      throw std::invalid_argument(fmt::format("{} '{}' is a folder without a bokehbench in it (build it first, or use "
                                              "bench/ab, which builds commits)", role, given));
    return std::filesystem::absolute(p / "bokehbench").string();
  }
  if (!std::filesystem::exists(p))
    throw std::invalid_argument(fmt::format("{} '{}' is neither a build folder nor a bokehbench binary (for commits, "
                                            "use bench/ab)", role, given));
  return std::filesystem::absolute(p).string();
}

void set_sides(Options& o, const std::string& baseline, const std::string& candidate, const std::string& sweep) {
  if (!is_package_reference(baseline) && !is_package_reference(candidate)) {
    o.sweep = sweep_words(sweep);
    o.baseline_exe = bokehbench_in(baseline, "baseline");
    o.candidate_exe = bokehbench_in(candidate, "candidate");
    return;
  }
  o.sweep = sweep_words(sweep == kDefaultSweep ? "figure9 --quick" : sweep);
  const auto& builtins = registered_methods();
  for (const std::string* given : {&baseline, &candidate})
    if (!is_package_reference(*given) &&
        std::none_of(builtins.begin(), builtins.end(), [&](const Method& m) { return m.name == *given; }))
      throw std::invalid_argument(fmt::format("ab compares two builds, or a method package with another or with a "
                                              "built-in method: '{}' is neither a package (a folder holding {}) nor "
                                              "a built-in's name, while the other is a package", *given, kPackageManifest));
  const Method* side[2] = {&find_method(baseline), &find_method(candidate)};
  if (side[0] == side[1])
    throw std::invalid_argument(fmt::format("ab: '{}' and '{}' are the same package; for an A/A check compare it with a "
                                            "copy of its folder", baseline, candidate));
  for (const auto& word : o.sweep)
    if (word.rfind("--method", 0) == 0)
      throw std::invalid_argument("ab of two packages: --sweep must not name methods (the two packages are its methods)");
  o.baseline_exe = o.candidate_exe = std::filesystem::canonical("/proc/self/exe").string();
  o.sweep.insert(o.sweep.end(), {"--methods", baseline, candidate});
  for (int k = 0; k < 2; ++k) {
    o.package_methods.push_back(side[k]->name);
    o.labels[k] = side[k]->package.is_null()
                          ? fmt::format("built-in method {}", side[k]->name)
                          : fmt::format("package {} ({}, content hash {})", side[k]->name,
                                        side[k]->package["path"].get<std::string>(), side[k]->package["hash"].get<std::string>());
  }
}

std::vector<std::string> sweep_words(const std::string& command_line) {
  std::istringstream in(command_line);
  std::vector<std::string> words;
  for (std::string w; in >> w;) words.push_back(w);
  if (words.empty()) throw std::invalid_argument("--sweep names no command");
  return words;
}

namespace {

// One build's worker process, spoken to over two pipes.
class Worker {
 public:
  Worker(std::string role, const std::string& exe, const std::vector<std::string>& args) : role_(std::move(role)) {
    if (access(exe.c_str(), X_OK) != 0) throw std::runtime_error(fmt::format("{}: no executable bokehbench at {}", role_, exe));
    int to[2], from[2];
    if (pipe2(to, O_CLOEXEC) != 0 || pipe2(from, O_CLOEXEC) != 0) throw std::runtime_error("cannot create pipes");
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_adddup2(&actions, to[0], STDIN_FILENO);
    posix_spawn_file_actions_adddup2(&actions, from[1], STDOUT_FILENO);
    std::vector<std::string> words = {exe};
    words.insert(words.end(), args.begin(), args.end());
    std::vector<char*> argv;
    for (auto& w : words) argv.push_back(w.data());
    argv.push_back(nullptr);
    const int err = posix_spawn(&pid_, exe.c_str(), &actions, nullptr, argv.data(), environ);
    posix_spawn_file_actions_destroy(&actions);
    close(to[0]);
    close(from[1]);
    to_ = to[1];
    from_ = from[0];
    if (err != 0) throw std::runtime_error(fmt::format("{}: cannot start {} ({})", role_, exe, std::strerror(err)));
    command_ = fmt::format("{}", fmt::join(words, " "));
  }
  ~Worker() {
    if (to_ >= 0) {
      const std::string quit = "{\"op\":\"quit\"}\n";
      [[maybe_unused]] auto n = write(to_, quit.data(), quit.size());
      close(to_);
    }
    if (from_ >= 0) close(from_);
    if (pid_ > 0) waitpid(pid_, nullptr, 0);
  }
  Worker(const Worker&) = delete;
  Worker& operator=(const Worker&) = delete;

  const std::string& role() const { return role_; }

  // One reply line. A worker that ends or stays silent for `timeout_s` is an error naming it.
  json read(double timeout_s = 900) {
    for (;;) {
      if (const auto nl = buffer_.find('\n'); nl != std::string::npos) {
        const std::string line = buffer_.substr(0, nl);
        buffer_.erase(0, nl + 1);
        try {
          return json::parse(line);
        } catch (const json::parse_error&) {
          fail(fmt::format("answered what is not a reply: '{}'", line.substr(0, 200)));
        }
      }
      pollfd p{from_, POLLIN, 0};
      const int ready = poll(&p, 1, static_cast<int>(timeout_s * 1000));
      if (ready == 0) fail(fmt::format("gave no answer in {:.0f} s", timeout_s));
      char chunk[65536];
      const ssize_t n = ready > 0 ? ::read(from_, chunk, sizeof chunk) : -1;
      if (n <= 0) {
        int status = 0;
        std::string how = "its output closed";
        if (waitpid(pid_, &status, 0) == pid_) {
          pid_ = -1;
          how = WIFEXITED(status) ? fmt::format("it exited with status {}", WEXITSTATUS(status))
                                  : fmt::format("it was killed by signal {}", WTERMSIG(status));
        }
        fail(how + " (its messages are above; a build from before `bokehbench ab` does not know --serve: "
                   "pick a newer baseline)");
      }
      buffer_.append(chunk, static_cast<std::size_t>(n));
    }
  }

  json request(const json& r) {
    const std::string line = r.dump() + "\n";
    if (write(to_, line.data(), line.size()) != static_cast<ssize_t>(line.size())) fail("stopped reading requests");
    return read();
  }

 private:
  [[noreturn]] void fail(const std::string& what) const {
    throw std::runtime_error(fmt::format("the {} worker ({}) {}", role_, command_, what));
  }
  std::string role_, command_, buffer_;
  pid_t pid_ = -1;
  int to_ = -1, from_ = -1;
};

// A point both builds measure.
struct Pairing {
  std::string id, backend, clock;
  std::size_t index[2] = {0, 0};  // in the baseline's and the candidate's point lists
  json work[2];
  bool injected = false;
  // One measuring pass's state (reset for the confirmation).
  int frames = 0;
  std::string skipped;  // why it left the rounds ("" while measured)
  bool settled = false;
  std::vector<double> wall_ms[2], cpu_ms[2];
  const std::vector<double>& compared(int side) const { return clock == "cpu" ? cpu_ms[side] : wall_ms[side]; }
};

// The two builds' workers, started together (their set-up, shader compilation included, overlaps;
// what they measure never does), with their hellos. Two packages: one worker serves both sides, and
// each side's hello holds its package's points (with their index in the worker's list), A's ids.
struct Workers {
  std::unique_ptr<Worker> process[2];
  Worker* side[2] = {nullptr, nullptr};
  json hello[2];
  Workers(const Options& o, const std::vector<std::string>& args) {
    if (o.package_methods.empty()) {
      process[0] = std::make_unique<Worker>("baseline", o.baseline_exe, args);
      process[1] = std::make_unique<Worker>("candidate", o.candidate_exe, args);
    } else {
      process[0] = std::make_unique<Worker>("packages", o.baseline_exe, args);
    }
    for (int k = 0; k < 2; ++k) side[k] = process[k] ? process[k].get() : process[0].get();
    for (int k = 0; k < 2; ++k) {
      if (!process[k]) continue;
      const json h = process[k]->read();
      if (!h.contains("hello")) throw std::runtime_error(fmt::format("the {} worker did not say hello: {}", process[k]->role(), h.dump()));
      hello[k] = h["hello"];
    }
    if (!o.package_methods.empty()) split_by_package(o.package_methods);
  }

 private:
  void split_by_package(const std::vector<std::string>& names) {
    const json all = hello[0];
    for (int k = 0; k < 2; ++k) {
      hello[k] = all;
      hello[k]["points"] = json::array();
      for (std::size_t i = 0; i < all["points"].size(); ++i) {
        json p = all["points"][i];
        if (p["method"] != names[k]) continue;
        p["index"] = i;
        p["id"] = names[0] + p["id"].get<std::string>().substr(names[k].size());
        hello[k]["points"].push_back(std::move(p));
      }
    }
  }
};

// One measuring pass over `chosen` (indices into pairings): warm-up, then rounds until every point
// has settled, or the budget is spent and every point has min pairs. Returns the rounds taken.
int measure(std::vector<Pairing>& pairings, const std::vector<std::size_t>& chosen, Workers& w, const Options& o,
            std::mt19937_64& rng) {
  const auto start = std::chrono::steady_clock::now();
  const auto elapsed = [&] { return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(); };
  const auto ask = [&](Pairing& p, int side, json request) {
    request["point"] = p.index[side];
    json reply = w.side[side]->request(request);
    if (reply.contains("error"))
      p.skipped = fmt::format("the {} build failed it: {}", w.side[side]->role(), reply["error"].get<std::string>());
    return reply;
  };
  // Warm-up, which build goes first alternating; samples are sized on the baseline.
  for (std::size_t n = 0; n < chosen.size() && !runner::interrupted(); ++n) {
    Pairing& p = pairings[chosen[n]];
    double base_ms = 0;
    for (int turn = 0; turn < 2 && p.skipped.empty(); ++turn) {
      const int side = (turn + static_cast<int>(n)) % 2;
      const json reply = ask(p, side, {{"op", "warm"}});
      if (side == 0 && p.skipped.empty()) base_ms = reply["frame_ms"].get<double>();
    }
    p.frames = std::clamp(static_cast<int>(std::ceil(o.sample_min_ms / std::max(base_ms, 1e-3))), 1, 4096);
  }
  const double warm_s = elapsed();
  std::vector<std::size_t> active;
  for (std::size_t k : chosen)
    if (pairings[k].skipped.empty()) active.push_back(k);
  const double slow = 1 + o.inject_slowdown_pct / 100;
  int rounds = 0;
  while (!active.empty() && !runner::interrupted()) {
    std::shuffle(active.begin(), active.end(), rng);
    const double round_start = elapsed();
    for (std::size_t k : active) {
      if (runner::interrupted()) break;
      Pairing& p = pairings[k];
      json replies[2];
      for (int turn = 0; turn < 2 && p.skipped.empty(); ++turn) {
        const int side = (turn + rounds + static_cast<int>(k)) % 2;  // each point alternates every round
        replies[side] = ask(p, side, {{"op", "sample"}, {"frames", p.frames}});
      }
      if (!p.skipped.empty()) continue;
      for (int side = 0; side < 2; ++side) {
        const double scale = side == 1 && p.injected ? slow : 1;
        p.wall_ms[side].push_back(replies[side]["frame_ms"].get<double>() * scale);
        p.cpu_ms[side].push_back(replies[side]["cpu_ms"].get<double>() * scale);
      }
    }
    if (runner::interrupted()) break;
    ++rounds;
    std::vector<std::size_t> still;
    for (std::size_t k : active) {
      Pairing& p = pairings[k];
      if (!p.skipped.empty()) continue;
      const int pairs = static_cast<int>(p.wall_ms[0].size());
      if (pairs >= o.rule.min_samples) {
        // Settled once the interval is narrower than the threshold (it can then no longer straddle
        // "same" and "slower"): a stop on precision, not on the verdict, so it does not bias the verdict.
        const compare::RatioInterval ci = compare::paired_ratio_interval(p.compared(0), p.compared(1), o.rule.confidence);
        p.settled = pairs >= o.max_pairs || (ci.exists && ci.high / ci.low <= 1 + o.rule.threshold);
      }
      if (!p.settled) still.push_back(k);
    }
    active = std::move(still);
    const bool all_have_min = std::all_of(active.begin(), active.end(), [&](std::size_t k) {
      return static_cast<int>(pairings[k].wall_ms[0].size()) >= o.rule.min_samples;
    });
    const double round_s = elapsed() - round_start, spent = elapsed() - warm_s;
    if (all_have_min && spent >= o.budget_s) break;
    if (o.progress && !active.empty()) {
      const double owed = std::max(0, o.rule.min_samples - rounds) * round_s;
      const double most = std::max(0, o.max_pairs - rounds) * round_s;
      fmt::print("round {}: {} of {} points unsettled, {} elapsed, ~{} left\n", rounds, active.size(), chosen.size(),
                 duration_text(elapsed()), duration_text(std::max(owed, std::min(most, o.budget_s - spent))));
      std::fflush(stdout);
    }
  }
  return rounds;
}

// Options a run cannot work with, refused before any build starts.
void check(const Options& o) {
  if (!(o.rule.threshold > 0)) throw std::invalid_argument("the threshold must be > 0");
  if (o.max_pairs < o.rule.min_samples) throw std::invalid_argument("--max-pairs must be at least --min-pairs");
  if (compare::signed_rank_critical(o.rule.min_samples, o.rule.confidence) < 0) {
    int n = 1;
    while (compare::signed_rank_critical(n, o.rule.confidence) < 0) ++n;
    throw std::invalid_argument(fmt::format("{} pairs give no {:g}% interval: ask for at least {}", o.rule.min_samples,
                                            100 * o.rule.confidence, n));
  }
  if (o.times != "auto" && o.times != "wall" && o.times != "cpu")
    throw std::invalid_argument("--times is auto, wall or cpu, not '" + o.times + "'");
}

// The report's header: both builds, the machine, and what the run is (a test, when injected).
compare::Report describe_builds(const json hello[2], const Workers& workers, const Options& o) {
  compare::Report report;
  report.design = "paired";
  const auto commit = [](const json& h) { return h["context"].value("git_commit", std::string("?")); };
  report.baseline_path = o.labels[0].empty() ? fmt::format("{} (commit {})", o.baseline_exe, commit(hello[0])) : o.labels[0];
  report.current_path = o.labels[1].empty() ? fmt::format("{} (commit {})", o.candidate_exe, commit(hello[1])) : o.labels[1];
  report.options.rule = o.rule;
  report.options.times = o.times;
  report.options.normalise = "none";
  for (int side = 0; side < 2; ++side) report.contexts[side] = hello[side].value("context", json::object());
  for (int side = 0; side < 2; ++side)
    if (hello[side].value("protocol", 0) != kProtocol)
      report.mismatches.push_back(fmt::format("the {} build speaks protocol {}, this one {}", workers.side[side]->role(),
                                              hello[side].value("protocol", 0), kProtocol));
  if (!report.mismatches.empty()) return report;
  const json& context = hello[1]["context"];
  const json& device = context["device"];
  const auto device_name = [](const json& d) { return d.is_null() ? std::string("none") : d.value("name", std::string("?")); };
  if (hello[0]["context"]["device"] != device)
    report.notes.push_back(fmt::format("the builds chose different devices: {} and {}",
                                       device_name(hello[0]["context"]["device"]), device_name(device)));
  const bool software = is_cpu_device(device);
  report.clock = o.times == "auto" ? (software ? "cpu" : "wall") : o.times;
  report.notes.push_back(fmt::format("one machine, one run: {} ({} cores), device {}, LP_NUM_THREADS={}",
                                     context.value("cpu_model", std::string("?")), context.value("cpu_cores", 0),
                                     device_name(device), context.value("lp_num_threads", std::string("unset"))));
  if (o.inject_slowdown_pct > 0)
    report.notes.push_back(fmt::format("a test of this comparison, not a real run: the candidate's times of {} are "
                                       "multiplied by {:g}",
                                       o.inject_points.empty() ? std::string("every point")
                                                               : fmt::format("{}", fmt::join(o.inject_points, ", ")),
                                       1 + o.inject_slowdown_pct / 100));
  return report;
}

// The points both builds can measure, in the baseline's order; the rest are named in notes.
std::vector<Pairing> pair_points(const json hello[2], const Workers& workers, const Options& o, compare::Report& report) {
  const json& device = hello[1]["context"]["device"];
  const bool software = is_cpu_device(device);
  std::map<std::string, std::size_t> candidate_index;
  for (std::size_t i = 0; i < hello[1]["points"].size(); ++i) candidate_index[hello[1]["points"][i]["id"]] = i;
  std::vector<Pairing> pairings;
  std::set<std::string> in_baseline;
  for (std::size_t i = 0; i < hello[0]["points"].size(); ++i) {
    const json& bp = hello[0]["points"][i];
    const std::string id = bp["id"];
    in_baseline.insert(id);
    const auto it = candidate_index.find(id);
    if (it == candidate_index.end()) {
      report.notes.push_back("not compared, only the baseline has it: " + id);
      continue;
    }
    const json& cp = hello[1]["points"][it->second];
    const std::string skip[2] = {bp["skip"], cp["skip"]};
    if (!skip[0].empty() || !skip[1].empty()) {
      const int k = skip[0].empty() ? 1 : 0;
      report.notes.push_back(fmt::format("not compared, the {} skips it ({}): {}", workers.side[k]->role(), skip[k], id));
      continue;
    }
    Pairing p;
    p.id = id;
    p.backend = bp["backend"];
    p.clock = o.times == "auto" ? (software || p.backend == "cpu" ? "cpu" : "wall") : o.times;
    p.index[0] = bp.value("index", i);
    p.index[1] = cp.value("index", it->second);
    p.work[0] = bp["work"];
    p.work[1] = cp["work"];
    p.injected = o.inject_slowdown_pct > 0 &&
                 (o.inject_points.empty() ||
                  std::find(o.inject_points.begin(), o.inject_points.end(), id) != o.inject_points.end());
    pairings.push_back(std::move(p));
  }
  for (const auto& [id, i] : candidate_index)
    if (!in_baseline.count(id)) report.notes.push_back("not compared, only the candidate has it: " + id);
  for (const auto& wanted : o.inject_points)
    if (std::none_of(pairings.begin(), pairings.end(), [&](const Pairing& p) { return p.id == wanted; }))
      throw std::invalid_argument("--inject-point: no point '" + wanted + "' both builds measure");
  if (pairings.empty()) report.mismatches.push_back("no point that both builds measure");

  return pairings;
}

// Each pairing's verdict; `first`: the first pass's, for the points measured again (`flagged`).
void add_verdicts(compare::Report& report, const std::vector<Pairing>& pairings,
                  const std::vector<compare::Judgement>& first, const std::vector<std::size_t>& flagged,
                  const Options& o) {
  for (std::size_t k = 0; k < pairings.size(); ++k) {
    const Pairing& p = pairings[k];
    if (!p.skipped.empty()) {
      report.notes.push_back(fmt::format("not compared: {}: {}", p.id, p.skipped));
      continue;
    }
    compare::PointComparison pc;
    pc.id = p.id;
    pc.times = fmt::format("{} time, paired", p.clock);
    pc.judgement = compare::judge_paired(p.compared(0), p.compared(1), o.rule);
    const bool measured_again = std::find(flagged.begin(), flagged.end(), k) != flagged.end() && o.confirm;
    if (measured_again) {
      pc.times += ", measured again";
      const auto& ci = first[k].interval;
      const std::string before = fmt::format("first pass slower, [{:.3f}, {:.3f}]", ci.low, ci.high);
      pc.judgement.why = pc.judgement.verdict == compare::Verdict::slower
                             ? before + "; slower again with fresh processes"
                             : before + "; not again with fresh processes" +
                                   (pc.judgement.why.empty() ? "" : " (" + pc.judgement.why + ")");
    }
    const auto estimate = [&](const std::vector<double>* v) {
      return v[0].empty() ? 0.0 : compare::judge_paired(v[0], v[1], o.rule).ratio_of_medians;
    };
    pc.raw_wall_ratio = estimate(p.wall_ms);
    pc.raw_cpu_ratio = estimate(p.cpu_ms);
    pc.baseline_samples = static_cast<int>(p.wall_ms[0].size());
    pc.current_samples = static_cast<int>(p.wall_ms[1].size());
    pc.baseline_median_ms = runner::quantile(p.wall_ms[0], 0.5);
    pc.current_median_ms = runner::quantile(p.wall_ms[1], 0.5);
    pc.work_changes = compare::json_differences(p.work[0], p.work[1]);
    pc.paired_baseline_ms = p.compared(0);
    pc.paired_current_ms = p.compared(1);
    for (int side = 0; side < 2; ++side) pc.wall_ms[side] = p.wall_ms[side], pc.cpu_ms[side] = p.cpu_ms[side];
    pc.backend = p.backend;
    report.points.push_back(std::move(pc));
  }
}

}  // namespace

compare::Report run(const Options& o) {
  check(o);
  std::signal(SIGPIPE, SIG_IGN);  // a worker that died is reported from its exit status, not by SIGPIPE
  const auto start = std::chrono::steady_clock::now();
  std::vector<std::string> args = o.sweep;
  args.insert(args.end(), {"--serve", "--no-plot"});
  auto workers = std::make_unique<Workers>(o, args);
  const json* hello = workers->hello;
  compare::Report report = describe_builds(hello, *workers, o);
  if (!report.mismatches.empty()) return report;
  std::vector<Pairing> pairings = pair_points(hello, *workers, o, report);
  if (!report.mismatches.empty()) return report;

  std::mt19937_64 rng(o.seed);
  runner::InterruptScope interrupts;
  std::vector<std::size_t> all(pairings.size());
  for (std::size_t k = 0; k < all.size(); ++k) all[k] = k;
  if (o.progress) fmt::print("ab: {} points, warming up both builds\n", pairings.size());
  const int rounds = measure(pairings, all, *workers, o, rng);
  std::vector<compare::Judgement> first(pairings.size());
  std::vector<std::size_t> flagged;
  for (std::size_t k = 0; k < pairings.size(); ++k)
    if (pairings[k].skipped.empty() && !pairings[k].wall_ms[0].empty()) {
      first[k] = compare::judge_paired(pairings[k].compared(0), pairings[k].compared(1), o.rule);
      if (first[k].verdict == compare::Verdict::slower) flagged.push_back(k);
    }
  const double first_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  report.notes.push_back(fmt::format("{} rounds, {} in all (both builds' start-up and warm-up included)", rounds,
                                     duration_text(first_s)));

  // A process is one draw of memory layout (heap addresses, cache-set aliasing), which can move a
  // point's time by itself and stays for the process's life: pairing cannot take that out. So what
  // the first pass flags is measured again by fresh processes of both builds, and is a regression
  // only if it shows again (a real slowdown does; one process's bad draw does not).
  if (o.confirm && !flagged.empty() && !runner::interrupted()) {
    if (o.progress) fmt::print("{} point(s) flagged: measuring them again with fresh processes of both builds\n", flagged.size());
    workers.reset();
    workers = std::make_unique<Workers>(o, args);
    for (std::size_t k : flagged) {
      Pairing& p = pairings[k];
      p.frames = 0, p.skipped.clear(), p.settled = false;
      for (int side = 0; side < 2; ++side) p.wall_ms[side].clear(), p.cpu_ms[side].clear();
    }
    const int again = measure(pairings, flagged, *workers, o, rng);
    report.notes.push_back(fmt::format("{} flagged point(s) measured again by fresh processes ({} rounds)", flagged.size(), again));
  }
  if (runner::interrupted())
    report.notes.push_back(fmt::format("interrupted: points with fewer than {} pairs are inconclusive", o.rule.min_samples));

  add_verdicts(report, pairings, first, flagged, o);
  return report;
}

}  // namespace bokeh::paired
