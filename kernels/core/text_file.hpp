#pragma once
// Reading a whole text file (results JSON, a lens file) with every failure named: the path, and what is
// wrong (no such file, a directory, no permission, a read error), never a bare stream error.
#include <string>

namespace bokeh {

// The file's bytes. Throws std::runtime_error "<path>: <why> (<what>)", e.g.
// "results/a: it is a directory, not a file (results file)".
std::string read_text_file(const std::string& path, const std::string& what);

}  // namespace bokeh
