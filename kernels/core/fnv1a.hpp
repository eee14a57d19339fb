#pragma once
// FNV-1a, 64 bits: a stable content hash (the same on every machine and build), for cache keys and
// the identity of a method package. Not for security.
#include <cstddef>
#include <cstdint>
#include <string_view>

namespace bokeh {

inline constexpr std::uint64_t kFnv1aOffset = 14695981039346656037ull;

inline void fnv1a(std::uint64_t& hash, const void* data, std::size_t bytes) {
  const auto* p = static_cast<const unsigned char*>(data);
  for (std::size_t i = 0; i < bytes; ++i) hash = (hash ^ p[i]) * 1099511628211ull;
}

inline void fnv1a(std::uint64_t& hash, std::string_view text) { fnv1a(hash, text.data(), text.size()); }

// The hash of one text on its own.
inline std::uint64_t fnv1a(std::string_view text) {
  std::uint64_t hash = kFnv1aOffset;
  fnv1a(hash, text);
  return hash;
}

}  // namespace bokeh
