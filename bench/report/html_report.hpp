#pragma once
// The static HTML report of a results store: one self-contained page (inline SVG trends, PNG plots
// embedded as data URIs, no script from elsewhere), which opens from disk with no server.
#include <string>
#include <vector>

#include "history.hpp"

namespace bokeh::history {

struct HtmlReportInput {
  std::string store_url;
  Metric metric = Metric::wall;
  ChangePointOptions change_points;
  std::vector<RunRow> runs;
  std::vector<Series> series;
  std::vector<std::string> plot_files;  // PNGs of the latest run (figure9, tradeoff, buffers), embedded
};

std::string html_report(const HtmlReportInput& input);

// One series as an inline SVG: the median per commit, its interquartile band, the change points marked.
std::string series_svg(const Series& s);

}  // namespace bokeh::history
