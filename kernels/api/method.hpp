#pragma once
// A filter method as the rest of the harness meets it: one declaration, written in the method's own
// folder (kernels/<name>/), registered with one line in kernels/CMakeLists.txt. The CLI, the sweeps,
// the JSON, the plots and the conformance tests read only this.
#include <cstddef>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <type_traits>
#include <vector>

#include <nlohmann/json.hpp>

#include "gpu_frame.hpp"
#include "image.hpp"
#include "lens.hpp"
#include "vk/context.hpp"

namespace bokeh {

// One option of a method's own: the CLI flag is --key with '_' written '-', the JSON name is key.
struct OptionSpec {
  std::string key;
  std::string help;
  double default_value = 0;
  double min = 0, max = 0;           // accepted range, inclusive (numeric options)
  bool integer = false;
  std::vector<std::string> choices;  // non-empty: an enumeration; the value is the index, CLI and JSON use names
  std::vector<double> tradeoff;      // the values `tradeoff` sweeps (empty: the default only)

  // Parses CLI text ("3", "0.5", or a choice name); throws std::invalid_argument naming the flag.
  double parse(const std::string& text) const;
  // Throws std::invalid_argument naming the flag unless `value` is accepted.
  void check(double value) const;
  nlohmann::json to_json(double value) const;  // number, or the choice's name
  std::string flag() const;                    // "--near-components"
};

// Everything that configures one run of a method.
struct FilterOptions {
  GatherPattern pattern;
  std::string precision;                 // one of Method::precisions
  int buffer_scale = 1;                  // one of Method::buffer_scales
  std::map<std::string, double> values;  // the method's own options (OptionSpec::key), every one present
  // The lens's aperture (Lens::aperture), which the method is asked to draw: run_cpu and run_gpu refuse
  // a lens whose aperture differs, so the two never disagree.
  Aperture aperture;

  double number(const std::string& key) const;  // throws std::logic_error if the method has no such option
  int integer(const std::string& key) const { return static_cast<int>(number(key)); }
  // An enumerated option (OptionSpec::choices): the index of its choice. Throws std::logic_error if
  // the method has no such option or the value is no index (check_options rejects those first).
  std::size_t choice_index(const std::string& key) const;
  // The same as the method's enum, whose enumerators are declared in the order of the choices (so a
  // method never compares an index with a number).
  template <class Enum>
  Enum choice(const std::string& key) const {
    static_assert(std::is_enum_v<Enum>, "choice<Enum>: an enum declared in the order of OptionSpec::choices");
    return static_cast<Enum>(choice_index(key));
  }
};

// What a CPU reference may read; the CoC pass has already run.
struct CpuInput {
  const Image& color;      // 3 channels, linear
  const Image& depth_m;    // 1 channel, planar depth
  const Lens& lens;
  const Image& radius_px;  // 1 channel, clamped to pattern.max_radius_px()
  const Image& packed;     // RGBA (rgb / discrete disc area, radius px)
  const FilterOptions& options;
  int threads;
  // Where the reference records what it found that depends on the scene, with the keys its GPU
  // driver's GpuFilter::stats() uses (null: not wanted).
  nlohmann::json* stats = nullptr;
};

struct MemoryUse {
  std::uint64_t bytes = 0;   // intermediate storage beyond the frame's shared buffers
  bool from_driver = false;  // true: vkGet*MemoryRequirements; false: the method's model
  nlohmann::json details = nlohmann::json::object();
};

struct Method {
  std::string name;  // the --method value and the JSON name
  std::string description;
  // A method package's identity (kernels/package/package.hpp): {name, hash, path[, rev]}; null for a
  // built-in. Results carry it beside the name.
  nlohmann::json package;
  std::vector<std::string> precisions;   // storage of intermediates it accepts, default first
  std::vector<int> buffer_scales = {1};  // resolution divisors of its intermediates it accepts
  std::vector<OptionSpec> options;
  // False for methods whose result depends only on the pattern's largest radius, not on its N x k
  // grid: sweeps over patterns then take the first of those with the same radius.
  bool samples_pattern = true;
  // Part of the sweeps that name no methods (figure9, tradeoff); variants that add little to a
  // default run (circular3..6) set false and run when named.
  bool in_default_sweeps = true;
  // What this configuration needs of a device (null: core Vulkan 1.1 compute only).
  std::function<vk::DeviceRequirements(const FilterOptions&)> device;

  // Why this method cannot draw options.aperture (empty: it can); null: the disc only. Checked first
  // (check_options, plan_frame): a sweep skips the point with this reason.
  std::function<std::string(const FilterOptions&)> aperture_unsupported;
  // Why this configuration cannot run at this size (empty: it can); checked before allocating.
  std::function<std::string(const FilterOptions&, int width_px, int height_px)> unsupported;
  std::function<Image(const CpuInput&)> cpu_reference;
  std::function<std::unique_ptr<gpu::GpuFilter>(gpu::GpuFrame&, const FilterOptions&)> make_gpu;
  std::function<std::vector<PassWork>(const FilterOptions&, int width_px, int height_px)> work;
  // The options as the GPU `device` runs them, where an option's auto choice changes the passes (null:
  // as given): the runner models a GPU point's work on these, while the point keeps its options as
  // given (auto), so its id and its baseline's stay the same.
  std::function<FilterOptions(const FilterOptions&, const vk::DeviceInfo* device)> on_device;
  // The CPU reference's work where it moves other bytes than the GPU passes (null: `work`'s): the
  // throughput a CPU point reports is this over its frame time.
  std::function<std::vector<PassWork>(const FilterOptions&, int width_px, int height_px)> cpu_work;
  // Intermediate memory on the device (ctx: ask the driver where the method can; may be null).
  std::function<MemoryUse(const FilterOptions&, int width_px, int height_px, vk::Context* ctx)> gpu_memory;
  // Intermediate memory the CPU reference allocates.
  std::function<std::uint64_t(const FilterOptions&, int width_px, int height_px)> cpu_memory_bytes;
  // Largest |GPU - CPU reference| / largest |CPU reference value| the GPU keeps (conformance suite).
  std::function<double(const FilterOptions&)> gpu_tolerance;
  // What the intermediates' storage costs against exact arithmetic, relative to the largest value:
  // how far radius 0 may be from the identity and the energy from conserved (0 for f32 storage).
  std::function<double(const FilterOptions&)> storage_tolerance;
  // The largest |colour| this configuration keeps finite and unsaturated for an isolated highlight
  // (its intermediates' range over how much a pass can amplify a value); null: only f32's range bounds
  // it. `render` warns before work when the input is brighter; `bokehbench stability` measures where
  // each configuration actually fails, and its test holds this declaration to that.
  std::function<double(const FilterOptions&)> input_limit;
  // Whether every source's light sums to its colour away from the borders (at a constant radius);
  // energy_note says what the method does instead when it does not.
  bool conserves_energy = true;
  std::string energy_note;

  // The method's defaults: its first precision, scale 1, every option at its default.
  FilterOptions defaults(const GatherPattern& pattern) const;
  vk::DeviceRequirements needs(const FilterOptions& options) const { return device ? device(options) : vk::DeviceRequirements{}; }
  const OptionSpec* option(const std::string& key) const;  // null if the method has no such option
  nlohmann::json options_json(const FilterOptions& options) const;  // {key: value or choice name}
};

// The registered (built-in) methods, in registration order (generated from kernels/CMakeLists.txt).
const std::vector<Method>& registered_methods();
// The built-ins, then the method packages loaded so far (kernels/package/package.hpp).
std::vector<const Method*> known_methods();
// A built-in or a loaded package by name, or a package by its folder (FOLDER or FOLDER@GIT-REV, loaded
// on first use). Throws std::invalid_argument listing the valid names, or naming what is wrong with
// the package.
const Method& find_method(const std::string& name);
// Why `method` cannot draw options.aperture ("" when it can): Method::aperture_unsupported, or for a
// method that declares none, that it draws the disc only.
std::string aperture_unsupported(const Method& method, const FilterOptions& options);
// Throws std::invalid_argument unless the method accepts the options' pattern, precision, buffer
// scale, option values and aperture; lists what it accepts.
void check_options(const Method& method, const FilterOptions& options);

}  // namespace bokeh
