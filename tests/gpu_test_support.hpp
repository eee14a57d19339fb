#pragma once
// The one Vulkan context a GPU test binary shares: created on first use (lavapipe unless a GPU is
// present), so device start-up is paid once per binary rather than once per test.
#include "vk/context.hpp"

namespace bokeh::test {

inline vk::Context& context() {
  static vk::Context ctx;
  return ctx;
}

}  // namespace bokeh::test
