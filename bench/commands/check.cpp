// `bokehbench check METHOD`: the conformance suite over one method, as a user runs it on a method of
// their own before sweeping it. One line per check, "PASS|FAIL|SKIP  name: reason" with the measured
// number and its bound, then the counts; exit 0 when nothing failed, 2 when a check failed, 1 on error.
// The measurements are the GoogleTest suite's (conformance.hpp); this adds bad inputs, the validation
// layer, memory and accuracy, on small frames so one method takes seconds on lavapipe.
#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <functional>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <regex>
#include <stdexcept>
#include <tuple>

#include <fmt/format.h>

#include "accuracy.hpp"
#include "atomic_file.hpp"
#include "coc.hpp"
#include "commands.hpp"
#include "conformance.hpp"
#include "exact_scatter.hpp"
#include "metrics.hpp"
#include "report.hpp"
#include "run.hpp"
#include "scene.hpp"
#include "text_file.hpp"

extern char** environ;

namespace bokeh {

namespace {

using conformance::Backend;
using conformance::Measure;

enum class Status { pass, fail, skip };
const char* to_string(Status s) { return s == Status::pass ? "PASS" : s == Status::fail ? "FAIL" : "SKIP"; }

struct Outcome {
  Status status = Status::pass;
  std::string reason;
  std::optional<double> value, bound;  // the measured number and its bound, where the check has them
  nlohmann::json details = nullptr;     // more of what it measured, for --json
};

struct Result {
  std::string id, name;
  Outcome outcome;
  double seconds = 0;
};

// Thrown by a check that does not apply to this method or device: SKIP with the reason.
struct Skip {
  std::string reason;
};

struct CheckOptions {
  std::string method, device, json_path;
  int size_n = 9, spacing_px = 2;
  std::vector<std::string> only;  // check ids; empty: every check except gpu_frame
};

// The frame every check that needs a scene of its own uses: small, so the suite takes seconds.
constexpr int kFrameW = 96, kFrameH = 64;
// Accuracy is ranked on a larger frame, so the interior (the largest radius in from each side) holds
// most of it.
constexpr int kRankW = 160, kRankH = 120;
// Allocated intermediates may exceed the declared by driver padding and alignment, this much at most.
constexpr double kMemorySlackRatio = 1.25;
constexpr std::uint64_t kMemorySlackBytes = 64 * 1024;
constexpr double kHugeColor = 1e30;
constexpr const char* kHugeColorText = "1e30";
constexpr float kNearDepthM = 1e-4f;  // a CoC far beyond any pattern's largest radius: it must clamp

std::string bytes_text(std::uint64_t bytes) {
  return bytes < 10 * 1024 ? fmt::format("{} B", bytes)
                           : fmt::format("{:.1f} KiB ({} B)", static_cast<double>(bytes) / 1024, bytes);
}

std::string ordinal(int n) {
  const int tens = n % 100, ones = n % 10;
  const char* suffix = (tens >= 11 && tens <= 13) ? "th" : ones == 1 ? "st" : ones == 2 ? "nd" : ones == 3 ? "rd" : "th";
  return fmt::format("{}{}", n, suffix);
}

// A temporary folder, removed with what it holds when the check is done.
class TempDir {
 public:
  TempDir() {
    std::string pattern = (std::filesystem::temp_directory_path() / "bokehbench-check-XXXXXX").string();
    if (!::mkdtemp(pattern.data()))
      throw std::runtime_error(fmt::format("cannot create a temporary folder '{}': {}", pattern, std::strerror(errno)));
    path_ = pattern;
  }
  ~TempDir() {
    std::error_code ignored;
    std::filesystem::remove_all(path_, ignored);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
};

// Runs argv with `env_overrides` set (the rest of the environment inherited), its stdout and stderr
// into `output_path`; returns its exit status (128 + signal when killed).
int run_child(const std::vector<std::string>& args, const std::map<std::string, std::string>& env_overrides,
              const std::filesystem::path& output_path) {
  std::vector<std::string> env_text;
  for (char** e = environ; *e; ++e) {
    const std::string entry = *e;
    if (!env_overrides.contains(entry.substr(0, entry.find('=')))) env_text.push_back(entry);
  }
  for (const auto& [key, value] : env_overrides) env_text.push_back(key + "=" + value);
  std::vector<char*> argv, envp;
  for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  for (const auto& e : env_text) envp.push_back(const_cast<char*>(e.c_str()));
  envp.push_back(nullptr);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, output_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0600);
  posix_spawn_file_actions_adddup2(&actions, STDOUT_FILENO, STDERR_FILENO);
  pid_t pid = 0;
  const int err = posix_spawn(&pid, argv.front(), &actions, nullptr, argv.data(), envp.data());
  posix_spawn_file_actions_destroy(&actions);
  if (err != 0) throw std::runtime_error(fmt::format("cannot start '{}': {}", args.front(), std::strerror(err)));
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0)
    if (errno != EINTR) throw std::runtime_error(fmt::format("waiting for '{}': {}", args.front(), std::strerror(errno)));
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

class Checker {
 public:
  Checker(const CheckOptions& o) : o_(o), method_(find_method(o.method)), options_(method_.defaults({o.size_n, o.spacing_px})) {
    check_options(method_, options_);
  }

  const Method& method() const { return method_; }
  const FilterOptions& options() const { return options_; }
  std::string device_name() { return ctx_ ? ctx_->info().name : ""; }
  const vk::DeviceInfo* device_info() const { return ctx_ ? &ctx_->info() : nullptr; }

  // Every check: id (for --only), name (as printed), what it does.
  std::vector<std::tuple<std::string, std::string, std::function<Outcome()>>> checks() {
    return {
        {"in_focus", "in-focus image unchanged", [this] { return in_focus(); }},
        {"uniform", "uniform image stays uniform", [this] { return uniform(); }},
        {"energy", "energy conserved away from the borders", [this] { return energy(); }},
        {"nan_color", "bad input: NaN colour", [this] { return bad_input("nan_color"); }},
        {"inf_color", "bad input: infinite colour", [this] { return bad_input("inf_color"); }},
        {"huge_color", fmt::format("bad input: colour {}", kHugeColorText), [this] { return bad_input("huge_color"); }},
        {"nan_depth", "bad input: NaN depth", [this] { return bad_input("nan_depth"); }},
        {"near_depth", fmt::format("bad input: depth {} m (huge CoC)", kNearDepthM), [this] { return bad_input("near_depth"); }},
        {"validation", "no out-of-bounds access (validation layer)", [this] { return validation(); }},
        {"gpu_frame", "one GPU frame with robust buffer access", [this] { return gpu_frame(); }},
        {"memory", "memory declared = memory allocated", [this] { return memory(); }},
        {"accuracy", "error vs the exact reference", [this] { return accuracy(); }},
        {"gpu_vs_cpu", "GPU matches its CPU reference", [this] { return gpu_vs_cpu(); }},
    };
  }

 private:
  // The device every GPU check shares, created on first use (the bad-input and CPU-only parts need none).
  vk::Context& gpu() {
    if (!ctx_) ctx_ = std::make_unique<vk::Context>(o_.device, method_.needs(options_));
    if (const std::string missing = ctx_->unmet(method_.needs(options_)); !missing.empty())
      throw Skip{fmt::format("{} needs {}, which {} lacks", method_.name, missing, ctx_->info().name)};
    return *ctx_;
  }

  // The scene's lens at the pattern's largest radius, drawing the method's aperture.
  Lens lens_for(const Scene& s) const {
    Lens lens = with_max_coc_radius(s.lens, s.depth_m, options_.pattern.max_radius_px());
    lens.aperture = options_.aperture;
    return lens;
  }

  void skip_if_unsupported(int width_px, int height_px) {
    if (const std::string why = method_.unsupported ? method_.unsupported(options_, width_px, height_px) : "";
        !why.empty())
      throw Skip{fmt::format("{}x{}: {}", width_px, height_px, why)};
  }

  static Outcome judged(const Measure& m, const std::string& what) {
    const bool ok = m.within();
    return {ok ? Status::pass : Status::fail, fmt::format("{} {:.3g} {} {:.3g}", what, m.value, ok ? "<=" : ">", m.bound),
            m.value, m.bound};
  }

  Outcome in_focus() {
    skip_if_unsupported(64, 48);
    const Measure m = conformance::identity_at_radius_zero(Backend::gpu, &gpu(), method_, options_);
    Outcome out = judged(m, "radius 0 everywhere (pinhole), max |out - in|");
    out.reason += fmt::format(" (storage tolerance {:.3g} x the largest value, + 1e-6 of it)",
                              method_.storage_tolerance(options_));
    return out;
  }

  Outcome uniform() {
    skip_if_unsupported(80, 64);
    const Measure m = conformance::uniform_stays_uniform(Backend::gpu, &gpu(), method_, options_);
    Outcome out = judged(m, fmt::format("colour (1, 2, 3) at radius {} px, max |out - c| from {} px inside the borders",
                                        options_.pattern.max_radius_px(),
                                        2 * static_cast<int>(options_.pattern.max_radius_px()) + 2));
    out.reason += fmt::format(" ((storage tolerance {:.3g} + 1e-5) x the largest value 3)",
                              method_.storage_tolerance(options_));
    return out;
  }

  Outcome energy() {
    if (!method_.conserves_energy)
      throw Skip{method_.energy_note.empty() ? "the method does not declare that it conserves energy"
                                             : "does not conserve energy: " + method_.energy_note};
    skip_if_unsupported(80, 64);
    const Measure m = conformance::energy_conserved(Backend::gpu, &gpu(), method_, options_);
    return judged(m, "|sum(out) / sum(in) - 1| at the largest radius, light inside a black border,");
  }

  // One hoops frame with one bad value: a refusal (an exception naming the problem) passes, so does a
  // finite output; NaN or infinities in the output fail unless the method declares the input beyond its
  // range (Method::input_limit, which `render` warns about).
  Outcome bad_input(const std::string& which) {
    skip_if_unsupported(kFrameW, kFrameH);
    Scene s = make_scene("hoops", kFrameW, kFrameH);
    const Lens lens = lens_for(s);
    const int x = kFrameW / 2, y = kFrameH / 2;
    if (which == "nan_color") s.color.px(x, y)[1] = std::numeric_limits<float>::quiet_NaN();
    if (which == "inf_color") s.color.px(x, y)[1] = std::numeric_limits<float>::infinity();
    if (which == "huge_color")
      for (int c = 0; c < 3; ++c) s.color.px(x, y)[c] = static_cast<float>(kHugeColor);
    if (which == "nan_depth") *s.depth_m.px(x, y) = std::numeric_limits<float>::quiet_NaN();
    if (which == "near_depth")
      for (int dy = -4; dy < 4; ++dy)
        for (int dx = -4; dx < 4; ++dx) *s.depth_m.px(x + dx, y + dy) = kNearDepthM;
    vk::Context& ctx = gpu();
    Image out;
    try {
      out = run_gpu(ctx, method_, s.color, s.depth_m, lens, options_);
    } catch (const std::exception& e) {
      return {Status::pass, fmt::format("refused: {}", e.what())};
    }
    const std::size_t bad = count_non_finite(out);
    const bool beyond_declared = which == "huge_color" && method_.input_limit && method_.input_limit(options_) < kHugeColor;
    if (bad == 0)
      return {Status::pass,
              fmt::format("output finite, largest |value| {:.3g}{}", conformance::max_abs(out),
                          beyond_declared ? fmt::format(" (saturated: {} is above its declared input limit {:.3g})",
                                                        kHugeColorText, method_.input_limit(options_))
                                          : ""),
              0.0, 0.0};
    if (beyond_declared)
      return {Status::pass,
              fmt::format("{} of {} output values non-finite, as declared: {} is above its input limit {:.3g} "
                          "(render warns before such a frame)",
                          bad, out.pixels.size(), kHugeColorText, method_.input_limit(options_)),
              static_cast<double>(bad), 0.0};
    return {Status::fail,
            fmt::format("{} of {} output values are NaN or infinite, and the input was not refused", bad,
                        out.pixels.size()),
            static_cast<double>(bad), 0.0};
  }

  // The frame the validation check runs under the layer: hoops at kFrameW x kFrameH on a device with
  // robust buffer access, so a stray access is reported, not a crash.
  Outcome gpu_frame() {
    skip_if_unsupported(kFrameW, kFrameH);
    vk::DeviceRequirements wanted = method_.needs(options_);
    wanted.robust_buffer_access = true;
    vk::Context ctx(o_.device, wanted);
    if (const std::string missing = ctx.unmet(wanted); !missing.empty())
      throw Skip{fmt::format("{} lacks {}", ctx.info().name, missing)};
    const Scene s = make_scene("hoops", kFrameW, kFrameH);
    const Lens lens = lens_for(s);
    const Image out = run_gpu(ctx, method_, s.color, s.depth_m, lens, options_);
    const std::size_t bad = count_non_finite(out);
    return {bad == 0 ? Status::pass : Status::fail,
            fmt::format("hoops {}x{} on {} with robust buffer access: {} non-finite values", kFrameW, kFrameH,
                        ctx.info().name, bad),
            static_cast<double>(bad), 0.0};
  }

  // This binary again with `--only gpu_frame`, under the Khronos validation layer: core and
  // synchronization checks plus GPU-assisted validation's out-of-bounds buffer checks (which also warn
  // where robust buffer access made an access harmless). Any message fails.
  Outcome validation() {
    static const char* const manifests[] = {"/usr/share/vulkan/explicit_layer.d/VkLayer_khronos_validation.json",
                                            "/usr/local/share/vulkan/explicit_layer.d/VkLayer_khronos_validation.json",
                                            "/etc/vulkan/explicit_layer.d/VkLayer_khronos_validation.json"};
    if (std::none_of(std::begin(manifests), std::end(manifests), [](const char* p) { return std::filesystem::exists(p); }))
      throw Skip{fmt::format("the Khronos validation layer is not installed (no {}): apt-get install "
                             "vulkan-validationlayers",
                             manifests[0])};
    const TempDir dir;
    const auto log = dir.path() / "validation.log", output = dir.path() / "output.txt";
    write_text_file_atomically((dir.path() / "vk_layer_settings.txt").string(),
                               fmt::format("khronos_validation.debug_action = VK_DBG_LAYER_ACTION_LOG_MSG\n"
                                           "khronos_validation.log_filename = {}\n"
                                           "khronos_validation.report_flags = error,warn\n"
                                           "khronos_validation.duplicate_message_limit = 3\n"
                                           "khronos_validation.enables = VK_VALIDATION_FEATURE_ENABLE_GPU_ASSISTED_EXT,"
                                           "VK_VALIDATION_FEATURE_ENABLE_SYNCHRONIZATION_VALIDATION_EXT\n"
                                           "khronos_validation.gpuav_buffer_oob = true\n"
                                           "khronos_validation.warn_on_robust_oob = true\n",
                                           log.string()),
                               "validation layer settings");
    std::vector<std::string> args = {std::filesystem::read_symlink("/proc/self/exe").string(),
                                     "check",
                                     o_.method,
                                     "--size",
                                     std::to_string(o_.size_n),
                                     "-k",
                                     std::to_string(o_.spacing_px),
                                     "--only",
                                     "gpu_frame"};
    if (!o_.device.empty()) args.insert(args.end(), {"--device", o_.device});
    const int rc = run_child(args,
                             {{"VK_INSTANCE_LAYERS", "VK_LAYER_KHRONOS_validation"},
                              {"VK_LAYER_SETTINGS_PATH", dir.path().string()},
                              {"VK_LOADER_DEBUG", "layer"}},
                             output);
    const std::string text = read_text_file(output.string(), "validation run's output"),
                      messages = std::filesystem::exists(log) ? read_text_file(log.string(), "validation layer log") : "";
    // The loader says when it inserted the layer; without that line nothing was validated.
    if (text.find("Insert instance layer \"VK_LAYER_KHRONOS_validation\"") == std::string::npos)
      return {Status::fail, fmt::format("the loader did not insert VK_LAYER_KHRONOS_validation (exit {}): nothing was "
                                        "validated",
                                        rc)};
    // The frame's own line ("PASS  one GPU frame ..."), or what it said when it failed.
    std::string frame_line, last_line;
    for (std::istringstream lines(text); std::getline(lines, last_line);)
      if (last_line.find("one GPU frame") != std::string::npos) frame_line = last_line;
    if (rc == 0 && frame_line.starts_with("SKIP")) throw Skip{frame_line.substr(frame_line.find(':') + 2)};
    // Each message starts unindented, "ID(SEVERITY / TYPE): msgNum: N - text" (tests/validation_layer.py).
    const std::regex header(R"((^|\n)(\S+)\(([A-Z]+) / [A-Z]+\): msgNum:)");
    std::map<std::string, int> ids;
    int count = 0;
    std::string first;
    for (auto it = std::sregex_iterator(messages.begin(), messages.end(), header); it != std::sregex_iterator(); ++it) {
      ++count;
      ++ids[(*it)[2].str()];
      if (first.empty()) {
        const std::size_t start = static_cast<std::size_t>(it->position(2));
        first = messages.substr(start, std::min<std::size_t>(messages.find('\n', start) - start, 300));
      }
    }
    if (count > 0) {
      std::string id_text;
      for (const auto& [id, n] : ids) id_text += fmt::format("{}{} x{}", id_text.empty() ? "" : ", ", id, n);
      return {Status::fail, fmt::format("{} validation messages ({}); the first: {}", count, id_text, first),
              static_cast<double>(count), 0.0};
    }
    if (rc != 0)
      return {Status::fail, fmt::format("the frame failed under the validation layer (exit {}): {}", rc,
                                        frame_line.empty() ? last_line : frame_line)};
    return {Status::pass,
            fmt::format("0 validation messages over one hoops {}x{} frame (core, synchronization, GPU-assisted "
                        "out-of-bounds checks; robust buffer access)",
                        kFrameW, kFrameH),
            0.0, 0.0};
  }

  Outcome memory() {
    const int w = kRankW, h = kRankH;
    skip_if_unsupported(w, h);
    vk::Context& ctx = gpu();
    const MemoryUse declared = method_.gpu_memory(options_, w, h, &ctx);
    const Scene s = make_scene("hoops", w, h);
    const Lens lens = lens_for(s);
    gpu::GpuFrame frame(ctx, s.color, s.depth_m, lens, options_.pattern);
    const std::uint64_t allocated = method_.make_gpu(frame, options_)->intermediate_bytes();
    const auto most = static_cast<std::uint64_t>(static_cast<double>(declared.bytes) * kMemorySlackRatio) + kMemorySlackBytes;
    const bool ok = allocated >= declared.bytes && allocated <= most;
    return {ok ? Status::pass : Status::fail,
            fmt::format("{}x{}: allocated {}, declared {} ({}); allowed {} .. {} B ({}x + 64 KiB of padding)", w, h,
                        bytes_text(allocated), bytes_text(declared.bytes),
                        declared.from_driver ? "asked of the driver" : "the method's model", declared.bytes, most,
                        kMemorySlackRatio),
            static_cast<double>(allocated), static_cast<double>(most)};
  }

  // The method's GPU output against the exact scatter (energy sum) over the interior, ranked among every
  // registered method's default GPU output on the same frame: a figure to read, failing only on NaN/Inf.
  Outcome accuracy() {
    const int w = kRankW, h = kRankH;
    skip_if_unsupported(w, h);
    vk::Context& ctx = gpu();
    const Scene s = make_scene("hoops", w, h);
    const float max_radius_px = options_.pattern.max_radius_px();
    const Lens lens = with_max_coc_radius(s.lens, s.depth_m, max_radius_px);  // the disc: every method draws it
    const Image radius = coc_radius_image(s.depth_m, lens, max_radius_px);
    const Image reference = exact_scatter(s.color, radius, s.depth_m, ScatterComposite::energy_sum);
    const int margin_px = static_cast<int>(std::ceil(*std::max_element(radius.pixels.begin(), radius.pixels.end())));
    auto rmse_of = [&](const Method& m, FilterOptions o) {
      o.aperture = lens.aperture;
      const Image out = run_gpu(ctx, m, s.color, s.depth_m, lens, o);
      return std::pair{compare_interior(out, reference, margin_px).rmse, count_non_finite(out)};
    };
    FilterOptions own = options_;
    own.aperture = lens.aperture;
    const auto [rmse, bad] = rmse_of(method_, own);
    if (bad > 0 || !std::isfinite(rmse))
      return {Status::fail, fmt::format("{} of {} output values are NaN or infinite on hoops {}x{}", bad, w * h * 3, w, h)};
    std::vector<std::pair<double, std::string>> ranking = {{rmse, method_.name}};
    std::vector<std::string> left_out;
    for (const Method& m : registered_methods()) {
      if (m.name == method_.name) continue;
      try {
        const FilterOptions o = m.defaults(options_.pattern);
        if (!ctx.unmet(m.needs(o)).empty() || (m.unsupported && !m.unsupported(o, w, h).empty())) {
          left_out.push_back(m.name);
          continue;
        }
        if (const auto [other, other_bad] = rmse_of(m, o); other_bad == 0 && std::isfinite(other))
          ranking.emplace_back(other, m.name);
        else
          left_out.push_back(m.name);
      } catch (const std::exception&) {  // a method that cannot run this pattern is not ranked
        left_out.push_back(m.name);
      }
    }
    std::stable_sort(ranking.begin(), ranking.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
    // Ties share a place: 1 + how many did strictly better.
    const int rank = 1 + static_cast<int>(std::count_if(ranking.begin(), ranking.end(), [&](const auto& r) { return r.first < rmse; }));
    std::string reason = fmt::format(
        "interior RMSE {:.4g} vs the exact scatter (energy sum), hoops {}x{}: {} of {} by RMSE (best {} {:.4g}, worst "
        "{} {:.4g})",
        rmse, w, h, ordinal(rank), ranking.size(), ranking.front().second, ranking.front().first, ranking.back().second,
        ranking.back().first);
    if (!left_out.empty()) {
      std::string names;
      for (const auto& n : left_out) names += (names.empty() ? "" : ", ") + n;
      reason += fmt::format("; not ranked: {}", names);
    }
    nlohmann::json details = {{"frame", fmt::format("hoops {}x{}", w, h)}, {"interior_margin_px", margin_px},
                              {"rank", rank}, {"ranked", ranking.size()}, {"not_ranked", left_out},
                              {"rmse_interior_vs_energy_sum", nlohmann::json::object()}};
    for (const auto& [error, name] : ranking) details["rmse_interior_vs_energy_sum"][name] = error;
    return {Status::pass, reason, rmse, std::nullopt, details};
  }

  Outcome gpu_vs_cpu() {
    if (!method_.cpu_reference) throw Skip{"GPU-only: no CPU reference"};
    skip_if_unsupported(63, 46);
    vk::Context& ctx = gpu();
    Measure worst{-1, 0};
    std::string worst_scene;
    for (const char* scene : {"hoops", "fully_defocused"}) {
      bool finite = true;
      const Measure m = conformance::gpu_matches_cpu(ctx, method_, options_, scene, nullptr, &finite);
      if (!finite) return {Status::fail, fmt::format("{} 63x46: the GPU output holds NaN or infinite values", scene)};
      if (!(m.value <= worst.value)) worst = m, worst_scene = scene;  // NaN wins
    }
    return judged(worst, fmt::format("{} 63x46 (the worse of hoops, fully_defocused), max |GPU - CPU| / largest "
                                     "value",
                                     worst_scene));
  }

  const CheckOptions& o_;
  const Method& method_;
  FilterOptions options_;
  std::unique_ptr<vk::Context> ctx_;
};

nlohmann::json result_json(const Result& r) {
  nlohmann::json j = {{"id", r.id}, {"name", r.name}, {"status", to_string(r.outcome.status)},
                      {"reason", r.outcome.reason}, {"seconds", r.seconds}};
  auto number = [](const std::optional<double>& v) {
    return v && std::isfinite(*v) ? nlohmann::json(*v) : nlohmann::json(nullptr);
  };
  j["value"] = number(r.outcome.value);
  j["bound"] = number(r.outcome.bound);
  if (!r.outcome.details.is_null()) j["details"] = r.outcome.details;
  return j;
}

void check(const CheckOptions& o) {
  if (!o.json_path.empty()) check_writable_file(o.json_path, {});
  Checker checker(o);
  const auto all = checker.checks();
  for (const auto& id : o.only)
    if (std::none_of(all.begin(), all.end(), [&](const auto& c) { return std::get<0>(c) == id; })) {
      std::string known;
      for (const auto& c : all) known += (known.empty() ? "" : ", ") + std::get<0>(c);
      throw std::invalid_argument(fmt::format("--only: unknown check '{}' (known: {})", id, known));
    }
  const FilterOptions& options = checker.options();
  fmt::print("check {} ({}), N={} k={} (max radius {} px)\n", checker.method().name, options.precision,
             options.pattern.size_n, options.pattern.spacing_px, options.pattern.max_radius_px());
  std::fflush(stdout);
  std::vector<Result> results;
  for (const auto& [id, name, run] : all) {
    // gpu_frame is what the validation check runs in a child process; asked for alone with --only.
    const bool wanted = o.only.empty() ? id != "gpu_frame" : std::find(o.only.begin(), o.only.end(), id) != o.only.end();
    if (!wanted) continue;
    Result r{id, name, {}, 0};
    const auto start = std::chrono::steady_clock::now();
    try {
      r.outcome = run();
    } catch (const Skip& skip) {
      r.outcome = {Status::skip, skip.reason};
    } catch (const std::bad_alloc&) {
      throw;
    } catch (const std::exception& e) {  // a valid input the method cannot run fails its check
      r.outcome = {Status::fail, fmt::format("threw: {}", e.what())};
    }
    r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    fmt::print("{}  {}: {}\n", to_string(r.outcome.status), r.name, r.outcome.reason);
    std::fflush(stdout);
    results.push_back(std::move(r));
  }
  int counts[3] = {0, 0, 0};
  for (const auto& r : results) ++counts[static_cast<int>(r.outcome.status)];
  if (!o.json_path.empty()) {
    nlohmann::json doc = {{"method", checker.method().name},
                          {"precision", options.precision},
                          {"size_n", options.pattern.size_n},
                          {"spacing_px", options.pattern.spacing_px},
                          {"options", checker.method().options_json(options)},
                          {"device", checker.device_name()},
                          {"passed", counts[0]},
                          {"failed", counts[1]},
                          {"skipped", counts[2]},
                          {"checks", nlohmann::json::array()}};
    for (const auto& r : results) doc["checks"].push_back(result_json(r));
    ensure_parent_dir(o.json_path);
    write_results(o.json_path, "bokehbench.check", run_context(checker.device_info()), doc);
    fmt::print("wrote {}\n", o.json_path);
  }
  fmt::print("{} passed, {} failed, {} skipped\n", counts[0], counts[1], counts[2]);
  if (counts[1] > 0) throw ExitStatus{2};
}

}  // namespace

void add_check_command(CLI::App& app) {
  auto o = std::make_shared<CheckOptions>();
  auto* cmd = app.add_subcommand(
      "check", "Run the conformance suite over one method: one PASS/FAIL/SKIP line per check (exit 0: none failed, "
               "2: a check failed, 1: an error)");
  cmd->add_option("method", o->method, "The method: a registered name (see `bokehbench methods`)")->required();
  cmd->add_option("-N,--size", o->size_n, "Gather size N")->check(CLI::Range(1, 1001))->capture_default_str();
  cmd->add_option("-k,--spacing", o->spacing_px, "Spacing k of the gather pattern, px")
      ->check(CLI::Range(1, 64))
      ->capture_default_str();
  cmd->add_option("--device", o->device, "Vulkan device index or name part (default: a GPU if present, else lavapipe)");
  cmd->add_option("--json", o->json_path, "Also write the results as JSON here");
  // Internal: the validation check re-runs this binary with --only gpu_frame under the layer.
  cmd->add_option("--only", o->only, "Run only these checks (ids)")->delimiter(',')->group("");
  cmd->callback([o] { check(*o); });
}

}  // namespace bokeh
