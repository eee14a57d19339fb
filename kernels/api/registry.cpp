// Lookups over the registered methods (the list itself is generated from kernels/CMakeLists.txt) and
// the method packages loaded beside them.
#include <stdexcept>

#include "method.hpp"
#include "package.hpp"

namespace bokeh {

std::vector<const Method*> known_methods() {
  std::vector<const Method*> all;
  for (const Method& m : registered_methods()) all.push_back(&m);
  for (const Method* p : loaded_packages()) all.push_back(p);
  return all;
}

const Method& find_method(const std::string& name) {
  std::string known;
  for (const Method* m : known_methods()) {
    if (m->name == name) return *m;
    known += (known.empty() ? "" : ", ") + m->name;
  }
  if (is_package_reference(name)) return load_package(name);
  throw std::invalid_argument("unknown method '" + name + "' (known: " + known +
                              "; or a method package: a folder holding " + kPackageManifest + ")");
}

}  // namespace bokeh
