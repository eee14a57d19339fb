#pragma once
// ceil(a / b) for non-negative integers: workgroups to cover invocations, tiles to cover pixels,
// reduced-resolution extents. Mixed argument types meet in their common type, as the division would.
#include <concepts>
#include <type_traits>

namespace bokeh {

template <std::integral A, std::integral B>
constexpr std::common_type_t<A, B> ceil_div(A a, B b) {
  using T = std::common_type_t<A, B>;
  return (static_cast<T>(a) + static_cast<T>(b) - 1) / static_cast<T>(b);
}

}  // namespace bokeh
