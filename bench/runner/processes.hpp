#pragma once
// A sweep measured by several processes one after another (--processes P), their rounds joined into
// one run.
//
// Why: two runs of the same build on one machine differ by more than either run's rounds show. A
// process is one draw of what stays fixed while it lives (on the EPYC VM: each point's allocations,
// its GPU vertical pass by up to 35%, and the machine's phase over its minutes; not heap or code addresses, the same
// with address randomisation off, nor page size, the same with huge pages): an `ab` of two identical
// builds put one point 5% apart between processes, far outside each process's own interval, and
// freeing and re-preparing every target inside one process did not redraw it. Rounds cannot show what they all share. Runs
// split over processes can: the spread of a figure between them (against what each one's rounds
// imply) measures that term on this machine in this run, with no earlier runs (derive_figure9 uses
// it). Each process k of P is this same command line with `--process k/P` added: it measures every
// point for budget_s / P with seed + k - 1, writes its results into part_dir(), and nothing else.
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "runner.hpp"
#include "sweep.hpp"

namespace bokeh::processes {

// Where process `index` of a run writes its results: <out_dir>/<name>.processes/<index>.
std::string part_dir(const std::string& out_dir, const std::string& name, int index);

struct Joined {
  // Every process's rounds in turn (round_process says whose), each point's samples with their rounds
  // renumbered, the probes' times per round; status complete only when every process completed.
  runner::RunRecord record;
  // Per point (as `ids`), its results entry from the first process that measured it (what it knows
  // beyond its samples: work, memory, error, counters); null when none did.
  std::vector<nlohmann::json> points;
};

// The results files of processes 1..before of a run (part_dir, complete or partial), joined as run()
// joins them: the rounds process `before + 1` follows when it judges which figures are still too wide
// (SweepSettings::run_out_dir). A missing file throws std::runtime_error naming it.
Joined join_earlier(const std::vector<std::string>& ids, const std::string& out_dir, const std::string& name,
                    int before);

// Runs settings.processes processes of this command line in turn and joins what they wrote. An
// interruption (forwarded to the process running) or a process that fails ends the run there, with
// what the finished processes measured (status "interrupted"); throws std::runtime_error when the
// first one fails before writing anything.
Joined run(const std::vector<std::string>& ids, const SweepSettings& settings);

}  // namespace bokeh::processes
