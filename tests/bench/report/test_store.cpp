// The results store on both back-ends: what is appended reads back exactly; a failed append leaves
// nothing; concurrent writers lose nothing; a newer store is refused without change; bad URLs name the
// problem. PostgreSQL runs when BOKEH_TEST_POSTGRES_HOST (a socket folder) and _USER are set, as
// tests/with_postgres.py sets them around this executable (a throwaway server).
#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <map>
#include <set>
#include <thread>

#include <fmt/format.h>
#include <sqlite3.h>
#ifdef BOKEH_HAVE_PQXX
#include <pqxx/pqxx>
#endif

#include "history.hpp"
#include "html_report.hpp"
#include "intervals.hpp"
#include "merge.hpp"
#include "store.hpp"

namespace bokeh::history {
namespace {

const char* env(const char* name) {
  const char* v = std::getenv(name);
  return v && *v ? v : nullptr;
}

// A fresh, empty store of the back-end under test; `sql` runs raw SQL on it (to tamper with it as a
// newer bokehbench or another tool would).
class StoreTest : public ::testing::TestWithParam<std::string> {
 protected:
  void SetUp() override {
    static std::atomic<int> counter{0};
    const int n = counter++;
    if (GetParam() == "sqlite") {
      dir_ = std::filesystem::temp_directory_path() / fmt::format("bokeh_store_test_{}_{}", ::getpid(), n);
      std::filesystem::remove_all(dir_);
      std::filesystem::create_directories(dir_);
      url_ = (dir_ / "history.sqlite").string();
      return;
    }
#ifdef BOKEH_HAVE_PQXX
    const char *host = env("BOKEH_TEST_POSTGRES_HOST"), *user = env("BOKEH_TEST_POSTGRES_USER");
    if (!host || !user) GTEST_SKIP() << "no PostgreSQL server: run through tests/with_postgres.py (ctest does)";
    const std::string db = fmt::format("store_test_{}_{}", ::getpid(), n);
    pqxx::connection admin(fmt::format("postgresql://{}@/postgres?host={}", user, host));
    pqxx::nontransaction(admin).exec("CREATE DATABASE " + db);
    url_ = fmt::format("postgresql://{}@/{}?host={}", user, db, host);
#else
    GTEST_SKIP() << "built without libpqxx";
#endif
  }
  void TearDown() override {
    if (!dir_.empty()) std::filesystem::remove_all(dir_);
  }
  void sql(const std::string& statement) {
    if (GetParam() == "sqlite") {
      sqlite3* db = nullptr;
      ASSERT_EQ(sqlite3_open(url_.c_str(), &db), SQLITE_OK);
      ASSERT_EQ(sqlite3_exec(db, statement.c_str(), nullptr, nullptr, nullptr), SQLITE_OK) << sqlite3_errmsg(db);
      sqlite3_close(db);
      return;
    }
#ifdef BOKEH_HAVE_PQXX
    pqxx::connection c(url_);
    pqxx::nontransaction(c).exec(statement);
#endif
  }
  std::filesystem::path dir_;
  std::string url_;
};

RunRow a_run(const std::string& commit, const std::string& date, const std::string& status = "complete") {
  RunRow r;
  r.commit = commit, r.date_utc = date, r.machine = "machine A", r.sweep = "figure9", r.status = status;
  r.command = "bokehbench figure9 --quick", r.source = "run", r.context = R"({"git_commit":")" + commit + "\"}";
  return r;
}

std::vector<PointRow> two_points(double scale) {
  PointRow a{"naive/gpu/x", "naive", "gpu", 10 * scale, 9 * scale, 11 * scale, 8 * scale, true,
             {10 * scale, 9 * scale, 11 * scale, 0.1 + 0.2}, {8 * scale, 8 * scale, 8 * scale, 1.0 / 3}};
  PointRow b{"flag/gpu/x", "flag", "gpu", 5, 4, 6, 0, false, {5, 4, 6}, {}};
  return {a, b};
}

// A sweep's calibration probes are headline figures of every run ("probe/NAME", ms), and
// machine_state holds a run's against the median of the same machine's earlier runs: a copy probe
// 1.6x slower (a shared VM's memory-bound phase) is unusual, 1.1x is not, another machine's runs and
// runs beyond the most recent `recent_runs` do not count, and a store with none says so.
TEST_P(StoreTest, MachineStateComparesTheProbesWithThisMachinesEarlierRuns) {
  auto sweep_doc = [](const std::string& cpu, const std::string& date, double copy_ms, double fma_ms) {
    return nlohmann::json{
        {"schema", "bokehbench.figure9"},
        {"status", "complete"},
        {"context", {{"cpu_model", cpu}, {"cpu_cores", 2}, {"date_utc", date}, {"git_commit", "c"}}},
        {"points", nlohmann::json::array()},
        {"measurement",
         {{"probes", {{"gpu_copy", {{"ms", {{"median", copy_ms}}}}}, {"gpu_fma", {{"ms", {{"median", fma_ms}}}}}}}}}};
  };
  auto store = Store::open(url_, true);
  const nlohmann::json first = sweep_doc("EPYC", "2026-01-01T00:00:00Z", 20, 40);
  EXPECT_EQ(machine_state(*store, first)["earlier_runs"], 0);
  store->append_document(sweep_doc("EPYC", "2026-01-01T00:00:00Z", 99, 99), "old", "run");  // beyond the latest 3
  EXPECT_TRUE(machine_state(*store, first)["unusual"].empty()) << "one earlier run is too few to call a phase unusual";
  for (int i = 1; i <= 3; ++i)
    store->append_document(sweep_doc("EPYC", fmt::format("2026-01-0{}T00:00:00Z", i + 1), 19 + i, 40), "x", "run");
  store->append_document(sweep_doc("Xeon", "2026-01-09T00:00:00Z", 5, 5), "other machine", "run");
  const auto h = store->headlines(store->runs().front().id);
  ASSERT_EQ(h.size(), 2u);
  EXPECT_EQ(h[0].name, "probe/gpu_copy");
  EXPECT_EQ(h[0].unit, "ms");

  const nlohmann::json slow = machine_state(*store, sweep_doc("EPYC", "2026-01-10T00:00:00Z", 33.6, 44), 3);
  EXPECT_EQ(slow["earlier_runs"], 3);
  EXPECT_DOUBLE_EQ(slow["probes"]["gpu_copy"]["usual_ms"].get<double>(), 21.0);  // median of 20, 21, 22
  EXPECT_NEAR(slow["probes"]["gpu_copy"]["ratio"].get<double>(), 1.6, 1e-12);
  EXPECT_NEAR(slow["probes"]["gpu_fma"]["ratio"].get<double>(), 1.1, 1e-12);
  EXPECT_EQ(slow["unusual"], nlohmann::json::array({"gpu_copy"}));
  EXPECT_TRUE(machine_state(*store, sweep_doc("EPYC", "2026-01-10T00:00:00Z", 16.8, 40), 3)["unusual"].empty());
  EXPECT_EQ(machine_state(*store, sweep_doc("EPYC", "2026-01-10T00:00:00Z", 10, 40), 3)["unusual"],
            nlohmann::json::array({"gpu_copy"})) << "faster counts too";
}

// run_to_run_spread takes each headline figure's spread over the same machine's earlier complete runs
// with the same point ids (ratios in logs), about each commit's own mean and pooled, and
// widen_repeat_intervals holds a figure9 ratio and exponent to it from kRunToRunMinDegreesOfFreedom
// on: the sample standard deviations of known values, and repeat_run's closed form (Student's t with 2
// degrees of freedom for 3 runs of one commit, 3 once another commit has 2 runs).
TEST_P(StoreTest, RepeatRunIntervalsTakeTheSpreadOfThisMachinesEarlierRuns) {
  auto run_doc = [](const std::string& cpu, const std::string& commit, const std::string& point, int day, double ratio,
                    double exponent, const std::string& status = "complete") {
    return nlohmann::json{
        {"schema", "bokehbench.figure9"},
        {"status", status},
        {"context", {{"cpu_model", cpu}, {"cpu_cores", 2}, {"date_utc", fmt::format("2026-01-{:02}T00:00:00Z", day)},
                     {"git_commit", commit}}},
        {"points", {{{"id", point}, {"method", "naive"}, {"backend", "gpu"}, {"samples_ms", {1.0, 2.0}}}}},
        {"naive_over_flag", {{{"N", 9}, {"backend", "gpu"}, {"naive_over_flag", ratio}, {"low", ratio * 0.99},
                              {"high", ratio * 1.01}, {"repeat_low", 0}, {"repeat_high", 0}}}},
        {"series", {{{"method", "naive"}, {"variant", ""}, {"backend", "gpu"},
                     {"fits", {{"larger_half", {{"exponent", exponent}, {"low", exponent - 0.01}, {"high", exponent + 0.01},
                                                {"repeat_low", 0}, {"repeat_high", 0}}}}}}}}};
  };
  auto store = Store::open(url_, true);
  const nlohmann::json now = run_doc("EPYC", "c", "p", 20, 2.0, 1.5);
  for (int i = 0; i < 2; ++i) store->append_document(run_doc("EPYC", "c", "p", i + 1, 2.0 + 0.2 * i, 1.0 + 0.1 * i), "x", "run");
  // None of these adds to the spread: one run of other code (a level of its own), another machine, other
  // points, not complete.
  store->append_document(run_doc("EPYC", "other", "p", 5, 50, 5), "x", "run");
  store->append_document(run_doc("Xeon", "c", "p", 6, 50, 5), "x", "run");
  store->append_document(run_doc("EPYC", "c", "q", 7, 50, 5), "x", "run");
  store->append_document(run_doc("EPYC", "c", "p", 8, 50, 5, "interrupted"), "x", "run");

  nlohmann::json two = now;
  two["measurement"]["run_to_run"] = run_to_run_spread(*store, now, "figure9");
  EXPECT_EQ(two["measurement"]["run_to_run"]["earlier_runs"], 3);  // c twice and `other` once
  widen_repeat_intervals(two);
  EXPECT_FALSE(two["naive_over_flag"][0].contains("run_to_run_sd")) << "two runs of one commit are too few";
  EXPECT_EQ(two["naive_over_flag"][0]["repeat_low"], 0) << "left as derive wrote it";

  store->append_document(run_doc("EPYC", "c", "p", 3, 2.4, 1.2), "x", "run");
  nlohmann::json doc = now;
  doc["measurement"]["run_to_run"] = run_to_run_spread(*store, now, "figure9");
  const auto& figures = doc["measurement"]["run_to_run"]["figures"];
  EXPECT_EQ(doc["measurement"]["run_to_run"]["earlier_runs"], 4);
  const double mean_log = (std::log(2.0) + std::log(2.2) + std::log(2.4)) / 3;
  const double sd_log = std::sqrt((std::pow(std::log(2.0) - mean_log, 2) + std::pow(std::log(2.2) - mean_log, 2) +
                                   std::pow(std::log(2.4) - mean_log, 2)) / 2);
  EXPECT_NEAR(figures["naive_over_flag/gpu/N:9"]["sd"].get<double>(), sd_log, 1e-12);
  EXPECT_TRUE(figures["naive_over_flag/gpu/N:9"]["relative"].get<bool>());
  EXPECT_NEAR(figures["exponent/naive/gpu/larger_half"]["sd"].get<double>(), 0.1, 1e-12);  // of 1.0, 1.1, 1.2

  widen_repeat_intervals(doc);
  const auto& r = doc["naive_over_flag"][0];
  EXPECT_NEAR(r["run_to_run_sd"].get<double>(), 2.0 * sd_log, 1e-12);  // relative, at this run's 2.0
  const double t = student_t_975(2);  // 3 earlier runs
  EXPECT_NEAR(r["run_to_run_t"].get<double>(), t, 1e-12);
  EXPECT_NEAR(r["repeat_low"].get<double>(), 2.0 - std::sqrt(2.0) * t * 2.0 * sd_log, 1e-12);
  EXPECT_NEAR(r["repeat_high"].get<double>(), 2.0 + std::sqrt(2.0) * t * 2.0 * sd_log, 1e-12);
  const auto& f = doc["series"][0]["fits"]["larger_half"];
  EXPECT_NEAR(f["repeat_low"].get<double>(), 1.5 - std::sqrt(2.0) * t * 0.1, 1e-12);
  EXPECT_NEAR(f["repeat_high"].get<double>(), 1.5 + std::sqrt(2.0) * t * 0.1, 1e-12);

  // A run whose own interval is wider than the spread keeps its own side, sqrt(2) wider.
  nlohmann::json wide = now;
  wide["naive_over_flag"][0]["low"] = 1.0;
  wide["measurement"]["run_to_run"] = doc["measurement"]["run_to_run"];
  widen_repeat_intervals(wide);
  EXPECT_NEAR(wide["naive_over_flag"][0]["repeat_low"].get<double>(), 2.0 - std::sqrt(2.0) * 1.0, 1e-12);
  EXPECT_NEAR(wide["naive_over_flag"][0]["repeat_high"].get<double>(), 2.0 + std::sqrt(2.0) * t * 2.0 * sd_log, 1e-12);

  // A second run of the other commit adds its spread about its own mean (50 and 60, far from 2.0-2.4):
  // the squares pooled over 2 + 1 degrees of freedom.
  store->append_document(run_doc("EPYC", "other", "p", 9, 60, 6), "x", "run");
  nlohmann::json pooled = now;
  pooled["measurement"]["run_to_run"] = run_to_run_spread(*store, now, "figure9");
  const auto& p = pooled["measurement"]["run_to_run"]["figures"]["naive_over_flag/gpu/N:9"];
  const double other_squares = std::pow(std::log(60.0) - std::log(50.0), 2) / 2;
  EXPECT_NEAR(p["sd"].get<double>(), std::sqrt((2 * sd_log * sd_log + other_squares) / 3), 1e-12);
  EXPECT_EQ(p["degrees_of_freedom"], 3);
  EXPECT_EQ(p["commits"], 2);
  EXPECT_EQ(p["runs"], 5);
  EXPECT_NEAR(pooled["measurement"]["run_to_run"]["figures"]["exponent/naive/gpu/larger_half"]["sd"].get<double>(),
              std::sqrt((2 * 0.01 + 0.5) / 3), 1e-12);  // (1.0, 1.1, 1.2) and (5, 6)
  widen_repeat_intervals(pooled);
  EXPECT_NEAR(pooled["naive_over_flag"][0]["run_to_run_t"].get<double>(), student_t_975(3), 1e-12);

  // On another machine, two runs each of two commits suffice (2 degrees of freedom), where two of one do not.
  for (const auto& [commit, day] : {std::pair{"a", 11}, {"a", 12}, {"b", 13}, {"b", 14}})
    store->append_document(run_doc("Xeon Gold", commit, "p", day, 0.1 * day, 1.0), "x", "run");
  nlohmann::json two_commits = run_doc("Xeon Gold", "c", "p", 20, 2.0, 1.5);
  two_commits["measurement"]["run_to_run"] = run_to_run_spread(*store, two_commits, "figure9");
  EXPECT_EQ(two_commits["measurement"]["run_to_run"]["figures"]["naive_over_flag/gpu/N:9"]["degrees_of_freedom"], 2);
  widen_repeat_intervals(two_commits);
  EXPECT_NEAR(two_commits["naive_over_flag"][0]["run_to_run_t"].get<double>(), student_t_975(2), 1e-12);
}

// A family (headline_family: one kind of figure on one backend, in one time) pools its figures' spread:
// two earlier runs of one commit give each of three ratios 1 degree of freedom, too few alone, and their
// family 3, which widen_repeat_intervals then uses (the sample standard deviation pooled by hand).
TEST_P(StoreTest, TwoEarlierRunsMeasureAFamilysSpreadWhereEachFigureHasTooFew) {
  EXPECT_EQ(headline_family("naive_over_flag/gpu/N:9/cpu_time"), "naive_over_flag/gpu/cpu_time");
  EXPECT_EQ(headline_family("naive_over_flag/cpu/N:153"), "naive_over_flag/cpu");
  EXPECT_EQ(headline_family("exponent/naive/gpu/larger_half/cpu_time"), "exponent/gpu/larger_half/cpu_time");
  EXPECT_EQ(headline_family("speedup/adaptive/x"), "");
  auto run_doc = [](int day, const std::vector<double>& ratios) {
    nlohmann::json rows = nlohmann::json::array();
    for (std::size_t i = 0; i < ratios.size(); ++i)
      rows.push_back({{"N", 9 + 24 * static_cast<int>(i)}, {"backend", "gpu"}, {"naive_over_flag", ratios[i]},
                      {"low", ratios[i] * 0.99}, {"high", ratios[i] * 1.01}, {"repeat_low", 0}, {"repeat_high", 0}});
    return nlohmann::json{{"schema", "bokehbench.figure9"},
                          {"status", "complete"},
                          {"context", {{"cpu_model", "EPYC"}, {"cpu_cores", 2},
                                       {"date_utc", fmt::format("2026-02-{:02}T00:00:00Z", day)}, {"git_commit", "c"}}},
                          {"points", {{{"id", "p"}, {"method", "naive"}, {"backend", "gpu"}, {"samples_ms", {1.0}}}}},
                          {"naive_over_flag", rows}};
  };
  auto store = Store::open(url_, true);
  const std::vector<double> first = {1.0, 2.0, 3.0}, second = {1.1, 2.0, 2.7};
  store->append_document(run_doc(1, first), "x", "run");
  store->append_document(run_doc(2, second), "x", "run");
  nlohmann::json doc = run_doc(3, {1.0, 2.0, 3.0});
  doc["measurement"]["run_to_run"] = run_to_run_spread(*store, doc, "figure9");
  double squares = 0;  // about each pair's mean, in logs: (a - b)^2 / 2 a pair
  for (std::size_t i = 0; i < first.size(); ++i) squares += std::pow(std::log(first[i]) - std::log(second[i]), 2) / 2;
  const auto& family = doc["measurement"]["run_to_run"]["families"]["naive_over_flag/gpu"];
  EXPECT_EQ(family["figures"], 3);
  EXPECT_EQ(family["degrees_of_freedom"], 3);
  EXPECT_NEAR(family["sd"].get<double>(), std::sqrt(squares / 3), 1e-12);
  EXPECT_EQ(doc["measurement"]["run_to_run"]["figures"]["naive_over_flag/gpu/N:9"]["degrees_of_freedom"], 1);

  widen_repeat_intervals(doc);
  const double t = student_t_975(3);
  for (std::size_t i = 0; i < first.size(); ++i) {
    const auto& r = doc["naive_over_flag"][i];
    const double sd = first[i] * std::sqrt(squares / 3);  // relative, at this run's estimate
    EXPECT_EQ(r["run_to_run_from"], "family");
    EXPECT_NEAR(r["run_to_run_sd"].get<double>(), sd, 1e-12);
    EXPECT_NEAR(r["run_to_run_t"].get<double>(), t, 1e-12);
    EXPECT_NEAR(r["repeat_low"].get<double>(), first[i] - std::sqrt(2.0) * t * sd, 1e-12);
    EXPECT_NEAR(r["repeat_high"].get<double>(), first[i] + std::sqrt(2.0) * t * sd, 1e-12);
  }
}

TEST_P(StoreTest, WhatIsAppendedReadsBackExactly) {
  auto store = Store::open(url_, true);
  const auto id = store->append(a_run("c1", "2026-01-01T00:00:00Z"), two_points(1));
  const auto runs = store->runs();
  ASSERT_EQ(runs.size(), 1u);
  EXPECT_EQ(runs[0].id, id);
  EXPECT_EQ(runs[0].commit, "c1");
  EXPECT_EQ(runs[0].machine, "machine A");
  EXPECT_EQ(runs[0].context, R"({"git_commit":"c1"})");
  const auto points = store->points(id);
  ASSERT_EQ(points.size(), 2u);  // ordered by id: flag before naive
  EXPECT_EQ(points[1].point_id, "naive/gpu/x");
  EXPECT_EQ(points[1].samples_ms, two_points(1)[0].samples_ms);  // bit for bit, 0.1 + 0.2 and 1/3 included
  EXPECT_EQ(points[1].samples_cpu_ms, two_points(1)[0].samples_cpu_ms);
  EXPECT_TRUE(points[0].samples_cpu_ms.empty());
  EXPECT_TRUE(points[1].settled);
  EXPECT_FALSE(points[0].settled);
}

// Headline figures are series of their own: a paired ratio with its interval, per commit, with the
// step at the commit it was injected; figures read from documents as their commands write them.
TEST_P(StoreTest, HeadlineFiguresAreSeriesWithTheirIntervals) {
  auto store = Store::open(url_, true);
  for (int c = 0; c < 12; ++c) {
    const double r = c < 7 ? 1.0 : 1.06;  // a 6% step: the paired ratio's interval is +-1%
    const double wiggle = 1 + 0.002 * ((c * 7) % 5 - 2);
    store->append(a_run(fmt::format("c{:02d}", c), fmt::format("2026-01-01T00:{:02d}:00Z", c)), two_points(1),
                  {{"new_over_old/naive/gpu/x", "ratio", r * wiggle, r * wiggle * 0.99, r * wiggle * 1.01},
                   {"exponent/flag/gpu/larger_half", "exponent", 1.0, std::nullopt, std::nullopt}});
  }
  const auto runs = store->runs();
  const auto h = store->headlines(runs[0].id);
  ASSERT_EQ(h.size(), 2u);  // by name
  EXPECT_EQ(h[0].name, "exponent/flag/gpu/larger_half");
  EXPECT_FALSE(h[0].low.has_value());
  EXPECT_EQ(h[1].unit, "ratio");
  EXPECT_DOUBLE_EQ(*h[1].low, h[1].value * 0.99);
  const auto ratio = series(*store, "new_over_old/naive/gpu/x", Metric::wall, {});
  ASSERT_EQ(ratio.size(), 1u);
  EXPECT_TRUE(ratio[0].headline);
  EXPECT_EQ(ratio[0].unit, "ratio");
  ASSERT_EQ(ratio[0].values.size(), 12u);
  EXPECT_TRUE(ratio[0].values[3].has_interval);
  EXPECT_DOUBLE_EQ(ratio[0].values[3].q3_ms, ratio[0].values[3].median_ms * 1.01);
  ASSERT_EQ(ratio[0].steps.size(), 1u);
  EXPECT_EQ(ratio[0].steps[0].commit, "c07");
  const auto exponent = series(*store, "exponent/flag/gpu/larger_half", Metric::wall, {});
  ASSERT_EQ(exponent.size(), 1u);
  EXPECT_TRUE(exponent[0].steps.empty());  // constant: no change point
  EXPECT_FALSE(exponent[0].values[0].has_interval);
  EXPECT_EQ(series(*store, "", Metric::wall, {}).size(), 4u);  // two points, two figures
  HtmlReportInput in;
  in.runs = runs;
  in.series = ratio;
  const std::string html = html_report(in);
  EXPECT_NE(html.find("class=\"trend headline\""), std::string::npos);
  EXPECT_NE(html.find("95% interval"), std::string::npos);
}

TEST(Headlines, ReadFromWhatEachCommandDerives) {
  const nlohmann::json figure9 = {
      {"schema", "bokehbench.figure9"},
      {"naive_over_flag", {{{"N", 9}, {"backend", "gpu"}, {"naive_over_flag", 0.75}, {"low", 0.73}, {"high", 0.77}}}},
      {"series", {{{"method", "flag"}, {"variant", ""}, {"backend", "cpu"}, {"time", "process CPU time"},
                   {"fits", {{"larger_half", {{"exponent", 1.1}, {"low", 1.0}, {"high", 1.2}}}}}}}}};
  auto h = headlines_of(figure9);
  ASSERT_EQ(h.size(), 2u);
  EXPECT_EQ(h[0].name, "naive_over_flag/gpu/N:9");  // no time: a run from before CPU time led (wall-clock)
  EXPECT_EQ(*h[0].high, 0.77);
  // Figures in process CPU time are series of their own, apart from the older wall-clock ones.
  EXPECT_EQ(h[1].name, "exponent/flag/cpu/larger_half/cpu_time");
  EXPECT_EQ(h[1].unit, "exponent");
  const nlohmann::json adaptive = {{"schema", "bokehbench.adaptive"},
                                   {"comparisons", {{{"off_id", "naive/a"}, {"speedup", 9.0},
                                                     {"speedup_same_round", {{"median", 10.0}, {"low", 9.5}, {"high", 10.5}}}},
                                                    {{"off_id", "flag/a"}, {"speedup", 2.0}, {"speedup_same_round", nullptr}}}}};
  h = headlines_of(adaptive);
  ASSERT_EQ(h.size(), 2u);
  EXPECT_EQ(h[0].name, "speedup/naive/a");
  EXPECT_EQ(h[0].value, 10.0);  // the paired figure when the run has it
  EXPECT_EQ(h[1].value, 2.0);
  EXPECT_FALSE(h[1].low.has_value());
  const nlohmann::json ab = {{"schema", "bokehbench.ab-figure9"},
                             {"paired_ratios", {{{"id", "naive/x"}, {"ratio", 1.02}, {"low", 1.0}, {"high", 1.04}}}}};
  h = headlines_of(ab);
  ASSERT_EQ(h.size(), 1u);
  EXPECT_EQ(h[0].name, "new_over_old/naive/x");
  // stability: the safe range's extent in cases around the nominal one, and the failures.
  const nlohmann::json stability = {
      {"schema", "bokehbench.stability"},
      {"context", nlohmann::json::object()},
      {"configurations",
       {{{"method", "flag"}, {"precision", "f16"}, {"backend", "gpu"},
         {"cases", {{{"axis", "radius"}, {"label", "0"}, {"status", "ok"}}, {{"axis", "radius"}, {"label", "4"}, {"status", "ok"}},
                    {{"axis", "radius"}, {"label", "16"}, {"status", "ok"}}, {{"axis", "radius"}, {"label", "64"}, {"status", "fail"}}}},
         {"safe_ranges", {{"radius", {{"low", "0"}, {"high", "16"}}}, {"disc", {{"low", nullptr}, {"high", nullptr}}}}}},
        {{"method", "x"}, {"precision", "f32"}, {"backend", "gpu"}, {"skipped", "needs what the device lacks"}}}}};
  h = headlines_of(stability);
  ASSERT_EQ(h.size(), 3u);
  EXPECT_EQ(h[0].name, "flag/f16/gpu/failing_cases");
  EXPECT_EQ(h[0].value, 1);
  EXPECT_EQ(h[1].name, "flag/f16/gpu/safe_range_cases/disc");
  EXPECT_EQ(h[1].value, 0);
  EXPECT_EQ(h[2].name, "flag/f16/gpu/safe_range_cases/radius");
  EXPECT_EQ(h[2].value, 3);
  EXPECT_EQ(run_of(stability, "c", "s").sweep, "stability");  // a run of figures only
  EXPECT_TRUE(headlines_of({{"schema", "bokehbench.tradeoff"}, {"pareto_front", {"a"}}}).empty());
  // buffers: a streamed point's streamed / full ratio, with its interval where the run has one.
  h = headlines_of({{"schema", "bokehbench.buffers"},
                    {"points",
                     {{{"id", "s"}, {"streamed_vs_full", {{"frame_ms_ratio_median", 1.3}, {"low", 1.2}, {"high", 1.5}, {"rounds", 9}}}},
                      {{"id", "old"}, {"streamed_vs_full", {{"frame_ms_ratio_median", 1.4}, {"rounds", 5}}}}}}});
  ASSERT_EQ(h.size(), 2u);
  for (const HeadlineRow& row : h) {
    EXPECT_TRUE(row.name == "streamed_over_full/s" || row.name == "streamed_over_full/old") << row.name;
    EXPECT_EQ(row.low, row.name == "streamed_over_full/s" ? std::optional<double>(1.2) : std::nullopt);
    EXPECT_EQ(row.high, row.name == "streamed_over_full/s" ? std::optional<double>(1.5) : std::nullopt);
  }
}

// A store written before headline figures were stored: read as it is (no figures), and given the
// table on its first append.
TEST_P(StoreTest, StoreWithoutTheHeadlinesTableStillReadsAndTakesFigures) {
  Store::open(url_, true)->append(a_run("c1", "2026-01-01T00:00:00Z"), two_points(1));
  sql("DROP TABLE headlines");
  {
    auto reader = Store::open(url_, false);
    EXPECT_EQ(reader->runs().size(), 1u);
    EXPECT_TRUE(reader->headlines(reader->runs()[0].id).empty());
    EXPECT_EQ(series(*reader, "", Metric::wall, {}).size(), 2u);
  }
  auto writer = Store::open(url_, true);
  writer->append(a_run("c2", "2026-01-02T00:00:00Z"), two_points(1), {{"f", "ratio", 1.5, std::nullopt, std::nullopt}});
  EXPECT_EQ(writer->headlines(writer->runs()[1].id).size(), 1u);
}

TEST_P(StoreTest, SeriesOverCommitsFindTheStepAndSkipInterruptedRuns) {
  auto store = Store::open(url_, true);
  for (int c = 0; c < 12; ++c)
    store->append(a_run(fmt::format("c{:02d}", c), fmt::format("2026-01-01T00:{:02d}:00Z", c)), two_points(c < 7 ? 1.0 : 1.2));
  store->append(a_run("c99", "2026-01-01T01:00:00Z", "interrupted"), two_points(5));  // never in a series
  const auto all = series(*store, "naive/gpu/x", Metric::wall, {});
  ASSERT_EQ(all.size(), 1u);
  ASSERT_EQ(all[0].values.size(), 12u);
  ASSERT_EQ(all[0].steps.size(), 1u);
  EXPECT_EQ(all[0].steps[0].commit, "c07");
  EXPECT_EQ(all[0].steps[0].before_commit, "c06");
  EXPECT_NEAR(all[0].steps[0].ratio, 1.2, 1e-9);
  EXPECT_THROW(series(*store, "no/such/point", Metric::wall, {}), std::runtime_error);
  // The report draws the step.
  HtmlReportInput in;
  in.runs = store->runs();
  in.series = all;
  const std::string html = html_report(in);
  EXPECT_NE(html.find("class=\"change-point\""), std::string::npos);
  EXPECT_NE(html.find("+20.0% at c07"), std::string::npos);
}

// A method package's point: its content hash is stored per point, and an edit of the package at the
// same harness commit is a value of its own in the series, in order, each with its hash.
TEST_P(StoreTest, APackagesEditsAreValuesOfTheirOwnAtOneCommit) {
  auto store = Store::open(url_, true);
  const auto package_points = [](const std::string& hash, double ms) {
    PointRow p{"my_dof/gpu/x", "my_dof", "gpu", ms, ms, ms, 0, true, {ms, ms, ms}, {}, hash};
    return std::vector<PointRow>{p};
  };
  store->append(a_run("c1", "2026-01-01T00:00:00Z"), package_points("aaaa", 10));
  store->append(a_run("c1", "2026-01-01T00:01:00Z"), package_points("aaaa", 10.2));
  store->append(a_run("c1", "2026-01-01T00:02:00Z"), package_points("bbbb", 12));
  const auto all = series(*store, "my_dof/gpu/x", Metric::wall, {});
  ASSERT_EQ(all.size(), 1u);
  ASSERT_EQ(all[0].values.size(), 2u);
  EXPECT_EQ(all[0].values[0].package, "aaaa");
  EXPECT_EQ(all[0].values[0].runs, 2);
  EXPECT_EQ(all[0].values[1].package, "bbbb");
  EXPECT_DOUBLE_EQ(all[0].values[1].median_ms, 12);
  // Read from a results document: the point's package object.
  const nlohmann::json doc = {{"points", {{{"id", "my_dof/gpu/x"}, {"method", "my_dof"}, {"backend", "gpu"},
                                           {"package", {{"name", "my_dof"}, {"hash", "cccc"}, {"path", "/x"}}}}}}};
  EXPECT_EQ(points_of(doc).at(0).package, "cccc");
}

TEST_P(StoreTest, AFailedAppendLeavesNothing) {
  auto store = Store::open(url_, true);
  store->append(a_run("c1", "2026-01-01T00:00:00Z"), two_points(1));
  auto twice = two_points(1);
  twice.push_back(twice[0]);  // the same point twice: the second insert fails inside the transaction
  EXPECT_THROW(store->append(a_run("c2", "2026-01-02T00:00:00Z"), twice), std::runtime_error);
  EXPECT_EQ(store->runs().size(), 1u);
  store->append(a_run("c3", "2026-01-03T00:00:00Z"), two_points(1));  // and the store still takes runs
  EXPECT_EQ(store->runs().size(), 2u);
}

// Runs body(store, w) on `count` threads, each with a store connection of its own, all starting once all
// have connected (as shards finishing together); one that fails to connect still counts as ready, so
// none waits forever. Returns how many threw (each also a test failure).
int at_once(const std::string& url, int count, const std::function<void(Store&, int)>& body) {
  std::vector<std::thread> threads;
  std::atomic<int> failures{0}, ready{0};
  for (int w = 0; w < count; ++w)
    threads.emplace_back([&, w] {
      bool counted = false;
      try {
        auto store = Store::open(url, true);
        ++ready, counted = true;
        while (ready.load() < count) std::this_thread::yield();
        body(*store, w);
      } catch (const std::exception& e) {
        if (!counted) ++ready;
        ++failures;
        ADD_FAILURE() << e.what();
      }
    });
  for (auto& t : threads) t.join();
  return failures;
}

// 8 writers at once (8 shards finishing together), each with a connection of its own: every run is
// stored once, none lost, none twice, each with all its rows.
TEST_P(StoreTest, EightWritersAtOnceLoseAndDuplicateNothing) {
  Store::open(url_, true);
  constexpr int kWriters = 8, kRuns = 25;
  EXPECT_EQ(at_once(url_, kWriters, [](Store& store, int w) {
              for (int r = 0; r < kRuns; ++r)
                store.append(a_run(fmt::format("w{}r{:02d}", w, r), "2026-01-01T00:00:00Z"), two_points(1),
                             {{"f", "ratio", 1.5, 1.4, 1.6}});
            }),
            0);
  auto store = Store::open(url_, false);
  std::multiset<std::string> commits;
  for (const auto& r : store->runs()) {
    commits.insert(r.commit);
    EXPECT_EQ(store->points(r.id).size(), 2u) << r.commit;
    EXPECT_EQ(store->headlines(r.id).size(), 1u) << r.commit;
  }
  std::multiset<std::string> expected;
  for (int w = 0; w < kWriters; ++w)
    for (int r = 0; r < kRuns; ++r) expected.insert(fmt::format("w{}r{:02d}", w, r));
  EXPECT_EQ(commits, expected);  // each exactly once
  EXPECT_EQ(store->series("naive/gpu/x").size(), static_cast<std::size_t>(kWriters * kRuns));
}

// A run's rows go in batches (multi-row INSERTs of at most 500 rows on PostgreSQL): a run of more
// points and figures than one batch holds reads back whole and exact.
TEST_P(StoreTest, ARunLargerThanOneBatchReadsBackWhole) {
  auto store = Store::open(url_, true);
  std::vector<PointRow> points;
  std::vector<HeadlineRow> headlines;
  for (int i = 0; i < 1234; ++i) {
    const double ms = 1 + i / 7.0;
    points.push_back({fmt::format("p/{:04d}", i), "naive", "cpu", ms, ms - 0.5, ms + 0.5, 0, i % 2 == 0, {ms, ms / 3}, {},
                      i % 3 == 0 ? fmt::format("hash{}", i) : ""});
    headlines.push_back({fmt::format("h/{:04d}", i), "ratio", ms, std::nullopt, std::nullopt});
  }
  const auto id = store->append(a_run("c1", "2026-01-01T00:00:00Z"), points, headlines);
  const auto back = store->points(id);
  ASSERT_EQ(back.size(), points.size());
  for (std::size_t i = 0; i < back.size(); ++i) {  // ordered by point id, as written
    EXPECT_EQ(back[i].point_id, points[i].point_id);
    EXPECT_NEAR(back[i].median_ms, points[i].median_ms, 1e-13 * points[i].median_ms);  // SQLite: REALs as 15 digits
    EXPECT_EQ(back[i].samples_ms, points[i].samples_ms);  // bit for bit, 1/3 included
    EXPECT_EQ(back[i].settled, points[i].settled);
  }
  EXPECT_EQ(store->headlines(id).size(), headlines.size());
  EXPECT_EQ(store->series("p/1232").at(0).package, "");
  EXPECT_EQ(store->series("p/1230").at(0).package, "hash1230");
}

// A shard's results document: shard `shard` ("i/n") of a figure9 sweep at commit abc, its one point
// N:i and a probe figure; `job` is context.sweep_id (the scheduler's job; "" none).
nlohmann::json shard_doc(const std::string& shard, const std::string& job, const std::string& status = "complete",
                         bool quick = true) {
  nlohmann::json context = {{"cpu_model", "EPYC"}, {"cpu_cores", 2}, {"date_utc", "2026-02-01T00:00:00Z"}, {"git_commit", "abc"}};
  if (!job.empty()) context["sweep_id"] = job;
  const std::string index = shard.substr(0, shard.find('/'));
  return {{"schema", "bokehbench.figure9"},
          {"status", status},
          {"config", {{"quick", quick}, {"sizes", {5, 9}}, {"shard", shard}}},
          {"context", context},
          {"measurement", {{"probes", {{"cpu_copy", {{"ms", {{"median", 2.0}}}}}}}}},
          {"points", {{{"id", "naive/cpu/N:" + index}, {"method", "naive"}, {"backend", "cpu"},
                       {"frame_ms", {{"median", 1.0}, {"q1", 1.0}, {"q3", 1.0}}}, {"samples_ms", {1.0, 1.0, 1.0}}}}}};
}

// A shard given twice (two tasks with the same --shard) is kept, marked kDuplicateShard, and counted
// nowhere: not in the point's series, not in the headline figures' series, not in the run-to-run
// spread. The same shard of another job, another configuration, or after an interrupted first try
// is a run of its own; a whole sweep run twice is two repeat runs as before.
TEST_P(StoreTest, AShardGivenTwiceIsKeptButCountedOnce) {
  auto store = Store::open(url_, true);
  std::int64_t duplicate_of = -1;
  const auto first = store->append_document(shard_doc("1/2", "slurm:7"), "c", "run", &duplicate_of);
  EXPECT_EQ(duplicate_of, 0);
  store->append_document(shard_doc("2/2", "slurm:7"), "c", "run", &duplicate_of);
  EXPECT_EQ(duplicate_of, 0);
  const auto second = store->append_document(shard_doc("1/2", "slurm:7"), "c", "run", &duplicate_of);
  EXPECT_EQ(duplicate_of, first);
  EXPECT_EQ(store->series("naive/cpu/N:1").size(), 1u);
  EXPECT_EQ(store->series("naive/cpu/N:2").size(), 1u);
  EXPECT_EQ(store->headline_series("probe/cpu_copy").size(), 2u);  // shards 1 and 2, once each
  std::map<std::int64_t, std::string> status;
  for (const auto& r : store->runs()) status[r.id] = r.status;
  EXPECT_EQ(status.at(first), "complete");
  EXPECT_EQ(status.at(second), kDuplicateShard);
  // A third try of the same shard names the first, still the one counted.
  store->append_document(shard_doc("1/2", "slurm:7"), "c", "run", &duplicate_of);
  EXPECT_EQ(duplicate_of, first);
  // Not duplicates: the same shard of a later job, of another configuration, of another count; a
  // rerun after an interrupted try (which counted nowhere); with no job, the first of its kind.
  for (const auto& doc : {shard_doc("1/2", "slurm:8"), shard_doc("1/2", "slurm:7", "complete", false), shard_doc("1/3", "slurm:7"),
                          shard_doc("2/3", "k8s-uid", "interrupted"), shard_doc("2/3", "k8s-uid"), shard_doc("1/2", "")}) {
    store->append_document(doc, "c", "run", &duplicate_of);
    EXPECT_EQ(duplicate_of, 0) << doc["config"].dump() << doc["context"].value("sweep_id", "");
  }
  EXPECT_EQ(store->series("naive/cpu/N:1").size(), 5u);  // jobs 7, 8, 7 unquick, 7 of 3, none
  // With no job, the same commit and configuration are one sweep: a second 1/2 is the duplicate.
  store->append_document(shard_doc("1/2", ""), "c", "run", &duplicate_of);
  EXPECT_NE(duplicate_of, 0);
  // The whole sweep (no shard) twice: two repeat runs, both counted, as before shards were checked.
  nlohmann::json whole = shard_doc("1/2", "slurm:7");
  whole["config"].erase("shard");
  store->append_document(whole, "c", "run", &duplicate_of);
  EXPECT_EQ(duplicate_of, 0);
  store->append_document(whole, "c", "run", &duplicate_of);
  EXPECT_EQ(duplicate_of, 0);
  EXPECT_EQ(store->series("naive/cpu/N:1").size(), 7u);
  // The run-to-run spread reads complete runs only.
  const auto spread = run_to_run_spread(*store, shard_doc("1/2", "slurm:7"), "figure9");
  EXPECT_EQ(spread["earlier_runs"].get<int>(), 7);
}

// Two tasks given the same shard finishing at once: exactly one stays complete, whichever commits
// first (the store serializes writers of one shard), and every shard of the sweep is counted once.
TEST_P(StoreTest, EightTasksOfOneShardAtOnceCountOnce) {
  Store::open(url_, true);
  constexpr int kWriters = 8;
  std::atomic<int> duplicates{0};
  EXPECT_EQ(at_once(url_, kWriters, [&duplicates](Store& store, int) {
              std::int64_t duplicate_of = 0;
              store.append_document(shard_doc("3/4", "slurm:9"), "c", "run", &duplicate_of);
              if (duplicate_of) ++duplicates;
            }),
            0);
  EXPECT_EQ(duplicates, kWriters - 1);
  auto store = Store::open(url_, false);
  const auto runs = store->runs();
  ASSERT_EQ(runs.size(), static_cast<std::size_t>(kWriters));  // every try kept
  EXPECT_EQ(std::count_if(runs.begin(), runs.end(), [](const RunRow& r) { return r.status == "complete"; }), 1);
  EXPECT_EQ(store->series("naive/cpu/N:3").size(), 1u);
}

TEST_P(StoreTest, ANewerStoreIsRefusedAndKeptAsItWas) {
  Store::open(url_, true)->append(a_run("c1", "2026-01-01T00:00:00Z"), two_points(1));
  sql("UPDATE meta SET value = '99' WHERE key = 'schema_version'");
  try {
    Store::open(url_, true);
    FAIL() << "a store of schema version 99 was opened";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("schema version 99, newer than this bokehbench reads (1)"), std::string::npos) << e.what();
  }
  sql("UPDATE meta SET value = '1' WHERE key = 'schema_version'");
  EXPECT_EQ(Store::open(url_, false)->runs().size(), 1u);
}

INSTANTIATE_TEST_SUITE_P(Backends, StoreTest, ::testing::Values("sqlite", "postgresql"),
                         [](const auto& info) { return info.param; });

TEST(StoreUrl, BadUrlsNameTheProblem) {
  auto message = [](const std::string& url, bool create) {
    try {
      Store::open(url, create);
    } catch (const std::runtime_error& e) {
      return std::string(e.what());
    }
    return std::string("opened");
  };
  EXPECT_NE(message("mysql://host/db", true).find("unknown URL scheme 'mysql'"), std::string::npos);
  EXPECT_NE(message("sqlite:", true).find("no file path"), std::string::npos);
  EXPECT_NE(message("/nonexistent/dir/h.sqlite", false).find("no results store at"), std::string::npos);
#ifdef BOKEH_HAVE_PQXX
  // Port 1 on the loopback: nothing listens there.
  EXPECT_NE(message("postgresql://nobody@127.0.0.1:1/db?connect_timeout=5", true).find("cannot connect to the PostgreSQL"),
            std::string::npos);
  EXPECT_NE(message("postgresql://[bad", true).find("PostgreSQL"), std::string::npos);
  // A password in the URL is not printed.
  const std::string with_password = message("postgresql://bench:secret@127.0.0.1:1/db?connect_timeout=5", true);
  EXPECT_EQ(with_password.find("secret"), std::string::npos) << with_password;
  EXPECT_NE(with_password.find("postgresql://bench:***@127.0.0.1:1/db"), std::string::npos) << with_password;
#endif
}

TEST(StoreUrl, AFileThatIsNotAStore) {
  const auto path = std::filesystem::temp_directory_path() / fmt::format("bokeh_not_a_store_{}.sqlite", ::getpid());
  {
    sqlite3* db = nullptr;
    ASSERT_EQ(sqlite3_open(path.c_str(), &db), SQLITE_OK);
    sqlite3_exec(db, "CREATE TABLE other (x)", nullptr, nullptr, nullptr);
    sqlite3_close(db);
  }
  EXPECT_THROW(Store::open(path.string(), false), std::runtime_error);
  std::filesystem::remove(path);
}

// Shards: three documents of one sweep join into one with every point once.
nlohmann::json shard_doc(int index, int count, const std::vector<std::string>& ids, const std::string& cpu = "EPYC") {
  nlohmann::json points = nlohmann::json::array();
  for (const auto& id : ids) points.push_back({{"id", id}, {"samples_ms", {1.0, 2.0, 3.0}}});
  return {{"schema", "bokehbench.figure9"},
          {"schema_version", 2},
          {"status", "complete"},
          {"context", {{"cpu_model", cpu}, {"cpu_cores", 2}, {"git_commit", "abc"}}},
          {"config", {{"sizes", {5, 9}}, {"shard", fmt::format("{}/{}", index, count)}}},
          {"methods", nlohmann::json::array()},
          {"measurement", {{"rounds", index}}},
          {"points", points},
          {"skipped", nlohmann::json::array()},
          {"elapsed_s", 10.0 * index},
          {"series", "derived from this shard's points only"}};
}

TEST(MergeShards, EveryPointOnceAndTheDerivedFiguresDropped) {
  const auto merged = merge_shards({shard_doc(2, 3, {"b"}), shard_doc(1, 3, {"a", "d"}), shard_doc(3, 3, {"c"})},
                                   {"s2.json", "s1.json", "s3.json"});
  std::set<std::string> ids;
  for (const auto& p : merged["points"]) ids.insert(p["id"].get<std::string>());
  EXPECT_EQ(ids, (std::set<std::string>{"a", "b", "c", "d"}));
  EXPECT_EQ(merged["points"].size(), 4u);
  EXPECT_EQ(merged["status"], "complete");
  EXPECT_FALSE(merged["config"].contains("shard"));
  EXPECT_FALSE(merged.contains("series"));
  EXPECT_EQ(merged["shards"].size(), 3u);
  EXPECT_EQ(merged["elapsed_s"], 30.0);
  EXPECT_FALSE(merged["context"].contains("shard_machines"));  // one machine
}

TEST(MergeShards, RefusesWhatIsNotOneWholeSweep) {
  auto message = [](const std::vector<nlohmann::json>& docs) {
    std::vector<std::string> names;
    for (std::size_t i = 0; i < docs.size(); ++i) names.push_back(fmt::format("f{}.json", i));
    try {
      merge_shards(docs, names);
    } catch (const std::runtime_error& e) {
      return std::string(e.what());
    }
    return std::string("merged");
  };
  EXPECT_NE(message({shard_doc(1, 3, {"a"}), shard_doc(2, 3, {"b"})}).find("shard 3/3 is missing"), std::string::npos);
  EXPECT_NE(message({shard_doc(1, 2, {"a"}), shard_doc(1, 2, {"b"})}).find("given twice"), std::string::npos);
  EXPECT_NE(message({shard_doc(1, 2, {"a"}), shard_doc(2, 2, {"a"})}).find("point a is in more than one file"), std::string::npos);
  auto other = shard_doc(2, 2, {"b"});
  other["config"]["sizes"] = {5};
  EXPECT_NE(message({shard_doc(1, 2, {"a"}), other}).find("config.sizes"), std::string::npos);
  EXPECT_NE(message({shard_doc(1, 2, {"a"}), shard_doc(2, 3, {"b"})}).find("one of 2"), std::string::npos);
}

// Shards measured by several processes each (--processes): one round-to-process map is kept only when
// every shard has it; shard 1's map would put the other shards' rounds in the wrong processes.
TEST(MergeShards, TheRoundToProcessMapIsKeptOnlyWhenTheShardsShareIt) {
  auto with_map = [](int index, std::vector<std::string> ids, std::vector<int> map) {
    auto doc = shard_doc(index, 2, ids);
    doc["measurement"]["round_process"] = map;
    return doc;
  };
  const auto same = merge_shards({with_map(1, {"a"}, {0, 0, 1, 1}), with_map(2, {"b"}, {0, 0, 1, 1})}, {"x", "y"});
  EXPECT_EQ(same["measurement"]["round_process"], nlohmann::json({0, 0, 1, 1}));
  const auto differ = merge_shards({with_map(1, {"a"}, {0, 0, 1, 1}), with_map(2, {"b"}, {0, 0, 0, 1, 1})}, {"x", "y"});
  EXPECT_FALSE(differ["measurement"].contains("round_process"));
  const auto one_has = merge_shards({with_map(1, {"a"}, {0, 1}), shard_doc(2, 2, {"b"})}, {"x", "y"});
  EXPECT_FALSE(one_has["measurement"].contains("round_process"));
}

TEST(MergeShards, MachinesAreNamedWhenTheyDiffer) {
  const auto merged = merge_shards({shard_doc(1, 2, {"a"}, "EPYC"), shard_doc(2, 2, {"b"}, "Xeon")}, {"x", "y"});
  ASSERT_TRUE(merged["context"].contains("shard_machines"));
  EXPECT_EQ(merged["context"]["shard_machines"].size(), 2u);
}

}  // namespace
}  // namespace bokeh::history
