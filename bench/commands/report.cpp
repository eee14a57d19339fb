// `bokehbench report`: the results store as one static HTML page (html_report.hpp): per series the
// trend over commits with its spread and change points, the latest verdicts, the latest run's plots.
#include <filesystem>

#include <fmt/format.h>

#include "commands.hpp"
#include "history.hpp"
#include "html_report.hpp"
#include "report.hpp"
#include "store.hpp"

namespace bokeh {

namespace {

struct ReportOptions {
  std::string store = history::default_store_url("results"), out = "results/report.html", plots_dir = "plots";
  std::string metric = "wall", sweep;
  double max_p_value = 0.01;
  int permutations = 999, min_segment = 3;
};

void run_report(const ReportOptions& o) {
  check_writable_file(o.out);
  auto store = history::Store::open(o.store, false);
  history::HtmlReportInput in;
  in.store_url = o.store;
  in.metric = history::parse_metric(o.metric);
  in.change_points.max_p_value = o.max_p_value;
  in.change_points.permutations = o.permutations;
  in.change_points.min_segment = o.min_segment;
  in.runs = store->runs();
  for (auto& s : history::series(*store, "", in.metric, in.change_points))
    if (o.sweep.empty() || s.sweep == o.sweep) in.series.push_back(std::move(s));
  for (const char* name : {"figure9.png", "tradeoff.png", "buffers.png"}) {
    const auto path = std::filesystem::path(o.plots_dir) / name;
    if (std::filesystem::exists(path)) in.plot_files.push_back(path.string());
  }
  write_text_atomically(o.out, history::html_report(in));
  std::size_t steps = 0;
  for (const auto& s : in.series) steps += s.steps.size();
  fmt::print("wrote {}: {} runs, {} series, {} change points, {} plots\n", o.out, in.runs.size(), in.series.size(), steps,
             in.plot_files.size());
}

}  // namespace

void add_report_command(CLI::App& app) {
  auto o = std::make_shared<ReportOptions>();
  auto* cmd = app.add_subcommand("report", "Write the results store as a static HTML page (opens from disk): trends over "
                                           "commits with spread and change points, latest verdicts, the latest plots");
  cmd->add_option("--store", o->store, "Results store: a file (SQLite) or postgresql://user@host/db")->capture_default_str();
  cmd->add_option("--out", o->out, "The HTML file")->capture_default_str();
  cmd->add_option("--plots-dir", o->plots_dir, "Where the latest figure9 / tradeoff / buffers PNGs are")->capture_default_str();
  cmd->add_option("--sweep", o->sweep, "Only this sweep's series");
  cmd->add_option("--metric", o->metric, "wall or cpu (process CPU time per frame)")
      ->check(CLI::IsMember({"wall", "cpu"}))
      ->capture_default_str();
  cmd->add_option("--max-p-value", o->max_p_value, "Change points kept at this p-value or below")
      ->check(finite_number())
      ->check(CLI::Range(1e-6, 0.5))
      ->capture_default_str();
  cmd->add_option("--permutations", o->permutations, "Permutations of each test")->check(CLI::Range(19, 100000))->capture_default_str();
  cmd->add_option("--min-segment", o->min_segment, "Commits on each side of a change point, at least")
      ->check(CLI::Range(2, 1000))
      ->capture_default_str();
  cmd->callback([o] { run_report(*o); });
}

}  // namespace bokeh
