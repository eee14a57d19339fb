// A method package read into a Method (package.hpp): the manifest's fields checked with clear errors,
// its shaders compiled, and the declared passes, intermediates, work and memory evaluated per point.
#include "package.hpp"

#include <algorithm>
#include <bit>
#include <cstdio>
#include <deque>
#include <filesystem>
#include <regex>
#include <set>
#include <sstream>

#include <fmt/format.h>

#include "expression.hpp"
#include "fnv1a.hpp"
#include "glsl_runtime.hpp"
#include "signed_coc.hpp"
#include "text_file.hpp"
#include "vk/memory.hpp"

namespace bokeh {

namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;
using package::Expression;
using package::Variables;

constexpr VkDescriptorType kBuffer = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER;
// Bindings 0..4 of every pass (README, "Method packages"): colour, depth, signed CoC, packed, output.
constexpr std::uint32_t kFixedBindings = 5;

struct BufferDecl {
  std::string name, format;
  std::uint64_t element_bytes = 0;
  Expression elements;
};

struct ConstantDecl {
  std::uint32_t id = 0;
  bool is_float = false;
  Expression value;
};

struct PassDecl {
  std::string name, shader;
  Expression invocations[2];
  vk::LocalSize local_size;
  std::vector<ConstantDecl> constants;
  Expression taps, bytes_read, bytes_written;  // the work model; empty: not declared (0)
  std::vector<std::uint32_t> spirv;
};

struct Package {
  std::string reference, name, path, rev;
  std::uint64_t hash = 0;
  std::vector<BufferDecl> buffers;
  std::vector<PassDecl> passes;
  std::vector<OptionSpec> options;
  const Method* reference_method = nullptr;  // cpu_reference.builtin
};

// ---- Reading the manifest ----

// Reads fields of one JSON object, naming the manifest and the field's path in every error.
class Fields {
 public:
  Fields(const json& object, std::string where, std::string file) : object_(object), where_(std::move(where)), file_(std::move(file)) {
    if (!object_.is_object()) fail(where_, "is not an object");
  }
  [[noreturn]] void fail(const std::string& field, const std::string& what) const {
    throw std::invalid_argument(fmt::format("{}: {} {}", file_, field, what));
  }
  std::string path(const std::string& key) const { return where_.empty() ? key : where_ + "." + key; }
  bool has(const std::string& key) const { return object_.contains(key); }
  const json& at(const std::string& key) const {
    if (!has(key)) fail(path(key), "is missing");
    return object_.at(key);
  }
  std::string text(const std::string& key) const {
    if (!at(key).is_string()) fail(path(key), "must be a string");
    return at(key).get<std::string>();
  }
  std::string text_or(const std::string& key, const std::string& fallback) const { return has(key) ? text(key) : fallback; }
  double number(const std::string& key, double fallback) const {
    if (!has(key)) return fallback;
    if (!at(key).is_number()) fail(path(key), "must be a number");
    return at(key).get<double>();
  }
  bool flag(const std::string& key, bool fallback) const {
    if (!has(key)) return fallback;
    if (!at(key).is_boolean()) fail(path(key), "must be true or false");
    return at(key).get<bool>();
  }
  const json& array(const std::string& key, bool required) const {
    static const json empty = json::array();
    if (!required && !has(key)) return empty;
    if (!at(key).is_array()) fail(path(key), "must be an array");
    return at(key);
  }
  Expression expression(const std::string& key, bool required = true) const {
    if (!required && !has(key)) return {};
    const json& v = at(key);
    if (v.is_number()) return {fmt::format("{}", v.get<double>()), file_ + ": " + path(key)};
    if (!v.is_string() || v.get<std::string>().empty()) fail(path(key), "must be an expression (a string) or a number");
    return {v.get<std::string>(), file_ + ": " + path(key)};
  }
  void only(const std::set<std::string>& known) const {
    for (const auto& [key, value] : object_.items())
      if (!known.count(key))
        fail(path(key), fmt::format("is not a field of the manifest here (known: {})", fmt::join(known, ", ")));
  }

 private:
  const json& object_;
  std::string where_, file_;
};

std::uint64_t element_bytes(const std::string& format) {
  static const std::map<std::string, std::uint64_t> sizes = {
      {"r32f", 4}, {"r32ui", 4}, {"r32i", 4}, {"rg32f", 8}, {"rgba16f", 8}, {"rgba32f", 16}, {"rgba32ui", 16}};
  const auto it = sizes.find(format);
  return it == sizes.end() ? 0 : it->second;
}

OptionSpec read_option(const Fields& f) {
  f.only({"key", "help", "default", "min", "max", "integer", "choices", "tradeoff"});
  OptionSpec spec;
  spec.key = f.text("key");
  if (!std::regex_match(spec.key, std::regex("[a-z][a-z0-9_]*"))) f.fail(f.path("key"), "must match [a-z][a-z0-9_]*");
  spec.help = f.text_or("help", "");
  for (const json& c : f.array("choices", false)) {
    if (!c.is_string()) f.fail(f.path("choices"), "must be strings");
    spec.choices.push_back(c.get<std::string>());
  }
  spec.integer = f.flag("integer", false);
  if (spec.choices.empty()) {
    spec.min = f.number("min", 0);
    spec.max = f.number("max", 0);
    if (!(spec.min <= spec.max)) f.fail(f.path("max"), "must be at least min");
  }
  // A choice's default may be its name.
  if (f.has("default") && f.at("default").is_string() && !spec.choices.empty())
    spec.default_value = spec.parse(f.text("default"));
  else
    spec.default_value = f.number("default", spec.choices.empty() ? spec.min : 0);
  for (const json& t : f.array("tradeoff", false)) {
    if (!t.is_number()) f.fail(f.path("tradeoff"), "must be numbers");
    spec.tradeoff.push_back(t.get<double>());
  }
  try {
    spec.check(spec.default_value);
    for (double t : spec.tradeoff) spec.check(t);
  } catch (const std::invalid_argument& e) {
    f.fail(f.path("default"), e.what());
  }
  return spec;
}

// The variables every expression may name, for a point (package.hpp; README, "Method packages").
Variables variables_of(const Package& pkg, const FilterOptions& o, int width_px, int height_px) {
  Variables v = {{"width", width_px},
                 {"height", height_px},
                 {"pixels", static_cast<double>(width_px) * height_px},
                 {"N", o.pattern.size_n},
                 {"k", o.pattern.spacing_px},
                 {"half_n", o.pattern.half()},
                 {"max_coc", o.pattern.max_radius_px()},
                 {"buffer_scale", o.buffer_scale}};
  for (const auto& spec : pkg.options) v[spec.key] = o.values.count(spec.key) ? o.number(spec.key) : spec.default_value;
  for (const auto& b : pkg.buffers) v[b.name + "_bytes"] = 0;  // filled below in order: later ones may read earlier ones
  for (const auto& b : pkg.buffers) v[b.name + "_bytes"] = b.elements.count(v) * static_cast<double>(b.element_bytes);
  return v;
}

std::uint64_t hash_folder(const fs::path& folder) {
  std::vector<fs::path> files;
  for (const auto& entry : fs::recursive_directory_iterator(folder))
    if (entry.is_regular_file()) files.push_back(fs::relative(entry.path(), folder));
  std::sort(files.begin(), files.end());
  std::uint64_t hash = kFnv1aOffset;
  for (const auto& f : files) {
    fnv1a(hash, f.generic_string());
    fnv1a(hash, read_text_file((folder / f).string(), "package file"));
  }
  return hash;
}

// ---- The GPU side ----

class PackageGpu final : public gpu::GpuFilter {
 public:
  PackageGpu(gpu::GpuFrame& frame, std::shared_ptr<const Package> pkg, const FilterOptions& o)
      : frame_(frame), pkg_(std::move(pkg)), options_(o), signed_coc_(frame) {
    const Variables v = variables_of(*pkg_, o, frame.params.width_px, frame.params.height_px);
    for (const auto& b : pkg_->buffers) {
      const auto bytes = static_cast<VkDeviceSize>(v.at(b.name + "_bytes"));
      buffers_.push_back(vk::make_storage_buffer(frame.ctx, std::max<VkDeviceSize>(bytes, 16), b.name.c_str()));
    }
    const std::vector<VkDescriptorType> bindings(kFixedBindings + buffers_.size(), kBuffer);
    for (const auto& pass : pkg_->passes) {
      std::vector<std::int32_t> constants;
      for (const auto& c : pass.constants) {
        if (constants.size() <= c.id) constants.resize(c.id + 1, 0);
        const double value = c.value.evaluate(v);
        constants[c.id] = c.is_float ? std::bit_cast<std::int32_t>(static_cast<float>(value)) : static_cast<std::int32_t>(value);
      }
      auto& p = pipelines_.emplace_back(frame.ctx, pass.spirv, bindings, sizeof(gpu::PassParams), constants, pass.local_size);
      p.bind(0, frame.color);
      p.bind(1, frame.depth);
      p.bind(2, signed_coc_.buffer);
      p.bind(3, frame.packed);
      p.bind(4, frame.output);
      for (std::size_t b = 0; b < buffers_.size(); ++b) p.bind(static_cast<std::uint32_t>(kFixedBindings + b), buffers_[b]);
    }
  }
  void record(VkCommandBuffer cmd, vk::TimestampQueries& timer) override {
    mark_progress(cmd, 0);
    signed_coc_.dispatch(cmd);
    timer.end_pass(cmd, "prepare");
    // The grid follows the frame's size as it is now (warm_up records a 16 x 16 corner).
    const Variables v = variables_of(*pkg_, options_, frame_.params.width_px, frame_.params.height_px);
    for (std::size_t k = 0; k < pipelines_.size(); ++k) {
      const PassDecl& pass = pkg_->passes[k];
      mark_progress(cmd, static_cast<std::uint32_t>(k + 1));
      pipelines_[k].dispatch(cmd, &frame_.params, static_cast<std::uint32_t>(pass.invocations[0].count(v)),
                             static_cast<std::uint32_t>(pass.invocations[1].count(v)));
      timer.end_pass(cmd, pass.name);
    }
  }
  std::string running_pass() const override {
    const auto k = *static_cast<const volatile std::uint32_t*>(progress_.mapped());
    return k == 0 ? "prepare" : k <= pkg_->passes.size() ? pkg_->passes[k - 1].name : "";
  }
  std::uint64_t intermediate_bytes() const override {
    std::uint64_t bytes = signed_coc_.buffer.allocated_bytes();
    for (const auto& b : buffers_) bytes += b.allocated_bytes();
    return bytes;
  }

 private:
  gpu::GpuFrame& frame_;
  std::shared_ptr<const Package> pkg_;
  FilterOptions options_;
  // The pass about to run, written by the device in command order: what running_pass() reads
  // when a submission runs past the watchdog (a package's shader may loop without end). The barrier
  // orders each mark after the one before (the validation layer's write-after-write hazard).
  void mark_progress(VkCommandBuffer cmd, std::uint32_t pass) {
    vkCmdFillBuffer(cmd, progress_.get(), 0, 4, pass);
    VkMemoryBarrier written{VK_STRUCTURE_TYPE_MEMORY_BARRIER};
    written.srcAccessMask = written.dstAccessMask = VK_ACCESS_TRANSFER_WRITE_BIT;
    vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_PIPELINE_STAGE_TRANSFER_BIT, 0, 1, &written, 0, nullptr, 0,
                         nullptr);
  }

  gpu::SignedCocPass signed_coc_;
  vk::Buffer progress_{frame_.ctx, 4, VK_BUFFER_USAGE_TRANSFER_DST_BIT, vk::Buffer::Where::host};
  std::vector<vk::Buffer> buffers_;
  std::deque<vk::ComputePipeline> pipelines_;
};

// The built-in reference's options for a package's: its defaults, with the values of options both name.
FilterOptions reference_options(const Method& reference, const FilterOptions& o) {
  FilterOptions r = reference.defaults(o.pattern);
  r.aperture = o.aperture;
  for (auto& [key, value] : r.values)
    if (o.values.count(key)) value = o.values.at(key);
  return r;
}

// ---- The manifest into a Method ----

// The manifest's intermediates (bindings 5, 6, ... in order), each checked.
std::vector<BufferDecl> read_buffers(const Fields& top, const std::string& file) {
  std::vector<BufferDecl> out;
  std::set<std::string> names;
  const json& buffers = top.array("buffers", false);
  for (std::size_t i = 0; i < buffers.size(); ++i) {
    const Fields f(buffers[i], fmt::format("buffers[{}]", i), file);
    f.only({"name", "format", "elements"});
    BufferDecl b{f.text("name"), f.text("format"), 0, f.expression("elements")};
    if (!std::regex_match(b.name, std::regex("[a-z][a-z0-9_]*"))) f.fail(f.path("name"), "must match [a-z][a-z0-9_]*");
    if (!names.insert(b.name).second) f.fail(f.path("name"), "'" + b.name + "' is declared twice");
    if (!(b.element_bytes = element_bytes(b.format)))
      f.fail(f.path("format"), fmt::format("'{}' is not one of r32f, r32ui, r32i, rg32f, rgba16f, rgba32f, rgba32ui", b.format));
    out.push_back(std::move(b));
  }
  return out;
}

// The manifest's passes in order: grid, workgroup, specialization constants, work model.
std::vector<PassDecl> read_passes(const Fields& top, const std::string& file) {
  std::vector<PassDecl> out;
  const json& passes = top.array("passes", true);
  if (passes.empty()) top.fail("passes", "must name at least one pass (the last writes binding 4, the output)");
  std::set<std::string> pass_names = {"coc", "prepare"};  // the harness's own passes
  for (std::size_t i = 0; i < passes.size(); ++i) {
    const Fields f(passes[i], fmt::format("passes[{}]", i), file);
    f.only({"name", "shader", "invocations", "local_size", "constants", "work"});
    PassDecl pass;
    pass.name = f.text("name");
    if (!pass_names.insert(pass.name).second) f.fail(f.path("name"), "'" + pass.name + "' is taken (names are unique; coc and prepare are the harness's)");
    pass.shader = f.text("shader");
    const json& grid = f.array("invocations", true);
    if (grid.size() != 2) f.fail(f.path("invocations"), "must be two expressions: [x, y]");
    for (int a = 0; a < 2; ++a) {
      if (!grid[a].is_string() && !grid[a].is_number()) f.fail(f.path("invocations"), "must be expressions (strings) or numbers");
      pass.invocations[a] = Expression(grid[a].is_string() ? grid[a].get<std::string>() : grid[a].dump(),
                                       fmt::format("{}: {}[{}]", file, f.path("invocations"), a));
    }
    const json& local = f.array("local_size", false);
    if (!local.empty()) {
      if (local.size() != 2 || !local[0].is_number_unsigned() || !local[1].is_number_unsigned() || local[0] == 0 || local[1] == 0)
        f.fail(f.path("local_size"), "must be two whole numbers >= 1: [x, y]");
      pass.local_size = {local[0].get<std::uint32_t>(), local[1].get<std::uint32_t>()};
    }
    const json& constants = f.array("constants", false);
    for (std::size_t c = 0; c < constants.size(); ++c) {
      const Fields cf(constants[c], f.path(fmt::format("constants[{}]", c)), file);
      cf.only({"id", "type", "value"});
      const double id = cf.number("id", -1);
      if (!(id >= 0 && id < 100 && id == std::floor(id))) cf.fail(cf.path("id"), "must be a whole number in [0, 99] (100, 101: the workgroup size)");
      const std::string type = cf.text_or("type", "int");
      if (type != "int" && type != "float") cf.fail(cf.path("type"), "must be int or float");
      pass.constants.push_back({static_cast<std::uint32_t>(id), type == "float", cf.expression("value")});
    }
    if (f.has("work")) {
      const Fields wf(f.at("work"), f.path("work"), file);
      wf.only({"taps", "bytes_read", "bytes_written"});
      pass.taps = wf.expression("taps", false);
      pass.bytes_read = wf.expression("bytes_read", false);
      pass.bytes_written = wf.expression("bytes_written", false);
    }
    out.push_back(std::move(pass));
  }
  return out;
}

// Every expression evaluated once at a small frame, so a typo or an unknown variable fails at load;
// every shader compiled, so a compile error names its file and line before any work, and what each
// binds checked against what the manifest declares.
void check_and_compile(Package& pkg, const Method& m, const fs::path& folder, const std::string& file) {
  const Variables v = variables_of(pkg, m.defaults({9, 2}), 64, 48);
  for (const auto& pass : pkg.passes) {
    for (const auto& e : pass.invocations) e.count(v);
    for (const auto& c : pass.constants) c.value.evaluate(v);
    for (const Expression* e : {&pass.taps, &pass.bytes_read, &pass.bytes_written})
      if (!e->empty()) e->evaluate(v);
  }
  const std::uint64_t source_hash = pkg.hash ^ package::shader_library_hash();
  for (auto& pass : pkg.passes) {
    if (!fs::is_regular_file(folder / pass.shader))
      throw std::invalid_argument(fmt::format("{}: passes '{}': shader '{}' is not a file in the package", file, pass.name, pass.shader));
    pass.spirv = package::compile_compute_shader(folder, pass.shader, source_hash);
    const std::uint32_t declared = kFixedBindings + static_cast<std::uint32_t>(pkg.buffers.size());
    for (const auto& [set, binding] : package::descriptor_bindings(pass.spirv))
      if (set != 0 || binding >= declared)
        throw std::invalid_argument(fmt::format(
            "{}: passes '{}': {} binds set {} binding {}, which the manifest does not declare (set 0: bindings 0-4 "
            "are the harness's, {})",
            file, pass.name, pass.shader, set, binding,
            pkg.buffers.empty() ? std::string("and the manifest declares no buffers")
                                : fmt::format("5-{} the manifest's buffers in order", declared - 1)));
  }
}

// The Method's functions over the loaded package: plan, GPU driver, work, memory, tolerances and the
// built-in CPU reference it names.
void set_functions(Method& m, std::shared_ptr<const Package> shared, const std::string& file, double gpu_tolerance,
                   double storage_tolerance) {
  m.unsupported = [shared, file](const FilterOptions& o, int w, int h) -> std::string {
    try {
      const Variables v = variables_of(*shared, o, w, h);
      for (std::size_t i = 0; i < shared->buffers.size(); ++i)
        if (v.at(shared->buffers[i].name + "_bytes") <= 0)
          return fmt::format("{}: buffers[{}] ('{}'): elements '{}' is 0 at {}x{}, N = {}: a buffer needs at least one",
                             file, i, shared->buffers[i].name, shared->buffers[i].elements.text(), w, h,
                             o.pattern.size_n);
    } catch (const std::invalid_argument& e) {
      return e.what();
    }
    return "";
  };
  m.make_gpu = [shared](gpu::GpuFrame& frame, const FilterOptions& o) -> std::unique_ptr<gpu::GpuFilter> {
    return std::make_unique<PackageGpu>(frame, shared, o);
  };
  m.work = [shared](const FilterOptions& o, int w, int h) {
    const double px = static_cast<double>(w) * h;
    std::vector<PassWork> work = {{"prepare", px, px * 36, px * 16}};  // as the built-ins' signed-CoC pass
    const Variables v = variables_of(*shared, o, w, h);
    const auto value = [&](const Expression& e) { return e.empty() ? 0.0 : e.evaluate(v); };
    for (const auto& pass : shared->passes)
      work.push_back({pass.name, value(pass.taps), value(pass.bytes_read), value(pass.bytes_written)});
    return work;
  };
  m.gpu_memory = [shared](const FilterOptions& o, int w, int h, vk::Context* ctx) {
    const Variables v = variables_of(*shared, o, w, h);
    MemoryUse use;
    use.bytes = static_cast<std::uint64_t>(w) * h * 16;
    use.details["signed_coc_bytes"] = use.bytes;
    for (const auto& b : shared->buffers) {
      const auto bytes = static_cast<std::uint64_t>(v.at(b.name + "_bytes"));
      if (ctx && bytes > ctx->info().max_storage_buffer_range_bytes)
        throw std::invalid_argument(fmt::format("buffer '{}' needs {} bytes at {}x{}, over {}'s maxStorageBufferRange of {}",
                                                b.name, bytes, w, h, ctx->info().name,
                                                ctx->info().max_storage_buffer_range_bytes));
      use.bytes += bytes;
      use.details[b.name + "_bytes"] = bytes;
    }
    return use;
  };
  m.gpu_tolerance = [gpu_tolerance](const FilterOptions&) { return gpu_tolerance; };
  m.storage_tolerance = [storage_tolerance](const FilterOptions&) { return storage_tolerance; };
  if (const Method* r = shared->reference_method) {
    m.cpu_reference = [r](const CpuInput& in) {
      const FilterOptions options = reference_options(*r, in.options);
      return r->cpu_reference({in.color, in.depth_m, in.lens, in.radius_px, in.packed, options, in.threads, in.stats});
    };
    m.cpu_memory_bytes = [r](const FilterOptions& o, int w, int h) {
      return r->cpu_memory_bytes ? r->cpu_memory_bytes(reference_options(*r, o), w, h) : 0;
    };
    m.cpu_work = [r](const FilterOptions& o, int w, int h) {
      const FilterOptions options = reference_options(*r, o);
      return r->cpu_work ? r->cpu_work(options, w, h) : r->work(options, w, h);
    };
  }
}

// `folder`: where the files are (a temporary checkout for FOLDER@REV); `home`: the folder results name.
Method read_package(const std::string& reference, const fs::path& folder, const fs::path& home, const std::string& rev,
                    const std::set<std::string>& taken) {
  const fs::path manifest_path = folder / kPackageManifest;
  const std::string file = reference + "/" + kPackageManifest;
  if (!fs::is_regular_file(manifest_path))
    throw std::invalid_argument(fmt::format("'{}' is not a method package: it has no {}", reference, kPackageManifest));
  json manifest;
  try {
    manifest = json::parse(read_text_file(manifest_path.string(), "package manifest"));
  } catch (const json::parse_error& e) {
    throw std::invalid_argument(fmt::format("{}: not valid JSON: {}", file, e.what()));
  }
  const Fields top(manifest, "", file);
  top.only({"$schema", "name", "description", "precisions", "samples_pattern", "buffer_scales", "options", "buffers",
            "passes", "cpu_reference", "gpu_tolerance", "storage_tolerance", "conserves_energy", "energy_note"});

  auto pkg = std::make_shared<Package>();
  pkg->reference = reference;
  pkg->path = fs::absolute(home).lexically_normal().string();
  pkg->rev = rev;
  pkg->hash = hash_folder(folder);
  pkg->name = top.text("name");
  if (!std::regex_match(pkg->name, std::regex("[a-z][a-z0-9_]*")))
    top.fail("name", fmt::format("'{}' must match [a-z][a-z0-9_]* (it names the method in results)", pkg->name));
  for (const Method& m : registered_methods())
    if (m.name == pkg->name) top.fail("name", fmt::format("'{}' is a built-in method's name: choose another", pkg->name));

  Method m;
  m.name = taken.count(pkg->name) ? fmt::format("{}@{:08x}", pkg->name, pkg->hash >> 32) : pkg->name;
  m.description = top.text_or("description", "method package " + pkg->name);
  m.in_default_sweeps = false;  // a package runs where it is named
  m.samples_pattern = top.flag("samples_pattern", true);
  for (const json& p : top.array("precisions", false)) {
    if (!p.is_string()) top.fail("precisions", "must be strings");
    m.precisions.push_back(p.get<std::string>());
  }
  if (m.precisions.empty()) m.precisions = {"f32"};
  // Resolution divisors of its intermediates (the variable buffer_scale): sweeps take each, as FLAG's.
  if (top.has("buffer_scales")) {
    m.buffer_scales.clear();
    for (const json& b : top.array("buffer_scales", true)) {
      if (!b.is_number_unsigned() || b.get<int>() < 1 || b.get<int>() > 64)
        top.fail("buffer_scales", "must be whole numbers from 1 to 64");
      if (std::find(m.buffer_scales.begin(), m.buffer_scales.end(), b.get<int>()) == m.buffer_scales.end())
        m.buffer_scales.push_back(b.get<int>());
    }
    if (std::find(m.buffer_scales.begin(), m.buffer_scales.end(), 1) == m.buffer_scales.end())
      top.fail("buffer_scales", "must include 1 (full resolution, the default)");
  }
  const json& options = top.array("options", false);
  for (std::size_t i = 0; i < options.size(); ++i) m.options.push_back(read_option(Fields(options[i], fmt::format("options[{}]", i), file)));
  pkg->options = m.options;

  pkg->buffers = read_buffers(top, file);
  pkg->passes = read_passes(top, file);

  if (top.has("cpu_reference")) {
    const Fields f(top.at("cpu_reference"), "cpu_reference", file);
    f.only({"builtin"});
    const std::string builtin = f.text("builtin");
    const auto& all = registered_methods();
    const auto it = std::find_if(all.begin(), all.end(), [&](const Method& b) { return b.name == builtin; });
    if (it == all.end()) f.fail(f.path("builtin"), fmt::format("'{}' is not a built-in method", builtin));
    pkg->reference_method = &*it;
  }
  const double gpu_tolerance = top.number("gpu_tolerance", 1e-5);
  const double storage_tolerance = top.number("storage_tolerance", 0);
  if (!(gpu_tolerance >= 0) || !(storage_tolerance >= 0)) top.fail("gpu_tolerance", "and storage_tolerance must be >= 0");
  m.conserves_energy = top.flag("conserves_energy", false);
  m.energy_note = top.text_or("energy_note", m.conserves_energy ? "" : "the package does not declare that it conserves energy");

  check_and_compile(*pkg, m, folder, file);

  m.package = {{"name", pkg->name}, {"hash", fmt::format("{:016x}", pkg->hash)}, {"path", pkg->path}};
  if (!rev.empty()) m.package["rev"] = rev;

  set_functions(m, pkg, file, gpu_tolerance, storage_tolerance);
  return m;
}

struct Loaded {
  std::string key;  // canonical folder [@rev]
  Method method;
};

std::deque<Loaded>& packages() {
  static std::deque<Loaded> all;
  return all;
}

// FOLDER@REV into a temporary copy of FOLDER as it was at REV (git archive of the repository holding it).
fs::path checkout_at(const fs::path& folder, const std::string& rev) {
  const auto run = [](const std::string& command) {
    std::string out;
    if (FILE* pipe = popen((command + " 2>&1").c_str(), "r")) {
      char chunk[4096];
      for (std::size_t n; (n = std::fread(chunk, 1, sizeof chunk, pipe)) > 0;) out.append(chunk, n);
      if (pclose(pipe) == 0) return std::pair{true, out};
    }
    return std::pair{false, out};
  };
  const auto quote = [](const std::string& s) {
    std::string q = "'";
    for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
    return q + "'";
  };
  const std::string dir = quote(fs::absolute(folder).string());
  const auto [ok, lines] = run("git -C " + dir + " rev-parse --show-toplevel --show-prefix");
  if (!ok) throw std::invalid_argument(fmt::format("'{}@{}': the folder is not in a git repository: {}", folder.string(), rev, lines));
  std::istringstream in(lines);
  std::string top, prefix;
  std::getline(in, top);
  std::getline(in, prefix);
  const fs::path out = fs::temp_directory_path() / fmt::format("bokehbench-package-{}-{}", getpid(), packages().size());
  fs::create_directories(out);
  const auto [archived, message] =
      run(fmt::format("git -C {} archive --format=tar {}:{} | tar -x -C {}", quote(top), quote(rev), quote(prefix), quote(out.string())));
  if (!archived || !fs::is_regular_file(out / kPackageManifest))
    throw std::invalid_argument(fmt::format("'{}@{}': no package at that revision ({})", folder.string(), rev,
                                            message.empty() ? std::string("no ") + kPackageManifest : message));
  return out;
}

std::pair<fs::path, std::string> split_reference(const std::string& reference) {
  const auto at = reference.rfind('@');
  if (at != std::string::npos && at > 0 && !fs::is_directory(reference)) return {reference.substr(0, at), reference.substr(at + 1)};
  return {reference, ""};
}

}  // namespace

bool is_package_reference(const std::string& reference) {
  const auto [folder, rev] = split_reference(reference);
  std::error_code ec;
  return fs::is_regular_file(folder / kPackageManifest, ec);
}

const Method& load_package(const std::string& reference) {
  const auto [folder, rev] = split_reference(reference);
  std::error_code ec;
  const fs::path canonical = fs::weakly_canonical(folder, ec);
  const std::string key = (ec ? folder : canonical).string() + (rev.empty() ? "" : "@" + rev);
  auto& all = packages();
  for (const auto& p : all)
    if (p.key == key) return p.method;
  std::set<std::string> taken;
  for (const auto& p : all) taken.insert(p.method.name);
  if (rev.empty()) {
    all.push_back({key, read_package(reference, folder, folder, rev, taken)});
  } else {  // the checkout is needed while loading only: the shaders are compiled by then
    const fs::path checkout = checkout_at(folder, rev);
    struct Remove {
      fs::path dir;
      ~Remove() { std::error_code ec; fs::remove_all(dir, ec); }
    } remove{checkout};
    all.push_back({key, read_package(reference, checkout, folder, rev, taken)});
  }
  return all.back().method;
}

std::vector<const Method*> loaded_packages() {
  std::vector<const Method*> out;
  for (const auto& p : packages()) out.push_back(&p.method);
  return out;
}

}  // namespace bokeh
