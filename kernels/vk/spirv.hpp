#pragma once
// SPIR-V of every shader variant, embedded at build time (shaders/spirv.cmake), by "<folder>/<name>".
#include <cstdint>
#include <map>
#include <span>
#include <stdexcept>
#include <string>

namespace bokeh::vk {

// Defined in the generated library bokeh_spirv.
const std::map<std::string, std::span<const std::uint32_t>>& spirv_variants();

inline std::span<const std::uint32_t> spirv(const std::string& variant) {
  const auto& all = spirv_variants();
  const auto it = all.find(variant);
  if (it == all.end()) throw std::logic_error("no SPIR-V variant '" + variant + "' (see shaders/*/variants.cmake)");
  return it->second;
}

}  // namespace bokeh::vk
