#include "report.hpp"

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <thread>
#include <vector>

#include <signal.h>
#include <unistd.h>

#include <fmt/chrono.h>
#include <fmt/format.h>

#include "build_info.hpp"  // generated: BOKEH_GIT_COMMIT
#include "half_float.hpp"
#include "simd.hpp"

#ifndef BOKEH_SOURCE_DIR
#define BOKEH_SOURCE_DIR "."
#endif

namespace bokeh {

namespace {

std::string cpu_model() {
  std::ifstream cpuinfo("/proc/cpuinfo");
  std::string line;
  while (std::getline(cpuinfo, line))
    if (line.rfind("model name", 0) == 0) {
      const auto colon = line.find(':');
      return colon == std::string::npos ? line : line.substr(colon + 2);
    }
  return "unknown";
}

std::string read_first_line(const std::string& path) {
  std::ifstream in(path);
  std::string line;
  std::getline(in, line);
  return line;
}

// Linux's view of the CPU cores: what lavapipe and the CPU references run on.
nlohmann::json cpu_power_state() {
  nlohmann::json out = {{"source", "linux /proc and /sys"}};
  std::ifstream cpuinfo("/proc/cpuinfo");
  std::string line;
  std::vector<double> mhz;
  bool hypervisor = false;
  while (std::getline(cpuinfo, line)) {
    if (line.rfind("cpu MHz", 0) == 0) {
      const auto colon = line.find(':');
      if (colon != std::string::npos) mhz.push_back(std::atof(line.c_str() + colon + 1));
    } else if (line.rfind("flags", 0) == 0 && line.find(" hypervisor") != std::string::npos) {
      hypervisor = true;
    }
  }
  if (!mhz.empty())
    out["cpuinfo_mhz"] = {{"min", *std::min_element(mhz.begin(), mhz.end())},
                          {"max", *std::max_element(mhz.begin(), mhz.end())}};
  out["virtualised"] = hypervisor;
  const std::string cpufreq = "/sys/devices/system/cpu/cpu0/cpufreq/";
  if (std::filesystem::exists(cpufreq)) {
    out["cpufreq"] = {{"governor", read_first_line(cpufreq + "scaling_governor")},
                      {"cur_khz", read_first_line(cpufreq + "scaling_cur_freq")},
                      {"min_khz", read_first_line(cpufreq + "scaling_min_freq")},
                      {"max_khz", read_first_line(cpufreq + "scaling_max_freq")}};
  } else {
    out["cpufreq"] = "not exposed (no /sys/devices/system/cpu/cpu0/cpufreq: typical of a VM; the host sets the clock)";
  }
  if (std::filesystem::exists("/sys/devices/system/cpu/intel_pstate/no_turbo"))
    out["intel_no_turbo"] = read_first_line("/sys/devices/system/cpu/intel_pstate/no_turbo");
  if (std::filesystem::exists("/sys/devices/system/cpu/cpufreq/boost"))
    out["boost"] = read_first_line("/sys/devices/system/cpu/cpufreq/boost");
  // Other work on the machine: on a shared machine this moves every number.
  out["load_average"] = read_first_line("/proc/loadavg");
  return out;
}

// Runs `cmd` through the shell; returns its exit status and output.
std::pair<int, std::string> run_command(const std::string& cmd) {
  std::string text;
  FILE* pipe = ::popen(cmd.c_str(), "r");
  if (!pipe) return {-1, "cannot start a shell"};
  char buf[512];
  while (std::fgets(buf, sizeof buf, pipe)) text += buf;
  return {::pclose(pipe), text};
}

// nvidia-smi's view of NVIDIA GPUs. A field it does not know fails the whole query, and drivers
// from 535 on call the throttle reasons "clocks_event_reasons": so the query is tried with the new
// name, the old one, then none.
nlohmann::json nvidia_power_state() {
  const std::vector<std::string> common = {"name",         "pci.bus_id",      "pstate",          "clocks.sm",
                                           "clocks.max.sm", "clocks.mem",     "clocks.max.mem",  "power.draw",
                                           "power.limit",  "temperature.gpu", "persistence_mode"};
  std::string last_error;
  for (const char* reasons : {"clocks_event_reasons.active", "clocks_throttle_reasons.active", ""}) {
    std::vector<std::string> fields = common;
    if (*reasons) fields.push_back(reasons);
    std::string query;
    for (const auto& f : fields) query += (query.empty() ? "" : ",") + f;
    const auto [status, text] =
        run_command("timeout 10 nvidia-smi --query-gpu=" + query + " --format=csv,noheader,nounits 2>&1");
    if (status != 0) {
      last_error = text.empty() ? "nvidia-smi is missing or failed" : text;
      continue;
    }
    nlohmann::json gpus = nlohmann::json::array();
    std::istringstream lines(text);
    for (std::string row; std::getline(lines, row);) {
      nlohmann::json gpu = nlohmann::json::object();
      std::istringstream cells(row);
      std::string cell;
      for (const auto& f : fields) {
        if (!std::getline(cells, cell, ',')) break;
        const auto first = cell.find_first_not_of(' ');
        gpu[f] = first == std::string::npos ? "" : cell.substr(first);
      }
      gpus.push_back(gpu);
    }
    return {{"source", "nvidia-smi"}, {"units", "MHz, W, degrees C"}, {"gpus", gpus}};
  }
  return {{"source", "nvidia-smi"}, {"error", last_error}};
}

std::string env_or(const char* name, const char* fallback) {
  const char* value = std::getenv(name);
  return value ? value : fallback;
}

// How this binary was compiled, as far as it changes CPU speed (CMake option BOKEH_NATIVE).
nlohmann::json build_json() {
#if defined(BOKEH_MARCH_NATIVE)
  const bool native = true;
#else
  const bool native = false;
#endif
#if defined(NDEBUG)
  const bool optimised = true;
#else
  const bool optimised = false;
#endif
  return {{"march_native", native},
          {"ndebug", optimised},
          {"cpu_vector_floats", simd::kWidth},  // lanes of the CPU references' vectors: 4 (SSE2) or 8 (AVX)
          {"half_conversion", half_conversion()}};
}

}  // namespace

bool is_cpu_device(const nlohmann::json& device) {
  return device.is_null() || device.value("type", std::string()) == "cpu";
}

nlohmann::json device_json(const vk::DeviceInfo& d) {
  return {{"index", d.index},
          {"name", d.name},
          {"type", d.type},
          {"vulkan_api_version", d.api_version},
          {"driver_name", d.driver_name},
          {"driver_info", d.driver_info},
          {"vendor_id", d.vendor_id},
          {"device_id", d.device_id},
          {"timestamp_period_ns", d.timestamp_period_ns},
          {"timestamp_valid_bits", d.timestamp_valid_bits},
          {"max_storage_buffer_range_bytes", d.max_storage_buffer_range_bytes},
          {"device_local_heap_bytes", d.device_local_heap_bytes}};
}

nlohmann::json run_context(const vk::DeviceInfo* device) {
  const auto now = std::chrono::system_clock::now();
  nlohmann::json ctx = {
      {"date_utc", fmt::format("{:%Y-%m-%dT%H:%M:%SZ}", fmt::gmtime(std::chrono::system_clock::to_time_t(now)))},
      {"git_commit", BOKEH_GIT_COMMIT},  // what the binary was built from; -dirty: with uncommitted changes
      {"bokehbench_version", BOKEH_VERSION},
      {"compiler", fmt::format("{} {}", "g++", __VERSION__)},
      {"cpu_model", cpu_model()},
      {"cpu_cores", std::thread::hardware_concurrency()},
      // lavapipe's worker threads; unset means one per core.
      {"lp_num_threads", env_or("LP_NUM_THREADS", "unset")},
      {"device", device ? device_json(*device) : nlohmann::json(nullptr)},
      {"power_state", {{"start", power_state(device)}}},
      {"build", build_json()}};
  return ctx;
}

nlohmann::json power_state(const vk::DeviceInfo* device) {
  nlohmann::json out = {{"cpu", cpu_power_state()}};
  if (!device) return out;
  if (device->type == "cpu")
    out["device"] = "a CPU device (lavapipe): its clock is the CPU's, above";
  else if (device->vendor_id == 0x10de)
    out["device"] = nvidia_power_state();
  else
    out["device"] = fmt::format("unknown: core Vulkan has no clock or power query, and bokehbench reads no vendor tool for "
                                "vendor 0x{:04x}", device->vendor_id);
  return out;
}

void ensure_parent_dir(const std::string& path) {
  const auto parent = std::filesystem::path(path).parent_path();
  if (!parent.empty()) std::filesystem::create_directories(parent);
}

void check_writable_dir(const std::string& dir) {
  const std::filesystem::path folder = dir.empty() ? std::filesystem::path(".") : std::filesystem::path(dir);
  std::error_code ec;
  if (std::filesystem::exists(folder, ec) && !std::filesystem::is_directory(folder, ec))
    throw std::runtime_error(fmt::format("'{}' is not a directory", folder.string()));
  std::filesystem::create_directories(folder, ec);
  if (ec) throw std::runtime_error(fmt::format("cannot create directory '{}': {}", folder.string(), ec.message()));
  // Permissions alone do not tell (root, read-only mounts, /proc): create and remove a file.
  const std::filesystem::path probe = folder / fmt::format(".bokehbench-write-probe-{}", ::getpid());
  {
    std::ofstream out(probe);
    if (!out)
      throw std::runtime_error(fmt::format("cannot write into directory '{}': {}", folder.string(), std::strerror(errno)));
  }
  std::filesystem::remove(probe, ec);
}

void check_writable_file(const std::string& path) {
  std::error_code ec;
  if (path.empty()) throw std::runtime_error("an output path is empty");
  if (std::filesystem::is_directory(path, ec))
    throw std::runtime_error(fmt::format("output '{}' is a directory, not a file", path));
  try {
    check_writable_dir(std::filesystem::path(path).parent_path().string());
  } catch (const std::runtime_error& e) {
    throw std::runtime_error(fmt::format("cannot write output '{}': {}", path, e.what()));
  }
}

void check_writable_file(const std::string& path, const std::vector<std::string>& inputs) {
  check_writable_file(path);
  // Every later write (write_file_atomically) refuses these too, whatever writes it.
  protect_inputs(inputs);
  refuse_input_as_output(path, inputs);
}

void run_plot_script(const std::string& script, const std::string& json_path, const std::string& out_prefix) {
  ensure_parent_dir(out_prefix);
  const std::string cmd = fmt::format("/usr/bin/python3 '{}/plots/{}' '{}' '{}'", BOKEH_SOURCE_DIR, script, json_path,
                                      out_prefix);
  std::fflush(stdout);
  if (std::system(cmd.c_str()) != 0)
    throw std::runtime_error("plotting failed (is python3-matplotlib installed?): " + cmd);
}

void write_text_atomically(const std::string& path, const std::string& text) {
  ensure_parent_dir(path);
  write_text_file_atomically(path, text);
}

void write_results(const std::string& path, const std::string& schema_name, const nlohmann::json& context,
                   const nlohmann::json& body) {
  nlohmann::json doc = {{"schema", schema_name}, {"schema_version", kSchemaVersion}, {"context", context}};
  doc.update(body);
  write_text_atomically(path, doc.dump(2) + "\n");
}

namespace {
std::string& command_line_text() {
  static std::string text;
  return text;
}
std::vector<std::string>& command_line_list() {
  static std::vector<std::string> words;
  return words;
}
}  // namespace

void set_command_line(int argc, char** argv) {
  std::string text;
  for (int i = 0; i < argc; ++i) {
    std::string arg = argv[i];
    if (arg.find_first_of(" \t\"'") != std::string::npos) arg = "'" + arg + "'";
    text += (i ? " " : "") + arg;
  }
  command_line_text() = text;
  command_line_list().assign(argv, argv + argc);
}

const std::string& command_line() { return command_line_text(); }
const std::vector<std::string>& command_line_words() { return command_line_list(); }

}  // namespace bokeh
