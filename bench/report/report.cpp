#include "report.hpp"

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <thread>

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
      {"build", build_json()}};
  return ctx;
}

void ensure_parent_dir(const std::string& path) {
  const auto parent = std::filesystem::path(path).parent_path();
  if (!parent.empty()) std::filesystem::create_directories(parent);
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
  const std::string tmp = fmt::format("{}.tmp.{}", path, ::getpid());
  {
    std::ofstream out(tmp);
    if (!out) throw std::runtime_error(fmt::format("cannot write '{}'", tmp));
    out << text;
    out.flush();
    if (!out) throw std::runtime_error(fmt::format("writing '{}' failed", tmp));
  }
  std::filesystem::rename(tmp, path);
}

void write_results(const std::string& path, const std::string& schema_name, const nlohmann::json& context,
                   const nlohmann::json& body) {
  nlohmann::json doc = {{"schema", schema_name}, {"schema_version", kSchemaVersion}, {"context", context}};
  doc.update(body);
  write_text_atomically(path, doc.dump(2) + "\n");
}

}  // namespace bokeh
