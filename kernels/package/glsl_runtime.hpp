#pragma once
// GLSL compute shaders compiled at run time (glslang as a library), for method packages. Includes
// ("#include" with GL_GOOGLE_include_directive) resolve beside the including file, in the package's
// folder, then in the harness's shader library: shaders/common's files by name ("common.glsl") and
// every built-in's by "<folder>/<file>" ("hexagon/blur.glsl"), embedded at build time.
#include <cstdint>
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

namespace bokeh::package {

// The SPIR-V of `file` (in `folder`), for Vulkan 1.1. Cached by `source_hash` (which must cover every
// file the shader can include): in this process, and on disk in $BOKEHBENCH_CACHE_DIR, else
// $XDG_CACHE_HOME/bokehbench/spirv, else ~/.cache/bokehbench/spirv (a cache that cannot be written is
// skipped). Throws std::invalid_argument with glslang's messages, each naming the file and line.
std::vector<std::uint32_t> compile_compute_shader(const std::filesystem::path& folder, const std::string& file,
                                                  std::uint64_t source_hash);

// The (descriptor set, binding) pairs the SPIR-V's resources are decorated with, from its
// OpDecorate instructions: what a shader binds, checked against what its manifest declares.
std::vector<std::pair<std::uint32_t, std::uint32_t>> descriptor_bindings(const std::vector<std::uint32_t>& spirv);

// A hash of the embedded shader library (part of every package shader's source hash).
std::uint64_t shader_library_hash();

}  // namespace bokeh::package
