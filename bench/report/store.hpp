#pragma once
// The results store: the history of every run (runs, their points, their samples), beside the
// per-run JSON files (which stay the schema'd output of one run). One interface, two back-ends:
//   SQLite (a file; the default: <out-dir>/history.sqlite), Debian's libsqlite3;
//   PostgreSQL (postgresql://... or postgres://...), libpqxx, for machines reporting to one database.
// Both run the same SQL (parameters $1, $2, ...); a run is appended in one transaction, so readers and
// concurrent writers (two sweeps, or shards, at once) see all of a run or none of it. An interrupted
// sweep is appended with its status ("interrupted"), never half-written.
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
  std::string status;    // complete, interrupted
  std::string shard;     // "i/n" (1-based) when the run measured a shard; "" for the whole sweep
  std::string command;   // the command line
  std::string source;    // "run" (appended by the sweep), or the file it was imported from
  std::string context;   // the run's context block, JSON text
};

struct PointRow {
  std::string point_id, method, backend;
  double median_ms = 0, q1_ms = 0, q3_ms = 0;  // wall time per frame
  double cpu_median_ms = 0;                    // process CPU time per frame (0 when not recorded)
  bool settled = false;
  std::vector<double> samples_ms, samples_cpu_ms;
};

// One value of a series: a run's figure for one point.
struct SeriesValue {
  std::int64_t run_id = 0;
  std::string commit, date_utc, machine, shard, sweep;
  double median_ms = 0, q1_ms = 0, q3_ms = 0, cpu_median_ms = 0;
  std::vector<double> samples_ms, samples_cpu_ms;
};

// A store's connection: the SQL both back-ends run. Rows come back as text (NULL as nullopt).
class Connection {
 public:
  using Row = std::vector<std::optional<std::string>>;
  virtual ~Connection() = default;
  virtual std::vector<Row> query(const std::string& sql, const std::vector<std::string>& params = {}) = 0;
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
  // Appends one run with its points and samples in one transaction; returns its id.
  std::int64_t append(const RunRow& run, const std::vector<PointRow>& points);
  std::vector<RunRow> runs();
  std::vector<PointRow> points(std::int64_t run_id);
  // Every complete run's value for `point_id` (of every sweep that has it), oldest first (by date, then id).
  std::vector<SeriesValue> series(const std::string& point_id);
  // The distinct point ids, with the sweep each belongs to.
  std::vector<std::pair<std::string, std::string>> point_ids();
  // What the store takes on disk: PostgreSQL's database size (its tables, indexes and their overhead);
  // SQLite's file (call after the last writer closed, so the write-ahead log is checkpointed into it).
  std::uint64_t size_bytes();
  std::string kind() const { return connection_->kind(); }
  const std::string& url() const { return url_; }

 private:
  std::unique_ptr<Connection> connection_;
  std::string url_, path_;  // path_: SQLite's file
};

// What identifies the machine a run was measured on: device, driver, CPU model and cores,
// LP_NUM_THREADS. Runs with different keys are different series.
std::string machine_key(const nlohmann::json& context);

// A sweep's results document (figure9.json, ...) as a run and its points.
RunRow run_of(const nlohmann::json& doc, const std::string& command, const std::string& source);
std::vector<PointRow> points_of(const nlohmann::json& doc);

// The default store of a sweep: <out_dir>/history.sqlite.
std::string default_store_url(const std::string& out_dir);

}  // namespace bokeh::history
