#pragma once
// The one JSON writer: every results file is {schema, schema_version, context, ...} and is written
// atomically (temp file + rename), so an interrupted run never leaves a half-written file.
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "atomic_file.hpp"
#include "vk/context.hpp"

namespace bokeh {

// Bumped when a key changes meaning or disappears; adding keys keeps the version.
constexpr int kSchemaVersion = 2;  // 2: one point format for every sweep (bench/runner/sweep.cpp)

// What a figure's times are, as results files name it (`time` on figure9's curves and ratios).
inline constexpr const char* kProcessCpuTime = "process CPU time";
inline constexpr const char* kWallClockTime = "wall-clock time";

// Device, driver, machine and build: what a reader needs to trust or compare a number.
// Includes power_state.start (see power_state()).
nlohmann::json run_context(const vk::DeviceInfo* device);

// What is known of clocks and power state now, and where it came from. Core Vulkan exposes no
// clock or power query, so: the CPU's from Linux (/proc/cpuinfo MHz, cpufreq governor and limits
// where the kernel has them, load average, virtualisation); an NVIDIA GPU's from `nvidia-smi`
// (SM and memory clocks with their maxima, performance state, power draw and limit, temperature,
// throttle reasons); other GPUs: recorded as unknown, with why.
nlohmann::json power_state(const vk::DeviceInfo* device);
nlohmann::json device_json(const vk::DeviceInfo& device);
// Whether a results context's device (context.device, as device_json writes it; null when the run
// used no Vulkan device) is the CPU, as lavapipe is: there the process's CPU time is the work done,
// and the commands that choose a clock (compare, ab, figure9) take it instead of wall-clock time.
bool is_cpu_device(const nlohmann::json& device);

// Wraps `body` as {"schema": name, "schema_version", "context", ...body} and writes it atomically.
void write_results(const std::string& path, const std::string& schema_name, const nlohmann::json& context,
                   const nlohmann::json& body);

// Writes `text` to `path` through write_text_file_atomically (kernels/core/atomic_file.hpp): a temporary
// beside it, fsync and a rename; readers see the old file or the new one, never a part, and a failed write
// leaves the old file and no temporary. remove_stale_temporaries (same header) clears those of killed runs.
void write_text_atomically(const std::string& path, const std::string& text);

// The command line of this process (main() records it): what the results store says ran.
void set_command_line(int argc, char** argv);
const std::string& command_line();
const std::vector<std::string>& command_line_words();  // argv as given (a run restarts itself in processes)

// Creates the parent directory of `path` if needed.
void ensure_parent_dir(const std::string& path);

// Before any work: throws std::runtime_error naming the path unless a file can be written there
// (it is not a directory, its folder exists or can be created, and a file can be created in it).
void check_writable_file(const std::string& path);
// check_writable_file, and throws naming both unless `path` is none of the command's `inputs` (the
// same file by any name): an output never replaces what the command reads. The inputs stay protected
// (protect_inputs): every later atomic write of this process refuses them as targets.
void check_writable_file(const std::string& path, const std::vector<std::string>& inputs);
// The same for a folder that files will be written into (created if missing).
void check_writable_dir(const std::string& dir);

// Runs plots/<script> with Debian's python3 (which has matplotlib): script JSON OUT_PREFIX.
// Throws if it fails; the results file is already written by then.
void run_plot_script(const std::string& script, const std::string& json_path, const std::string& out_prefix);

}  // namespace bokeh
