// Lookups over the registered methods (the list itself is generated from kernels/CMakeLists.txt).
#include <stdexcept>

#include "method.hpp"

namespace bokeh {

const Method& find_method(const std::string& name) {
  std::string known;
  for (const auto& m : registered_methods()) {
    if (m.name == name) return m;
    known += (known.empty() ? "" : ", ") + m.name;
  }
  throw std::invalid_argument("unknown method '" + name + "' (known: " + known + ")");
}

}  // namespace bokeh
