#pragma once
// Method packages: a filter from outside the tree, with no C++ and no rebuild. A package is a folder
// holding bokeh-package.json (the manifest: passes, intermediates, options, work and memory as
// expressions; schema in kernels/package/manifest.schema.json, README "Method packages") and GLSL
// compute shaders, compiled at run time (glslang) and cached by source hash. Loaded, it is a Method
// like the built-ins: the runner, the commands and the conformance checks cannot tell them apart.
#include <string>

#include "method.hpp"

namespace bokeh {

// The file that makes a folder a package.
inline constexpr const char* kPackageManifest = "bokeh-package.json";

// True when `reference` names a package: a folder holding a manifest, or FOLDER@GIT-REV (the folder
// as it was at that revision of the git repository holding it).
bool is_package_reference(const std::string& reference);

// Loads the package (once per folder and revision: later calls return the same Method), compiling
// every shader. Throws std::invalid_argument naming the file (and line, for GLSL and JSON) of the
// first problem: no manifest, a field missing or of the wrong type, an expression that does not
// parse or names an unknown variable, a shader that does not compile.
// The Method's name is the manifest's; a second package of that name (another version) is named
// NAME@HASH8. Method::package holds {name, hash, path[, rev]}: results carry it, so a history series
// follows the package by name across edits and its hash says when it changed.
const Method& load_package(const std::string& reference);

// The packages loaded so far, in load order.
std::vector<const Method*> loaded_packages();

}  // namespace bokeh
