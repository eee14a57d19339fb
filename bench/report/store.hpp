#pragma once
// The results store: the history of every run (runs, their points, their samples), beside the
// per-run JSON files (which stay the schema'd output of one run). One interface, two back-ends:
//   SQLite (a file; the default: <out-dir>/history.sqlite), Debian's libsqlite3;
//   PostgreSQL (postgresql://... or postgres://...), libpqxx, for machines reporting to one database.
// Both run the same SQL (parameters $1, $2, ...); a run is appended in one transaction, so readers and
// concurrent writers (two sweeps, or shards, at once) see all of a run or none of it. An interrupted
// sweep is appended with its status ("interrupted"), never half-written. A run's rows go in batches (a
// multi-row INSERT a table on PostgreSQL), not a statement a row: each statement is a round trip to the
// server, and CI's figure9 run (48 points, 58 figures) took 157 of them, 17-21 ms, where 6 take 2.3-2.6 ms
// (`history cost`, 1,000 runs, a quiet 2-core EPYC VM, local socket).
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace bokeh::history {

// Bumped when a table or column changes meaning or disappears. A store of a newer version is refused
// (read or written) with a message, never altered.
constexpr int kStoreSchemaVersion = 1;

struct RunRow {
  std::int64_t id = 0;
  std::string commit;    // context.git_commit
  std::string date_utc;  // context.date_utc (ISO 8601, so text order is time order)
  std::string machine;   // machine_key(context): runs of different machines are never one statistic
  std::string sweep;     // figure9, tradeoff, ... (the results schema without "bokehbench.")
  std::string status;    // complete, interrupted, duplicate (kDuplicateShard)
  std::string shard;     // "i/n" (1-based) when the run measured a shard; "" for the whole sweep
  std::string command;   // the command line
  std::string source;    // "run" (appended by the sweep), or the file it was imported from
  std::string context;   // the run's context block, JSON text
  // A shard's run: what makes shards one sweep (sweep_identity_of); "" for the whole sweep. Stored in
  // the shard_runs table, not in runs, so that the runs table and every query on it stay as they were.
  std::string sweep_identity;
};

// The status of a shard's complete run when a complete run of the same shard of the same sweep (same
// sweep_identity and shard) is already in the store: kept (nothing measured is lost) but, like an
// interrupted run, in no series, headline series, run-to-run spread or report figure; `history list`
// shows it. The second of two tasks given the same --shard is counted once, whichever order they end in.
inline constexpr const char* kDuplicateShard = "duplicate";

struct PointRow {
  std::string point_id, method, backend;
  double median_ms = 0, q1_ms = 0, q3_ms = 0;  // wall time per frame
  double cpu_median_ms = 0;                    // process CPU time per frame (0 when not recorded)
  bool settled = false;
  std::vector<double> samples_ms, samples_cpu_ms;
  std::string package;  // a method package's content hash ("": a built-in method)
};

// A run's headline figure: what a person reads of the run (figure9's naive/FLAG ratio at one N and its
// growth exponents, adaptive's speed-ups, ab's paired new/old ratio per point, stability's safe ranges),
// with its interval when the run gave one. Stored per run beside the points, so a figure is a series
// over commits of its own: a paired ratio's interval is a few percent where single runs' per-point
// medians move 12-17% run to run.
struct HeadlineRow {
  std::string name;  // e.g. "naive_over_flag/gpu/N:9" (unique within a run)
  std::string unit;  // "ratio", "exponent", "cases"
  double value = 0;
  std::optional<double> low, high;  // the run's interval (95%), when it gave one
  std::string at;                    // headlines_of: the figure's JSON pointer in its document (figure9's)
};

// One value of a series: a run's figure for one point (or one headline figure: median_ms is its value,
// q1_ms and q3_ms its interval, or the value itself when the run gave none).
struct SeriesValue {
  std::int64_t run_id = 0;
  std::string commit, date_utc, machine, shard, sweep;
  double median_ms = 0, q1_ms = 0, q3_ms = 0, cpu_median_ms = 0;
  std::vector<double> samples_ms, samples_cpu_ms;
  bool has_interval = false;  // headline figures: q1_ms and q3_ms are the run's interval
  std::string package;        // a method package's content hash at this run ("": a built-in method)
};

// A store's connection: the SQL both back-ends run. Rows come back as text (NULL as nullopt).
class Connection {
 public:
  using Row = std::vector<std::optional<std::string>>;
  virtual ~Connection() = default;
  virtual std::vector<Row> query(const std::string& sql, const std::vector<std::string>& params = {}) = 0;
  // Rows of one table (each row's values in `columns`' order), inside the write transaction: the
  // back-end's batched way (PostgreSQL: multi-row INSERTs, one round trip per up to 500 rows; SQLite:
  // one prepared INSERT stepped per row, which its in-process calls make cheaper than a long VALUES list).
  virtual void insert_rows(const std::string& table, const std::vector<std::string>& columns,
                           const std::vector<std::vector<std::string>>& rows);
  virtual void begin_write() = 0;  // a write transaction (SQLite: BEGIN IMMEDIATE, waiting for other writers)
  virtual void commit() = 0;
  virtual void rollback() noexcept = 0;
  virtual std::string kind() const = 0;  // "sqlite" or "postgresql"
  virtual std::string id_column() const = 0;  // an auto-numbered primary key column's type
};

class Store {
 public:
  // Opens (create: creating it when missing) the store at `url`: a path or sqlite:PATH, or a
  // postgresql:// URL. Throws std::runtime_error naming the URL for a malformed URL, an unreachable
  // server, a file that is not a store, or a store of a newer schema version.
  static std::unique_ptr<Store> open(const std::string& url, bool create);

  explicit Store(std::unique_ptr<Connection> connection, const std::string& url, bool create, std::string path = "");
  // Appends one run with its points and samples in one transaction; returns its id. A complete shard
  // run whose shard of the same sweep is already there complete is appended as kDuplicateShard, and
  // *duplicate_of (when given) gets that earlier run's id (else 0). Concurrent writers of the same shard
  // are serialized (SQLite: one writer at a time; PostgreSQL: an advisory lock on the identity), so
  // exactly one of them stays complete.
  std::int64_t append(const RunRow& run, const std::vector<PointRow>& points, const std::vector<HeadlineRow>& headlines = {},
                      std::int64_t* duplicate_of = nullptr);
  // A results document (a sweep's, stability's, ab's) appended as one run: run_of, points_of and
  // headlines_of, the one way every command and import appends.
  std::int64_t append_document(const nlohmann::json& doc, const std::string& command, const std::string& source,
                               std::int64_t* duplicate_of = nullptr);
  std::vector<RunRow> runs();
  std::vector<PointRow> points(std::int64_t run_id);
  // Every complete run's value for `point_id` (of every sweep that has it), oldest first (by date, then id).
  std::vector<SeriesValue> series(const std::string& point_id);
  // The distinct point ids, with the sweep each belongs to.
  std::vector<std::pair<std::string, std::string>> point_ids();
  std::vector<HeadlineRow> headlines(std::int64_t run_id);
  // Every complete run's value of headline figure `name`, oldest first, as series() (median_ms: the value).
  std::vector<SeriesValue> headline_series(const std::string& name);
  // The distinct headline figures: (name, sweep) and their unit.
  std::vector<std::pair<std::pair<std::string, std::string>, std::string>> headline_names();
  // What the store takes on disk: PostgreSQL's database size (its tables, indexes and their overhead);
  // SQLite's file (call after the last writer closed, so the write-ahead log is checkpointed into it).
  std::uint64_t size_bytes();
  std::string kind() const { return connection_->kind(); }
  const std::string& url() const { return url_; }

 private:
  std::unique_ptr<Connection> connection_;
  std::string url_, path_;  // path_: SQLite's file
  bool has_headlines_ = false;  // a store written before headline figures were stored lacks the table
  bool has_packages_ = false;   // likewise the point_packages table (method packages' content hashes)
  bool has_shard_runs_ = false;  // likewise the shard_runs table (shards' sweep identities)
};

// What identifies the machine a run was measured on: device, driver, CPU model and cores,
// LP_NUM_THREADS. Runs with different keys are different series.
std::string machine_key(const nlohmann::json& context);

// What makes shard runs one sweep, so that a shard given twice is told from a later sweep of the same
// configuration: the sweep (schema), the commit, the config less its shard (as JSON) and the scheduler's
// job (context.sweep_id: Slurm's array job, or BOKEH_SWEEP_ID, e.g. a Kubernetes Job's uid; absent, runs
// of the same commit and config are one sweep). "" for a run that is not a shard.
std::string sweep_identity_of(const nlohmann::json& doc);

// A sweep's results document (figure9.json, ...) as a run and its points. stability.json is a run of
// headline figures only (no timed points).
RunRow run_of(const nlohmann::json& doc, const std::string& command, const std::string& source);
std::vector<PointRow> points_of(const nlohmann::json& doc);
// The document's headline figures (HeadlineRow), read from what its command derived: figure9's
// naive_over_flag and series fits, adaptive's comparisons, buffers' streamed_vs_full, an ab run's
// paired_ratios, stability's safe ranges. tradeoff has none (its Pareto front is a set, not a figure).
std::vector<HeadlineRow> headlines_of(const nlohmann::json& doc);

// How the machine's state during a run (`doc`, not yet appended) compares with its earlier runs in the
// store: per calibration probe, this run's median ms against the median of the same machine's (machine_key)
// last `recent_runs` complete runs; a probe `unusual_ratio` times slower or faster is listed in "unusual"
// once there are kMachineStateMinRuns earlier runs (against fewer, "usual" may itself be a phase).
// A shared VM has phases that last longer than a run (two figure9 runs 5 minutes apart: copy probes 1.6x
// apart, naive/FLAG ratios up to 12%), which no interval drawn from one run's rounds can cover.
constexpr int kMachineStateMinRuns = 3;
nlohmann::json machine_state(Store& store, const nlohmann::json& doc, int recent_runs = 10, double unusual_ratio = 1.3);

// How far this machine's repeat runs put each headline figure: over the same machine's (machine_key)
// latest `recent_runs` complete runs of sweep `sweep` with the same point ids as `doc` (context and
// points; not yet appended), the standard deviation of each figure that had an interval (ratios: of
// their logs, a relative spread), taken about each commit's own mean and pooled over the commits with
// two runs or more, so that a new commit starts from the machine's spread rather than from nothing.
// {"earlier_runs", "min_degrees_of_freedom", "figures": {name: {"sd", "relative", "runs", "commits",
// "degrees_of_freedom", "family"}}, "families": {family: {"sd", "figures", "degrees_of_freedom"}}}: a
// family (headline_family) pools its figures' squares and degrees of freedom, so that two earlier runs
// of one commit already measure a spread (figure9's 7 GPU ratios: 7 degrees of freedom, where each
// ratio alone has 1). A run's own rounds cannot show this spread (see repeat_run); from
// kRunToRunMinDegreesOfFreedom on (a figure: 3 runs of one commit, or 2 each of two; a family: 2 runs),
// widen_repeat_intervals uses it.
constexpr int kRunToRunMinDegreesOfFreedom = 2;
nlohmann::json run_to_run_spread(Store& store, const nlohmann::json& doc, const std::string& sweep, int recent_runs = 10);

// The family a headline figure's run-to-run spread is pooled in: figures of one kind and backend in one
// time, whose offsets between runs come from the same machine state ("naive_over_flag/gpu/N:9/cpu_time"
// -> "naive_over_flag/gpu/cpu_time", "exponent/naive/gpu/larger_half" -> "exponent/gpu/larger_half");
// "" for figures pooled with no other.
std::string headline_family(const std::string& name);

// Every headline figure of `doc` with a repeat-run interval (figure9's repeat_low/repeat_high) gets
// it from repeat_run(its interval, a spread of measurement.run_to_run, that spread's degrees of freedom)
// and what it used (run_to_run_sd, in its units; run_to_run_t; run_to_run_from: "figure" or "family"),
// where the figure's own spread or its family's has kRunToRunMinDegreesOfFreedom; with both, the one
// whose t * sd is wider. Held to the four pairs of default figure9 runs of 2026-12-04 (each pair's
// repeat intervals widened by one other pair as their history), pairs agreed on 194 of 216 figures with
// families, 183 with each figure's own spread (too few runs: never used) and 183 with none.
void widen_repeat_intervals(nlohmann::json& doc);

// A command's run appended to the store at `url` once its results file is written (the file is the
// run's output; the store its history), as `doc` (with its schema and context) by Store::append_document;
// prints the run's id. Every command appends through here. Throws, naming the store, when it cannot take
// the run.
std::int64_t append_run(const std::string& url, const nlohmann::json& doc, const std::string& command);

// The default store of a sweep: <out_dir>/history.sqlite.
std::string default_store_url(const std::string& out_dir);

}  // namespace bokeh::history
