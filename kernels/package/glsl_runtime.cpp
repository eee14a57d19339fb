#include "glsl_runtime.hpp"

#include <algorithm>
#include <cstdlib>
#include <cstring>
#include <map>
#include <memory>
#include <mutex>
#include <set>
#include <stdexcept>

#include <fmt/format.h>
#include <glslang/Public/ResourceLimits.h>
#include <glslang/Public/ShaderLang.h>
#include <glslang/SPIRV/GlslangToSpv.h>
#include <glslang/build_info.h>

#include "atomic_file.hpp"
#include "fnv1a.hpp"
#include "text_file.hpp"

namespace bokeh::package {

// Generated from shaders/**/*.glsl (kernels/CMakeLists.txt): "<folder>/<file>" -> text, and
// shaders/common's files also by their bare name.
const std::map<std::string, std::string>& shader_library_files();

namespace {

namespace fs = std::filesystem;
constexpr const char* kLibraryPrefix = "bokehbench:";

std::uint64_t library_hash() {
  std::uint64_t hash = kFnv1aOffset;
  for (const auto& [name, text] : shader_library_files()) {
    fnv1a(hash, name);
    fnv1a(hash, text);
  }
  return hash;
}

// Resolves includes as glsl_runtime.hpp says. Results are named "<path in the package>" or
// "bokehbench:<library name>", the names glslang's messages then carry.
class Includer final : public glslang::TShader::Includer {
 public:
  explicit Includer(fs::path folder) : folder_(std::move(folder)) {}

  IncludeResult* includeLocal(const char* header, const char* includer, size_t) override { return resolve(header, includer); }
  IncludeResult* includeSystem(const char* header, const char* includer, size_t) override { return resolve(header, includer); }
  void releaseInclude(IncludeResult* result) override {
    if (result) delete static_cast<std::string*>(result->userData);
    delete result;
  }

 private:
  IncludeResult* resolve(const std::string& header, const std::string& includer) {
    const auto& library = shader_library_files();
    if (includer.rfind(kLibraryPrefix, 0) == 0) {  // beside a library file first
      const fs::path beside = fs::path(includer.substr(std::string(kLibraryPrefix).size())).parent_path() / header;
      if (const auto it = library.find(beside.lexically_normal().generic_string()); it != library.end())
        return result(kLibraryPrefix + it->first, it->second);
    } else {
      for (const fs::path& candidate : {fs::path(includer).parent_path() / header, fs::path(header)})
        if (const fs::path file = folder_ / candidate; fs::is_regular_file(file))
          return result(candidate.lexically_normal().generic_string(), read_text_file(file.string(), "shader include"));
    }
    if (const auto it = library.find(header); it != library.end()) return result(kLibraryPrefix + it->first, it->second);
    return nullptr;  // glslang reports it, naming the file and line of the #include
  }
  static IncludeResult* result(const std::string& name, const std::string& text) {
    auto* owned = new std::string(text);
    return new IncludeResult(name, owned->data(), owned->size(), owned);
  }
  fs::path folder_;
};

fs::path cache_dir() {
  if (const char* dir = std::getenv("BOKEHBENCH_CACHE_DIR"); dir && *dir) return dir;
  if (const char* xdg = std::getenv("XDG_CACHE_HOME"); xdg && *xdg) return fs::path(xdg) / "bokehbench" / "spirv";
  if (const char* home = std::getenv("HOME"); home && *home) return fs::path(home) / ".cache" / "bokehbench" / "spirv";
  return {};
}

std::vector<std::uint32_t> read_cached(const fs::path& file) {
  std::error_code ec;
  if (!fs::is_regular_file(file, ec)) return {};
  const std::string bytes = read_text_file(file.string(), "SPIR-V cache entry");
  if (bytes.size() < 20 || bytes.size() % 4 != 0) return {};
  std::vector<std::uint32_t> words(bytes.size() / 4);
  std::memcpy(words.data(), bytes.data(), bytes.size());
  return words[0] == 0x07230203u ? words : std::vector<std::uint32_t>{};  // the SPIR-V magic number
}

std::vector<std::uint32_t> compile(const fs::path& folder, const std::string& file) {
  static std::once_flag initialised;
  std::call_once(initialised, [] {
    glslang::InitializeProcess();
    std::atexit([] { glslang::FinalizeProcess(); });
  });
  const std::string source = read_text_file((folder / file).string(), "shader");
  glslang::TShader shader(EShLangCompute);
  const char* text = source.c_str();
  const char* name = file.c_str();
  shader.setStringsWithLengthsAndNames(&text, nullptr, &name, 1);
  shader.setEnvInput(glslang::EShSourceGlsl, EShLangCompute, glslang::EShClientVulkan, 100);
  shader.setEnvClient(glslang::EShClientVulkan, glslang::EShTargetVulkan_1_1);
  shader.setEnvTarget(glslang::EShTargetSpv, glslang::EShTargetSpv_1_3);
  Includer includer(folder);
  const auto messages = static_cast<EShMessages>(EShMsgSpvRules | EShMsgVulkanRules);
  const auto failed = [&](const char* log) {
    return std::invalid_argument(fmt::format("{} does not compile (glslang):\n{}", (folder / file).string(), log));
  };
  if (!shader.parse(GetDefaultResources(), 450, false, messages, includer)) throw failed(shader.getInfoLog());
  glslang::TProgram program;
  program.addShader(&shader);
  if (!program.link(messages)) throw failed(program.getInfoLog());
  std::vector<std::uint32_t> spirv;
  glslang::SpvOptions options;
  options.validate = true;  // glslang's own SPIR-V validation (spirv-tools) before any driver sees it
  glslang::GlslangToSpv(*program.getIntermediate(EShLangCompute), spirv, &options);
  return spirv;
}

}  // namespace

std::uint64_t shader_library_hash() {
  static const std::uint64_t hash = library_hash();
  return hash;
}

std::vector<std::uint32_t> compile_compute_shader(const fs::path& folder, const std::string& file,
                                                  std::uint64_t source_hash) {
  std::uint64_t key = source_hash;
  fnv1a(key, file);
  const std::string compiler = fmt::format("glslang {}.{}.{} vulkan1.1 spv1.3", GLSLANG_VERSION_MAJOR,
                                           GLSLANG_VERSION_MINOR, GLSLANG_VERSION_PATCH);
  fnv1a(key, compiler);
  static std::mutex mutex;
  static std::map<std::uint64_t, std::vector<std::uint32_t>> in_process;
  const std::lock_guard lock(mutex);
  if (const auto it = in_process.find(key); it != in_process.end()) return it->second;
  const fs::path dir = cache_dir();
  const fs::path cached = dir.empty() ? fs::path() : dir / fmt::format("{:016x}.spv", key);
  std::vector<std::uint32_t> spirv = cached.empty() ? std::vector<std::uint32_t>{} : read_cached(cached);
  if (spirv.empty()) {
    spirv = compile(folder, file);
    try {  // a cache that cannot be written costs a compile next time, nothing more
      fs::create_directories(dir);
      write_text_file_atomically(cached.string(),
                                 std::string_view(reinterpret_cast<const char*>(spirv.data()), spirv.size() * 4),
                                 "SPIR-V cache entry");
    } catch (const std::exception&) {
    }
  }
  return in_process[key] = spirv;
}

std::vector<std::pair<std::uint32_t, std::uint32_t>> descriptor_bindings(const std::vector<std::uint32_t>& spirv) {
  constexpr std::uint32_t kOpDecorate = 71, kBinding = 33, kDescriptorSet = 34, kHeaderWords = 5;
  std::map<std::uint32_t, std::pair<std::uint32_t, std::uint32_t>> by_id;  // id -> (set, binding)
  std::set<std::uint32_t> bound;
  for (std::size_t at = kHeaderWords; at < spirv.size();) {
    const std::uint32_t words = spirv[at] >> 16, opcode = spirv[at] & 0xffff;
    if (words == 0 || at + words > spirv.size()) break;  // malformed: glslang's output never is
    if (opcode == kOpDecorate && words >= 4) {
      const std::uint32_t id = spirv[at + 1], decoration = spirv[at + 2], value = spirv[at + 3];
      if (decoration == kDescriptorSet) by_id[id].first = value;
      if (decoration == kBinding) by_id[id].second = value, bound.insert(id);
    }
    at += words;
  }
  std::vector<std::pair<std::uint32_t, std::uint32_t>> out;
  for (std::uint32_t id : bound) out.push_back(by_id[id]);
  std::sort(out.begin(), out.end());
  return out;
}

}  // namespace bokeh::package
