#include "store.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <numeric>
#include <set>
#include <stdexcept>

#include <fmt/format.h>
#include <sqlite3.h>

#ifdef BOKEH_HAVE_PQXX
#include <pqxx/pqxx>
#endif

#include "fnv1a.hpp"  // stable across machines and builds (std::hash is not): sweep identities, lock keys
#include "intervals.hpp"
#include "report.hpp"
#include "runner.hpp"

namespace bokeh::history {

namespace {

std::string shown(const std::string& url);

// At most this many rows a multi-row INSERT: its parameters stay within PostgreSQL's limit (65,535)
// whatever a run holds (a stability run's thousands of figures).
constexpr std::size_t kRowsPerInsert = 500;

}  // namespace

// Multi-row INSERTs: a statement per table and not per row, since on PostgreSQL each statement is a
// round trip to the server.
void Connection::insert_rows(const std::string& table, const std::vector<std::string>& columns,
                             const std::vector<std::vector<std::string>>& rows) {
  std::string head = "INSERT INTO " + table + " (";
  for (std::size_t k = 0; k < columns.size(); ++k) head += (k ? ", " : "") + columns[k];
  head += ") VALUES ";
  for (std::size_t first = 0; first < rows.size(); first += kRowsPerInsert) {
    const std::size_t last = std::min(rows.size(), first + kRowsPerInsert);
    std::string sql = head;
    std::vector<std::string> params;
    params.reserve((last - first) * columns.size());
    for (std::size_t r = first; r < last; ++r) {
      sql += r == first ? "(" : ", (";
      for (std::size_t k = 0; k < columns.size(); ++k) {
        params.push_back(rows[r].at(k));
        sql += fmt::format("{}${}", k ? ", " : "", params.size());
      }
      sql += ")";
    }
    query(sql, params);
  }
}

namespace {

// ---- SQLite ----------------------------------------------------------------------------------------

class SqliteConnection : public Connection {
 public:
  SqliteConnection(const std::string& path, bool create) : path_(path) {
    if (!create && !std::filesystem::exists(path))
      throw std::runtime_error(fmt::format("no results store at '{}' (a sweep creates one; or give --store)", path));
    if (create) {
      const auto parent = std::filesystem::path(path).parent_path();
      if (!parent.empty()) std::filesystem::create_directories(parent);
    }
    const int flags = SQLITE_OPEN_READWRITE | (create ? SQLITE_OPEN_CREATE : 0) | SQLITE_OPEN_FULLMUTEX;
    if (sqlite3_open_v2(path.c_str(), &db_, flags, nullptr) != SQLITE_OK) {
      const std::string reason = db_ ? sqlite3_errmsg(db_) : "out of memory";
      sqlite3_close(db_);
      throw std::runtime_error(fmt::format("cannot open results store '{}': {}", path, reason));
    }
    // Concurrent writers (shards, two sweeps) wait for each other instead of failing: WAL lets
    // readers go on while one writes, and a writer waits up to 60 s for the lock.
    sqlite3_busy_timeout(db_, 60000);
    query("PRAGMA journal_mode=WAL");
    query("PRAGMA synchronous=NORMAL");
  }
  ~SqliteConnection() override { sqlite3_close(db_); }

  // A compiled statement, finalised when it goes out of scope (also when a step throws).
  using Statement = std::unique_ptr<sqlite3_stmt, decltype(&sqlite3_finalize)>;
  Statement prepare(const std::string& sql) {
    sqlite3_stmt* stmt = nullptr;
    if (sqlite3_prepare_v2(db_, sql.c_str(), -1, &stmt, nullptr) != SQLITE_OK) fail("prepare", sql);
    return Statement(stmt, &sqlite3_finalize);
  }

  std::vector<Row> query(const std::string& sql, const std::vector<std::string>& params = {}) override {
    const Statement statement = prepare(sql);
    sqlite3_stmt* stmt = statement.get();
    // Each of the statement's parameters ($N, in the order SQLite numbers them) by its name: one pass,
    // where looking each $N up by name (sqlite3_bind_parameter_index) scans them all, which a multi-row
    // INSERT's hundreds of parameters make quadratic. Params the statement does not name are ignored.
    for (int index = 1; index <= sqlite3_bind_parameter_count(stmt); ++index) {
      const char* name = sqlite3_bind_parameter_name(stmt, index);
      if (!name || name[0] != '$') continue;
      const unsigned long n = std::strtoul(name + 1, nullptr, 10);
      if (n < 1 || n > params.size()) continue;  // left NULL
      if (sqlite3_bind_text(stmt, index, params[n - 1].c_str(), static_cast<int>(params[n - 1].size()), SQLITE_STATIC) !=
          SQLITE_OK)
        fail("bind", sql);
    }
    std::vector<Row> rows;
    for (;;) {
      const int rc = sqlite3_step(stmt);
      if (rc == SQLITE_DONE) break;
      if (rc != SQLITE_ROW) fail("run", sql);
      Row row;
      for (int c = 0; c < sqlite3_column_count(stmt); ++c) {
        const auto* text = sqlite3_column_text(stmt, c);
        row.push_back(text ? std::optional<std::string>(reinterpret_cast<const char*>(text)) : std::nullopt);
      }
      rows.push_back(std::move(row));
    }
    return rows;
  }
  // One prepared statement, bound and stepped per row: in-process calls cost no round trip, and a long
  // VALUES list costs SQLite more to compile than it saves (history cost, a figure9 run: 0.8 ms so, 3.0 ms
  // with VALUES lists, 1.6 ms with a statement prepared for each row).
  void insert_rows(const std::string& table, const std::vector<std::string>& columns,
                   const std::vector<std::vector<std::string>>& rows) override {
    if (rows.empty()) return;
    std::string sql = "INSERT INTO " + table + " (", values;
    for (std::size_t k = 0; k < columns.size(); ++k) {
      sql += (k ? ", " : "") + columns[k];
      values += fmt::format("{}${}", k ? ", " : "", k + 1);
    }
    sql += ") VALUES (" + values + ")";
    const Statement statement = prepare(sql);
    sqlite3_stmt* stmt = statement.get();
    for (const auto& row : rows) {
      for (std::size_t k = 0; k < columns.size(); ++k)  // $1..$k appear in order: parameter k + 1 is $k+1
        if (sqlite3_bind_text(stmt, static_cast<int>(k + 1), row.at(k).c_str(), static_cast<int>(row[k].size()),
                              SQLITE_STATIC) != SQLITE_OK)
          fail("bind", sql);
      if (sqlite3_step(stmt) != SQLITE_DONE) fail("run", sql);
      sqlite3_reset(stmt);
    }
  }
  void begin_write() override { query("BEGIN IMMEDIATE"); }
  void commit() override { query("COMMIT"); }
  void rollback() noexcept override { sqlite3_exec(db_, "ROLLBACK", nullptr, nullptr, nullptr); }
  std::string kind() const override { return "sqlite"; }
  std::string id_column() const override { return "INTEGER PRIMARY KEY AUTOINCREMENT"; }

 private:
  [[noreturn]] void fail(const char* what, const std::string& sql) {
    throw std::runtime_error(fmt::format("results store '{}': cannot {} '{}': {}", path_, what, sql.substr(0, 60),
                                         sqlite3_errmsg(db_)));
  }
  std::string path_;
  sqlite3* db_ = nullptr;
};

// ---- PostgreSQL ------------------------------------------------------------------------------------

#ifdef BOKEH_HAVE_PQXX
class PostgresConnection : public Connection {
 public:
  explicit PostgresConnection(const std::string& url) : url_(shown(url)) {
    try {
      connection_ = std::make_unique<pqxx::connection>(url);
    } catch (const std::exception& e) {
      throw std::runtime_error(fmt::format("cannot connect to the PostgreSQL results store '{}': {}", url_, trimmed(e.what())));
    }
  }
  std::vector<Row> query(const std::string& sql, const std::vector<std::string>& params = {}) override {
    try {
      pqxx::result result;
      if (work_) {
        result = work_->exec_params(sql, pqxx::prepare::make_dynamic_params(params));
      } else {
        pqxx::nontransaction tx(*connection_);
        result = tx.exec_params(sql, pqxx::prepare::make_dynamic_params(params));
      }
      std::vector<Row> rows;
      for (const auto& r : result) {
        Row row;
        for (const auto& field : r) row.push_back(field.is_null() ? std::nullopt : std::optional<std::string>(field.c_str()));
        rows.push_back(std::move(row));
      }
      return rows;
    } catch (const pqxx::sql_error& e) {
      throw std::runtime_error(fmt::format("results store '{}': cannot run '{}': {}", url_, sql.substr(0, 60), trimmed(e.what())));
    } catch (const pqxx::broken_connection& e) {
      throw std::runtime_error(fmt::format("results store '{}': connection lost: {}", url_, trimmed(e.what())));
    }
  }
  void begin_write() override { work_ = std::make_unique<pqxx::work>(*connection_); }
  void commit() override {
    work_->commit();
    work_.reset();
  }
  void rollback() noexcept override {
    try {
      if (work_) work_->abort();
    } catch (...) {
    }
    work_.reset();
  }
  std::string kind() const override { return "postgresql"; }
  std::string id_column() const override { return "BIGSERIAL PRIMARY KEY"; }

 private:
  static std::string trimmed(std::string text) {
    while (!text.empty() && (text.back() == '\n' || text.back() == ' ')) text.pop_back();
    return text;
  }
  std::string url_;
  std::unique_ptr<pqxx::connection> connection_;
  std::unique_ptr<pqxx::work> work_;
};
#endif

// A URL as messages show it: a password (user:PASSWORD@host) is not printed.
std::string shown(const std::string& url) {
  const auto scheme = url.find("://");
  if (scheme == std::string::npos) return url;
  const auto at = url.find('@', scheme + 3);
  const auto colon = url.find(':', scheme + 3);
  if (at == std::string::npos || colon == std::string::npos || colon > at) return url;
  return url.substr(0, colon + 1) + "***" + url.substr(at);
}

double number(const std::optional<std::string>& text) { return text ? std::strtod(text->c_str(), nullptr) : 0.0; }
std::string text(const std::optional<std::string>& t) { return t.value_or(""); }

// A series value's run, from a row whose first columns are r.id, r.commit_hash, r.date_utc, r.machine,
// r.shard (the series queries select them first).
SeriesValue series_value_of_run(const Connection::Row& r) {
  SeriesValue v;
  v.run_id = std::stoll(text(r[0]));
  v.commit = text(r[1]), v.date_utc = text(r[2]), v.machine = text(r[3]), v.shard = text(r[4]);
  return v;
}
std::string num(double v) { return fmt::format("{:.17g}", v); }

// Samples are stored as a comma-separated list in one row per point (a row per sample made a run's
// write cost ~10x more statements for no query that needs them one by one).
std::string join(const std::vector<double>& values) {
  std::string out;
  for (double v : values) out += (out.empty() ? "" : ",") + num(v);
  return out;
}
std::vector<double> split(const std::string& text) {
  std::vector<double> out;
  std::size_t start = 0;
  while (start < text.size()) {
    std::size_t end = text.find(',', start);
    if (end == std::string::npos) end = text.size();
    out.push_back(std::strtod(text.substr(start, end - start).c_str(), nullptr));
    start = end + 1;
  }
  return out;
}

}  // namespace

std::unique_ptr<Store> Store::open(const std::string& url, bool create) {
  if (url.empty()) throw std::runtime_error("no results store given (--store PATH or postgresql://...)");
  const auto scheme_end = url.find("://");
  if (url.rfind("postgresql://", 0) == 0 || url.rfind("postgres://", 0) == 0) {
#ifdef BOKEH_HAVE_PQXX
    return std::make_unique<Store>(std::make_unique<PostgresConnection>(url), url, create);
#else
    throw std::runtime_error(fmt::format("results store '{}': this bokehbench was built without PostgreSQL (libpqxx-dev)", shown(url)));
#endif
  }
  if (scheme_end != std::string::npos)
    throw std::runtime_error(fmt::format("results store '{}': unknown URL scheme '{}' (a path, sqlite:PATH, or "
                                         "postgresql://[user@]host[:port]/database)",
                                         url, url.substr(0, scheme_end)));
  const std::string path = url.rfind("sqlite:", 0) == 0 ? url.substr(7) : url;
  if (path.empty()) throw std::runtime_error(fmt::format("results store '{}': no file path", url));
  return std::make_unique<Store>(std::make_unique<SqliteConnection>(path, create), url, create, path);
}

Store::Store(std::unique_ptr<Connection> connection, const std::string& url, bool create, std::string path)
    : connection_(std::move(connection)), url_(shown(url)), path_(std::move(path)) {
  Connection& c = *connection_;
  // The version first: a newer store is refused before anything is created or changed in it.
  auto version_of = [&]() -> std::optional<int> {
    const auto tables = c.kind() == "sqlite"
                            ? c.query("SELECT name FROM sqlite_master WHERE type = 'table' AND name = 'meta'")
                            : c.query("SELECT table_name FROM information_schema.tables WHERE table_name = 'meta'");
    if (tables.empty()) return std::nullopt;
    const auto rows = c.query("SELECT value FROM meta WHERE key = 'schema_version'");
    if (rows.empty() || !rows[0][0]) throw std::runtime_error(fmt::format("results store '{}': no schema_version in its meta table", url_));
    return std::atoi(rows[0][0]->c_str());
  };
  std::optional<int> version = version_of();
  if (version && *version > kStoreSchemaVersion)
    throw std::runtime_error(fmt::format("results store '{}' has schema version {}, newer than this bokehbench reads ({}): "
                                         "use a newer bokehbench (nothing was changed in the store)",
                                         url_, *version, kStoreSchemaVersion));
  if (!version && !create) throw std::runtime_error(fmt::format("'{}' is not a bokehbench results store (no meta table)", url_));
  auto has_table = [&](const std::string& name) {
    return !(c.kind() == "sqlite" ? c.query("SELECT name FROM sqlite_master WHERE type = 'table' AND name = $1", {name})
                                  : c.query("SELECT table_name FROM information_schema.tables WHERE table_name = $1", {name}))
                .empty();
  };
  has_headlines_ = version && has_table("headlines");
  has_packages_ = version && has_table("point_packages");
  has_shard_runs_ = version && has_table("shard_runs");
  // Reading a store written before headline figures (or packages, or shard identities) were stored: it
  // has none (nothing is changed in it).
  if ((has_headlines_ && has_packages_ && has_shard_runs_) || (version && !create)) return;
  c.begin_write();
  try {
    // PostgreSQL: shards starting at once on an empty database create the tables once.
    if (c.kind() == "postgresql") c.query("SELECT pg_advisory_xact_lock(20201)");
    if (!version_of()) {  // another writer may have created it meanwhile
      c.query("CREATE TABLE meta (key TEXT PRIMARY KEY, value TEXT NOT NULL)");
      c.query("INSERT INTO meta (key, value) VALUES ('schema_version', $1)", {std::to_string(kStoreSchemaVersion)});
      c.query("CREATE TABLE runs (id " + c.id_column() +
              ", commit_hash TEXT NOT NULL, date_utc TEXT NOT NULL, machine TEXT NOT NULL, sweep TEXT NOT NULL, "
              "status TEXT NOT NULL, shard TEXT NOT NULL, command TEXT NOT NULL, source TEXT NOT NULL, "
              "context TEXT NOT NULL)");
      c.query("CREATE TABLE points (run_id BIGINT NOT NULL REFERENCES runs(id), point_id TEXT NOT NULL, "
              "method TEXT NOT NULL, backend TEXT NOT NULL, median_ms DOUBLE PRECISION NOT NULL, "
              "q1_ms DOUBLE PRECISION NOT NULL, q3_ms DOUBLE PRECISION NOT NULL, cpu_median_ms DOUBLE PRECISION NOT NULL, "
              "settled INTEGER NOT NULL, PRIMARY KEY (run_id, point_id))");
      c.query("CREATE TABLE samples (run_id BIGINT NOT NULL REFERENCES runs(id), point_id TEXT NOT NULL, "
              "frame_ms TEXT NOT NULL, cpu_ms TEXT NOT NULL, PRIMARY KEY (run_id, point_id))");
      c.query("CREATE INDEX points_by_id ON points (point_id)");
    }
    // Added to schema version 1 (a table more: older readers ignore it, so no version bump); a store
    // written before gains it on its first append. low/high hold the value when has_interval is 0.
    c.query("CREATE TABLE IF NOT EXISTS headlines (run_id BIGINT NOT NULL REFERENCES runs(id), name TEXT NOT NULL, "
            "unit TEXT NOT NULL, value DOUBLE PRECISION NOT NULL, low DOUBLE PRECISION NOT NULL, "
            "high DOUBLE PRECISION NOT NULL, has_interval INTEGER NOT NULL, PRIMARY KEY (run_id, name))");
    // Likewise: a method package's content hash per point, so a series follows the package's edits.
    c.query("CREATE TABLE IF NOT EXISTS point_packages (run_id BIGINT NOT NULL REFERENCES runs(id), point_id TEXT NOT "
            "NULL, package TEXT NOT NULL, PRIMARY KEY (run_id, point_id))");
    // Likewise: a shard run's sweep identity (RunRow::sweep_identity), so that a shard given twice is
    // found (Store::append) without a column more in runs.
    c.query("CREATE TABLE IF NOT EXISTS shard_runs (run_id BIGINT NOT NULL PRIMARY KEY REFERENCES runs(id), "
            "identity TEXT NOT NULL)");
    c.query("CREATE INDEX IF NOT EXISTS shard_runs_by_identity ON shard_runs (identity)");
    c.commit();
    has_headlines_ = has_packages_ = has_shard_runs_ = true;
  } catch (...) {
    c.rollback();
    throw;
  }
}

std::int64_t Store::append(const RunRow& run, const std::vector<PointRow>& points, const std::vector<HeadlineRow>& headlines,
                           std::int64_t* duplicate_of) {
  if (!headlines.empty() && !has_headlines_)
    throw std::logic_error("results store opened for reading only: it cannot take headline figures");
  if (!has_packages_ && std::any_of(points.begin(), points.end(), [](const PointRow& p) { return !p.package.empty(); }))
    throw std::logic_error("results store opened for reading only: it cannot take method packages' hashes");
  const bool shard_run = !run.shard.empty() && !run.sweep_identity.empty();
  if (shard_run && !has_shard_runs_)
    throw std::logic_error("results store opened for reading only: it cannot take shards' sweep identities");
  if (duplicate_of) *duplicate_of = 0;
  Connection& c = *connection_;
  c.begin_write();
  try {
    std::string status = run.status;
    if (shard_run && status == "complete") {
      // Writers of the same shard wait for each other here until the first commits (SQLite's BEGIN
      // IMMEDIATE already admits one writer at a time), so the second always sees the first.
      if (c.kind() == "postgresql")
        c.query("SELECT pg_advisory_xact_lock($1)",
                {std::to_string(static_cast<std::int64_t>(fnv1a(run.sweep_identity + "\n" + run.shard)))});
      const auto earlier = c.query("SELECT r.id FROM shard_runs s JOIN runs r ON r.id = s.run_id WHERE s.identity = $1 AND "
                                   "r.shard = $2 AND r.status = 'complete' ORDER BY r.id LIMIT 1",
                                   {run.sweep_identity, run.shard});
      if (!earlier.empty()) {
        status = kDuplicateShard;
        if (duplicate_of) *duplicate_of = std::stoll(text(earlier[0][0]));
      }
    }
    const auto id_rows =
        c.query("INSERT INTO runs (commit_hash, date_utc, machine, sweep, status, shard, command, source, context) "
                "VALUES ($1, $2, $3, $4, $5, $6, $7, $8, $9) RETURNING id",
                {run.commit, run.date_utc, run.machine, run.sweep, status, run.shard, run.command, run.source, run.context});
    const std::string id = text(id_rows.at(0).at(0));
    if (shard_run) c.query("INSERT INTO shard_runs (run_id, identity) VALUES ($1, $2)", {id, run.sweep_identity});
    std::vector<std::vector<std::string>> point_rows, sample_rows, package_rows, headline_rows;
    for (const auto& p : points) {
      point_rows.push_back({id, p.point_id, p.method, p.backend, num(p.median_ms), num(p.q1_ms), num(p.q3_ms),
                            num(p.cpu_median_ms), p.settled ? "1" : "0"});
      sample_rows.push_back({id, p.point_id, join(p.samples_ms), join(p.samples_cpu_ms)});
      if (!p.package.empty()) package_rows.push_back({id, p.point_id, p.package});
    }
    for (const auto& h : headlines)
      headline_rows.push_back({id, h.name, h.unit, num(h.value), num(h.low.value_or(h.value)), num(h.high.value_or(h.value)),
                               h.low && h.high ? "1" : "0"});
    c.insert_rows("points", {"run_id", "point_id", "method", "backend", "median_ms", "q1_ms", "q3_ms", "cpu_median_ms", "settled"},
                point_rows);
    c.insert_rows("samples", {"run_id", "point_id", "frame_ms", "cpu_ms"}, sample_rows);
    c.insert_rows("point_packages", {"run_id", "point_id", "package"}, package_rows);
    c.insert_rows("headlines", {"run_id", "name", "unit", "value", "low", "high", "has_interval"}, headline_rows);
    c.commit();
    return std::stoll(id);
  } catch (...) {
    c.rollback();
    throw;
  }
}

std::int64_t Store::append_document(const nlohmann::json& doc, const std::string& command, const std::string& source,
                                    std::int64_t* duplicate_of) {
  return append(run_of(doc, command, source), points_of(doc), headlines_of(doc), duplicate_of);
}

std::vector<HeadlineRow> Store::headlines(std::int64_t run_id) {
  std::vector<HeadlineRow> out;
  if (!has_headlines_) return out;
  for (const auto& r : connection_->query("SELECT name, unit, value, low, high, has_interval FROM headlines WHERE run_id = $1 "
                                          "ORDER BY name",
                                          {std::to_string(run_id)})) {
    HeadlineRow h{text(r[0]), text(r[1]), number(r[2]), std::nullopt, std::nullopt};
    if (text(r[5]) == "1") h.low = number(r[3]), h.high = number(r[4]);
    out.push_back(std::move(h));
  }
  return out;
}

std::vector<SeriesValue> Store::headline_series(const std::string& name) {
  std::vector<SeriesValue> out;
  if (!has_headlines_) return out;
  for (const auto& r : connection_->query(
           "SELECT r.id, r.commit_hash, r.date_utc, r.machine, r.shard, h.value, h.low, h.high, h.has_interval, r.sweep "
           "FROM headlines h JOIN runs r ON r.id = h.run_id WHERE h.name = $1 AND r.status = 'complete' "
           "ORDER BY r.date_utc, r.id",
           {name})) {
    SeriesValue v = series_value_of_run(r);
    v.median_ms = number(r[5]), v.q1_ms = number(r[6]), v.q3_ms = number(r[7]);
    v.has_interval = text(r[8]) == "1";
    v.samples_ms = v.samples_cpu_ms = {v.median_ms};
    v.sweep = text(r[9]);
    out.push_back(std::move(v));
  }
  return out;
}

std::vector<std::pair<std::pair<std::string, std::string>, std::string>> Store::headline_names() {
  std::vector<std::pair<std::pair<std::string, std::string>, std::string>> out;
  if (!has_headlines_) return out;
  for (const auto& r : connection_->query("SELECT DISTINCT h.name, r.sweep, h.unit FROM headlines h JOIN runs r ON r.id = "
                                          "h.run_id ORDER BY r.sweep, h.name"))
    out.push_back({{text(r[0]), text(r[1])}, text(r[2])});
  return out;
}

std::uint64_t Store::size_bytes() {
  if (connection_->kind() == "postgresql")
    return static_cast<std::uint64_t>(number(connection_->query("SELECT pg_database_size(current_database())").at(0).at(0)));
  std::uint64_t bytes = 0;
  for (const char* suffix : {"", "-wal"})
    if (std::filesystem::exists(path_ + suffix)) bytes += std::filesystem::file_size(path_ + suffix);
  return bytes;
}

std::vector<RunRow> Store::runs() {
  std::vector<RunRow> out;
  for (const auto& r : connection_->query("SELECT id, commit_hash, date_utc, machine, sweep, status, shard, command, source, "
                                          "context FROM runs ORDER BY date_utc, id")) {
    RunRow run;
    run.id = std::stoll(text(r[0]));
    run.commit = text(r[1]), run.date_utc = text(r[2]), run.machine = text(r[3]), run.sweep = text(r[4]);
    run.status = text(r[5]), run.shard = text(r[6]), run.command = text(r[7]), run.source = text(r[8]), run.context = text(r[9]);
    out.push_back(std::move(run));
  }
  return out;
}

std::vector<PointRow> Store::points(std::int64_t run_id) {
  std::vector<PointRow> out;
  for (const auto& r : connection_->query(
           "SELECT p.point_id, p.method, p.backend, p.median_ms, p.q1_ms, p.q3_ms, p.cpu_median_ms, p.settled, s.frame_ms, "
           "s.cpu_ms FROM points p JOIN samples s ON s.run_id = p.run_id AND s.point_id = p.point_id WHERE p.run_id = $1 "
           "ORDER BY p.point_id",
           {std::to_string(run_id)})) {
    PointRow p;
    p.point_id = text(r[0]), p.method = text(r[1]), p.backend = text(r[2]);
    p.median_ms = number(r[3]), p.q1_ms = number(r[4]), p.q3_ms = number(r[5]), p.cpu_median_ms = number(r[6]);
    p.settled = text(r[7]) == "1";
    p.samples_ms = split(text(r[8])), p.samples_cpu_ms = split(text(r[9]));
    out.push_back(std::move(p));
  }
  return out;
}

std::vector<SeriesValue> Store::series(const std::string& point_id) {
  std::vector<SeriesValue> out;
  for (const auto& r : connection_->query(
           "SELECT r.id, r.commit_hash, r.date_utc, r.machine, r.shard, p.median_ms, p.q1_ms, p.q3_ms, p.cpu_median_ms, "
           "s.frame_ms, s.cpu_ms, r.sweep FROM points p JOIN runs r ON r.id = p.run_id JOIN samples s ON s.run_id = p.run_id AND "
           "s.point_id = p.point_id WHERE p.point_id = $1 AND r.status = 'complete' ORDER BY r.date_utc, r.id",
           {point_id})) {
    SeriesValue v = series_value_of_run(r);
    v.median_ms = number(r[5]), v.q1_ms = number(r[6]), v.q3_ms = number(r[7]), v.cpu_median_ms = number(r[8]);
    v.samples_ms = split(text(r[9])), v.samples_cpu_ms = split(text(r[10]));
    v.sweep = text(r[11]);
    out.push_back(std::move(v));
  }
  if (has_packages_) {
    std::map<std::int64_t, std::string> package_of_run;
    for (const auto& r : connection_->query("SELECT run_id, package FROM point_packages WHERE point_id = $1", {point_id}))
      package_of_run[std::stoll(text(r[0]))] = text(r[1]);
    for (auto& v : out)
      if (const auto it = package_of_run.find(v.run_id); it != package_of_run.end()) v.package = it->second;
  }
  return out;
}

std::vector<std::pair<std::string, std::string>> Store::point_ids() {
  std::vector<std::pair<std::string, std::string>> out;
  for (const auto& r : connection_->query("SELECT DISTINCT p.point_id, r.sweep FROM points p JOIN runs r ON r.id = p.run_id "
                                          "ORDER BY r.sweep, p.point_id"))
    out.emplace_back(text(r[0]), text(r[1]));
  return out;
}

std::string machine_key(const nlohmann::json& context) {
  auto field = [](const nlohmann::json& obj, const char* key) -> std::string {
    if (!obj.is_object() || !obj.contains(key)) return "?";
    return obj[key].is_string() ? obj[key].get<std::string>() : obj[key].dump();
  };
  const nlohmann::json device = context.value("device", nlohmann::json());
  const std::string dev = device.is_object() ? field(device, "name") + " (" + field(device, "driver_info") + ")" : "no device";
  return fmt::format("{}; {} x{}; LP_NUM_THREADS={}", dev, field(context, "cpu_model"), field(context, "cpu_cores"),
                     field(context, "lp_num_threads"));
}

RunRow run_of(const nlohmann::json& doc, const std::string& command, const std::string& source) {
  const std::string schema = doc.value("schema", "");
  // stability: a run of headline figures only (its safe ranges; nothing timed).
  const bool figures_only = schema == "bokehbench.stability" && doc.contains("configurations") &&
                            doc["configurations"].is_array() && doc.contains("context") && doc["context"].is_object();
  const bool timed_sweep = schema.rfind("bokehbench.", 0) == 0 && doc.contains("points") && doc["points"].is_array() &&
                           doc.contains("context") && doc["context"].is_object() &&
                           std::all_of(doc["points"].begin(), doc["points"].end(),
                                       [](const nlohmann::json& p) { return p.is_object() && p.contains("id"); });
  const bool sweep = figures_only || timed_sweep;
  if (!sweep)
    throw std::runtime_error(fmt::format("not the results of a sweep (schema '{}': a sweep file has context and points with "
                                         "ids and samples; memory and kernels are not sweeps)",
                                         schema));
  const nlohmann::json& context = doc["context"];
  RunRow run;
  run.commit = context.value("git_commit", "unknown");
  run.date_utc = context.value("date_utc", "");
  run.machine = machine_key(context);
  run.sweep = schema.substr(std::string("bokehbench.").size());
  run.status = doc.value("status", "complete");
  const nlohmann::json config = doc.value("config", nlohmann::json::object());
  run.shard = config.contains("shard") && config["shard"].is_string() ? config["shard"].get<std::string>() : "";
  run.command = command;
  run.source = source;
  run.context = context.dump();
  run.sweep_identity = sweep_identity_of(doc);
  return run;
}

std::string sweep_identity_of(const nlohmann::json& doc) {
  nlohmann::json config = doc.value("config", nlohmann::json::object());
  if (!config.is_object() || !config.contains("shard") || !config["shard"].is_string()) return "";
  config.erase("shard");
  const nlohmann::json context = doc.value("context", nlohmann::json::object());
  const std::string job = context.is_object() ? context.value("sweep_id", std::string()) : std::string();
  // nlohmann's objects keep their keys sorted: the same config dumps the same text whatever wrote it.
  return fmt::format("{} {} {} config:{:016x}", doc.value("schema", std::string()),
                     context.is_object() ? context.value("git_commit", std::string("unknown")) : "unknown",
                     job.empty() ? "-" : job, fnv1a(config.dump()));
}

std::vector<PointRow> points_of(const nlohmann::json& doc) {
  std::vector<PointRow> out;
  if (!doc.contains("points") || !doc["points"].is_array()) return out;
  for (const auto& p : doc["points"]) {
    if (!p.is_object()) continue;
    PointRow row;
    row.point_id = p.value("id", "");
    row.method = p.value("method", "");
    row.backend = p.value("backend", "");
    if (p.contains("frame_ms") && p["frame_ms"].is_object()) {
      row.median_ms = p["frame_ms"].value("median", 0.0);
      row.q1_ms = p["frame_ms"].value("q1", 0.0);
      row.q3_ms = p["frame_ms"].value("q3", 0.0);
    }
    row.settled = p.value("settled", false);
    if (p.contains("package") && p["package"].is_object()) row.package = p["package"].value("hash", "");
    if (p.contains("samples_ms")) row.samples_ms = p["samples_ms"].get<std::vector<double>>();
    if (p.contains("samples_cpu_ms")) row.samples_cpu_ms = p["samples_cpu_ms"].get<std::vector<double>>();
    if (!row.samples_cpu_ms.empty()) {
      std::vector<double> sorted = row.samples_cpu_ms;
      std::sort(sorted.begin(), sorted.end());
      const std::size_t n = sorted.size();
      row.cpu_median_ms = n % 2 ? sorted[n / 2] : 0.5 * (sorted[n / 2 - 1] + sorted[n / 2]);
    }
    if (!row.point_id.empty()) out.push_back(std::move(row));
  }
  return out;
}

namespace {
bool is_number(const nlohmann::json& obj, const char* key) { return obj.is_object() && obj.contains(key) && obj[key].is_number(); }

// A figure with the interval in obj[low_key] / obj[high_key] when the run gave one.
HeadlineRow figure(std::string name, std::string unit, double value, const nlohmann::json& obj, const char* low_key = "low",
                   const char* high_key = "high") {
  HeadlineRow h{std::move(name), std::move(unit), value, std::nullopt, std::nullopt};
  if (is_number(obj, low_key) && is_number(obj, high_key)) h.low = obj[low_key].get<double>(), h.high = obj[high_key].get<double>();
  return h;
}

// stability: per configuration and axis, how many cases the safe range around the nominal case spans
// (0: the nominal case fails), and how many cases fail in all. Deterministic: a step is a change in
// the numerics.
void stability_headlines(const nlohmann::json& doc, std::vector<HeadlineRow>& out) {
  for (const auto& config : doc["configurations"]) {
    if (!config.is_object() || !config.contains("cases") || !config["cases"].is_array()) continue;  // skipped
    const std::string prefix = fmt::format("{}/{}/{}/", config.value("method", "?"), config.value("precision", "?"),
                                           config.value("backend", "?"));
    int failures = 0;
    for (const auto& c : config["cases"]) failures += c.value("status", "") == "fail";
    out.push_back({prefix + "failing_cases", "cases", static_cast<double>(failures), std::nullopt, std::nullopt});
    if (!config.contains("safe_ranges") || !config["safe_ranges"].is_object()) continue;
    for (const auto& [axis, range] : config["safe_ranges"].items()) {
      const std::string case_axis = axis == "disc" ? "radius" : axis;  // disc: the radius axis judged by shape
      std::vector<std::string> labels;
      for (const auto& c : config["cases"])
        if (c.value("axis", "") == case_axis) labels.push_back(c.value("label", ""));
      double spanned = 0;
      if (range["low"].is_string() && range["high"].is_string()) {
        const auto lo = std::find(labels.begin(), labels.end(), range["low"].get<std::string>());
        const auto hi = std::find(labels.begin(), labels.end(), range["high"].get<std::string>());
        if (lo != labels.end() && hi != labels.end()) spanned = static_cast<double>(hi - lo + 1);
      }
      out.push_back({prefix + "safe_range_cases/" + axis, "cases", spanned, std::nullopt, std::nullopt});
    }
  }
}
}  // namespace

std::vector<HeadlineRow> headlines_of(const nlohmann::json& doc) {
  std::vector<HeadlineRow> out;
  const std::string schema = doc.value("schema", "");
  auto array = [&](const char* key) -> const nlohmann::json& {
    static const nlohmann::json none = nlohmann::json::array();
    return doc.contains(key) && doc[key].is_array() ? doc[key] : none;
  };
  if (schema == "bokehbench.stability") stability_headlines(doc, out);
  // Every sweep: its calibration probes' median ms a round (the machine's state: machine_state()).
  if (doc.contains("measurement") && doc["measurement"].contains("probes") && doc["measurement"]["probes"].is_object())
    for (const auto& [probe, p] : doc["measurement"]["probes"].items())
      if (p.contains("ms") && is_number(p["ms"], "median"))
        out.push_back(figure("probe/" + probe, "ms", p["ms"]["median"].get<double>(), nlohmann::json()));
  // figure9: naive / FLAG per N and backend (paired within rounds), each curve's growth exponents.
  // Figures in process CPU time are series of their own ("/cpu_time"): older runs took them in
  // wall-clock time, and one series mixing the two would show the switch as a change.
  auto in_time = [](const nlohmann::json& figure) {
    return figure.value("time", std::string()) == kProcessCpuTime ? std::string("/cpu_time") : std::string();
  };
  for (std::size_t i = 0; i < array("naive_over_flag").size(); ++i)
    if (const auto& r = array("naive_over_flag")[i]; is_number(r, "naive_over_flag")) {
      out.push_back(figure(fmt::format("naive_over_flag/{}/N:{}{}", r.value("backend", "?"), r.value("N", 0), in_time(r)),
                           "ratio", r["naive_over_flag"].get<double>(), r));
      out.back().at = fmt::format("/naive_over_flag/{}", i);
    }
  for (std::size_t i = 0; i < array("series").size(); ++i)
    if (const auto& c = array("series")[i]; c.is_object() && c.contains("fits") && c["fits"].is_object())
      for (const auto& [fit, f] : c["fits"].items())
        if (is_number(f, "exponent")) {
          out.push_back(figure(fmt::format("exponent/{}{}/{}/{}{}", c.value("method", "?"), c.value("variant", ""),
                                           c.value("backend", "?"), fit, in_time(c)),
                               "exponent", f["exponent"].get<double>(), f));
          out.back().at = fmt::format("/series/{}/fits/{}", i, fit);
        }
  // adaptive: off / on per configuration, paired within rounds when the run has it.
  for (const auto& c : array("comparisons")) {
    if (!c.is_object() || !c.contains("off_id")) continue;
    const std::string name = "speedup/" + c["off_id"].get<std::string>();
    if (c.contains("speedup_same_round") && is_number(c["speedup_same_round"], "median"))
      out.push_back(figure(name, "ratio", c["speedup_same_round"]["median"].get<double>(), c["speedup_same_round"]));
    else if (is_number(c, "speedup") && c["speedup"].get<double>() > 0)
      out.push_back(figure(name, "ratio", c["speedup"].get<double>(), nlohmann::json()));
  }
  // buffers: streamed layers over the full-frame layers, per point (median of same-round ratios, with
  // its interval where the run has it).
  for (const auto& p : array("points"))
    if (p.is_object() && p.contains("streamed_vs_full") && is_number(p["streamed_vs_full"], "frame_ms_ratio_median"))
      out.push_back(figure("streamed_over_full/" + p.value("id", "?"), "ratio",
                           p["streamed_vs_full"]["frame_ms_ratio_median"].get<double>(), p["streamed_vs_full"]));
  // ab (the candidate's run): new / old per point, paired, with its Hodges-Lehmann interval.
  for (const auto& r : array("paired_ratios"))
    if (is_number(r, "ratio")) out.push_back(figure("new_over_old/" + r.value("id", "?"), "ratio", r["ratio"].get<double>(), r));
  return out;
}

nlohmann::json machine_state(Store& store, const nlohmann::json& doc, int recent_runs, double unusual_ratio) {
  const std::string machine = machine_key(doc.at("context"));
  nlohmann::json probes = nlohmann::json::object(), unusual = nlohmann::json::array();
  int earlier_runs = 0;
  for (const HeadlineRow& h : headlines_of(doc)) {
    if (h.name.rfind("probe/", 0) != 0) continue;
    std::vector<double> earlier;
    for (const SeriesValue& v : store.headline_series(h.name))
      if (v.machine == machine) earlier.push_back(v.median_ms);
    if (earlier.size() > static_cast<std::size_t>(recent_runs))
      earlier.erase(earlier.begin(), earlier.end() - recent_runs);  // oldest first: keep the latest
    if (earlier.empty()) continue;
    const std::size_t m = earlier.size();
    earlier_runs = std::max(earlier_runs, static_cast<int>(m));
    const double usual = runner::quantile(std::move(earlier), 0.5);
    const double ratio = h.value / usual;
    const std::string name = h.name.substr(6);
    probes[name] = {{"this_run_ms", h.value}, {"usual_ms", usual}, {"ratio", ratio}, {"earlier_runs", m}};
    if (m >= kMachineStateMinRuns && (ratio > unusual_ratio || ratio < 1 / unusual_ratio)) unusual.push_back(name);
  }
  return {{"earlier_runs", earlier_runs}, {"recent_runs_compared", recent_runs}, {"unusual_ratio", unusual_ratio},
          {"min_earlier_runs", kMachineStateMinRuns}, {"probes", probes}, {"unusual", unusual}};
}

nlohmann::json run_to_run_spread(Store& store, const nlohmann::json& doc, const std::string& sweep, int recent_runs) {
  const nlohmann::json& context = doc.at("context");
  const std::string machine = machine_key(context);
  std::set<std::string> point_ids;
  for (const auto& p : doc.at("points")) point_ids.insert(p.at("id").get<std::string>());
  std::vector<RunRow> earlier;  // oldest first
  for (const RunRow& run : store.runs()) {
    if (run.machine != machine || run.sweep != sweep || run.status != "complete") continue;
    std::set<std::string> theirs;
    for (const PointRow& p : store.points(run.id)) theirs.insert(p.point_id);
    if (theirs == point_ids) earlier.push_back(run);
  }
  if (earlier.size() > static_cast<std::size_t>(recent_runs))
    earlier.erase(earlier.begin(), earlier.end() - recent_runs);  // keep the latest
  // Each figure's values by commit: a commit may change a figure's level, so the spread is taken about
  // each commit's own mean and pooled (its runs less one degrees of freedom each).
  std::map<std::string, std::map<std::string, std::vector<double>>> values;
  std::map<std::string, bool> relative;
  for (const RunRow& run : earlier)
    for (const HeadlineRow& h : store.headlines(run.id))
      if (h.low && (h.unit == "exponent" || (h.unit == "ratio" && h.value > 0))) {
        relative[h.name] = h.unit == "ratio";
        values[h.name][run.commit].push_back(relative[h.name] ? std::log(h.value) : h.value);
      }
  struct Pooled {
    double squares = 0;
    int degrees_of_freedom = 0, figures = 0;
  };
  std::map<std::string, Pooled> families;
  nlohmann::json figures = nlohmann::json::object();
  for (const auto& [name, by_commit] : values) {
    double squares = 0;
    int degrees_of_freedom = 0, runs = 0, commits = 0;
    for (const auto& [commit, v] : by_commit) {
      if (v.size() < 2) continue;  // one run of a commit says nothing about its spread
      const double mean = std::accumulate(v.begin(), v.end(), 0.0) / static_cast<double>(v.size());
      for (double x : v) squares += (x - mean) * (x - mean);
      degrees_of_freedom += static_cast<int>(v.size()) - 1;
      runs += static_cast<int>(v.size());
      ++commits;
    }
    if (degrees_of_freedom == 0) continue;
    figures[name] = {{"sd", std::sqrt(squares / degrees_of_freedom)},
                     {"relative", relative[name]},
                     {"runs", runs},
                     {"commits", commits},
                     {"degrees_of_freedom", degrees_of_freedom}};
    if (const std::string family = headline_family(name); !family.empty()) {
      Pooled& f = families[family];
      f.squares += squares;
      f.degrees_of_freedom += degrees_of_freedom;
      ++f.figures;
      figures[name]["family"] = family;
    }
  }
  nlohmann::json family_spread = nlohmann::json::object();
  for (const auto& [family, f] : families)
    family_spread[family] = {{"sd", std::sqrt(f.squares / f.degrees_of_freedom)},
                             {"figures", f.figures},
                             {"degrees_of_freedom", f.degrees_of_freedom}};
  return {{"earlier_runs", earlier.size()},
          {"min_degrees_of_freedom", kRunToRunMinDegreesOfFreedom},
          {"recent_runs_compared", recent_runs},
          {"same", "machine, sweep and point ids; the spread about each commit's own mean, pooled over commits"},
          {"figures", figures},
          {"families", family_spread}};
}

std::string headline_family(const std::string& name) {
  std::vector<std::string> parts;
  for (std::size_t from = 0;;) {
    const std::size_t slash = name.find('/', from);
    parts.push_back(name.substr(from, slash - from));
    if (slash == std::string::npos) break;
    from = slash + 1;
  }
  auto join = [&](std::size_t skip) {
    std::string out;
    for (std::size_t i = 0; i < parts.size(); ++i)
      if (i != skip) out += (out.empty() ? "" : "/") + parts[i];
    return out;
  };
  if (parts.size() >= 3 && parts[0] == "naive_over_flag" && parts[2].rfind("N:", 0) == 0) return join(2);
  if (parts.size() >= 4 && parts[0] == "exponent") return join(1);
  return "";
}

void widen_repeat_intervals(nlohmann::json& doc) {
  if (!doc.contains("measurement") || !doc["measurement"].contains("run_to_run")) return;
  const nlohmann::json& spread = doc["measurement"]["run_to_run"];
  const nlohmann::json figures = spread.value("figures", nlohmann::json::object());
  const nlohmann::json families = spread.value("families", nlohmann::json::object());
  // A spread of run_to_run (a figure's own or its family's) in the figure's units, with Student's t for
  // its degrees of freedom where it has enough to be used (else 0: it reaches nowhere).
  struct Spread {
    double sd = 0, t = 0;
    int degrees_of_freedom = 0;
    const char* from = "";
    double reach() const { return t * sd; }
  };
  auto spread_of = [](const nlohmann::json& s, double scale, const char* from) {
    Spread out{s["sd"].get<double>() * scale, 0, s.value("degrees_of_freedom", 0), from};
    if (out.degrees_of_freedom >= kRunToRunMinDegreesOfFreedom) out.t = student_t_975(out.degrees_of_freedom);
    return out;
  };
  for (const HeadlineRow& h : headlines_of(doc)) {
    if (h.at.empty() || !h.low || !figures.contains(h.name)) continue;
    nlohmann::json& f = doc[nlohmann::json::json_pointer(h.at)];
    const auto& s = figures[h.name];
    if (!f.contains("repeat_low")) continue;
    // The figure's own spread, or its family's pooled one (run_to_run_spread), whichever reaches wider.
    const double scale = s["relative"].get<bool>() ? h.value : 1;
    Spread use = spread_of(s, scale, "figure");
    if (s.contains("family") && families.contains(s["family"].get<std::string>()))
      if (const Spread pooled = spread_of(families[s["family"].get<std::string>()], scale, "family");
          pooled.reach() > use.reach())
        use = pooled;
    if (use.reach() == 0) continue;
    const Interval repeat = repeat_run({h.value, *h.low, *h.high}, use.sd, use.degrees_of_freedom);
    f["repeat_low"] = repeat.low;
    f["repeat_high"] = repeat.high;
    f["run_to_run_sd"] = use.sd;
    f["run_to_run_t"] = use.t;
    f["run_to_run_from"] = use.from;
  }
}

std::int64_t append_run(const std::string& url, const nlohmann::json& doc, const std::string& command) {
  try {
    auto store = Store::open(url, true);
    std::int64_t duplicate_of = 0;
    const auto id = store->append_document(doc, command, "run", &duplicate_of);
    if (duplicate_of) {
      // Not an error: the run is measured and kept, and the sweep's other shards go on; the scheduler's
      // log says which task repeated which.
      const std::string shard = doc["config"]["shard"].get<std::string>();
      fmt::print(stderr, "warning: shard {} of this sweep is already in the results store {} (run {}): appended as run {} "
                         "with status '{}', which series, reports and run-to-run spreads do not count (is --shard {} "
                         "given to two tasks?)\n",
                 shard, store->url(), duplicate_of, id, kDuplicateShard, shard);
      return id;
    }
    fmt::print("appended run {} ({}) to the results store {}\n", id, doc.value("status", "complete"), store->url());
    return id;
  } catch (const std::exception& e) {
    throw std::runtime_error(fmt::format("the results file is written, but {}", e.what()));
  }
}

std::string default_store_url(const std::string& out_dir) {
  return (std::filesystem::path(out_dir) / "history.sqlite").string();
}

}  // namespace bokeh::history
