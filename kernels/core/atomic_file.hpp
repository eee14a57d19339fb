#pragma once
// The one way bokehbench writes a file (results JSON, images, cached references, sweep partial files):
// into a temporary beside the target, flushed to disk (fsync), then renamed over it. Readers, and a run
// that dies mid-write, see the old file or the new one, never a part; a write that fails (disk full,
// read-only folder, a file-size limit) leaves the old file byte for byte, removes its temporary, and
// throws naming the target. A target that is one of the command's inputs is refused.
#include <functional>
#include <string>
#include <string_view>
#include <vector>

namespace bokeh {

// Writes `path` atomically. `fill` writes the whole content into the file named by its argument (a
// temporary in the target's folder, created empty and reserved for this write: "<path>.tmp.<pid>", or
// "<path>.tmp.<pid>-<n>" while another thread of this process writes the same target); it throws
// std::exception with the reason on failure. Then the temporary is fsynced and renamed over `path`, and the
// folder fsynced. The folder must exist (a missing one is an error). On any failure the temporary is removed, `path` is
// left as it was, and std::runtime_error "cannot write <what> '<path>': <reason>" is thrown.
// Refuses (std::runtime_error, nothing written) a `path` that is one of the protected inputs.
void write_file_atomically(const std::string& path, const std::function<void(const std::string& temporary)>& fill,
                           const std::string& what = "file");

// For a `fill`: writes `bytes` into the existing file `file` (truncating it), checking every write and the
// close (a full disk or a file-size limit fails here, unlike in writers that ignore short writes). Throws
// std::runtime_error with the reason.
void write_whole_file(const std::string& file, std::string_view bytes);

// write_file_atomically with `text` as the content.
void write_text_file_atomically(const std::string& path, std::string_view text, const std::string& what = "file");

// The command's input files, by any name (hard links, symlinks, relative paths): every later
// write_file_atomically refuses them as targets. Paths that do not exist are ignored.
void protect_inputs(const std::vector<std::string>& inputs);
// Throws std::runtime_error naming both unless `path` is none of `inputs` and none of the protected inputs
// (the same file by any name): "output 'P' is the input 'I': choose another output path".
void refuse_input_as_output(const std::string& path, const std::vector<std::string>& inputs = {});

// Removes the temporaries write_file_atomically left in `dir` when a process died mid-write (SIGKILL):
// files named *.tmp.PID or *.tmp.PID-N whose process no longer runs. Returns how many were removed.
int remove_stale_temporaries(const std::string& dir);

}  // namespace bokeh
