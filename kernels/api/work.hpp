#pragma once
#include <string>

namespace bokeh {

// The work one frame of a pass does, by the method's model (not timed, so it compares exactly across
// runs; a change is an algorithmic change): throughput is this over the pass's measured time.
struct PassWork {
  std::string pass;          // the timestamp name of the pass
  double taps = 0;           // input samples evaluated (the pattern's, for pixels inside the image)
  double bytes_read = 0;     // compulsory traffic: every buffer the pass reads, once
  double bytes_written = 0;  // every buffer the pass writes, once
  // What a fused pass keeps out of memory that the unfused passes move (FLAG's layers, written once
  // and read once): the pass's speed counted as the unfused passes' work, (read + written + kept) / time.
  double bytes_kept = 0;
};

}  // namespace bokeh
