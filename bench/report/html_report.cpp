#include "html_report.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

#include <fmt/format.h>

namespace bokeh::history {

namespace {

std::string escape(const std::string& text) {
  std::string out;
  for (char c : text) switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      case '\'': out += "&#39;"; break;
      default: out += c;
    }
  return out;
}

std::string base64(const std::string& bytes) {
  static const char* table = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  std::size_t i = 0;
  for (; i + 2 < bytes.size(); i += 3) {
    const unsigned v = (static_cast<unsigned char>(bytes[i]) << 16) | (static_cast<unsigned char>(bytes[i + 1]) << 8) |
                       static_cast<unsigned char>(bytes[i + 2]);
    out += {table[v >> 18], table[(v >> 12) & 63], table[(v >> 6) & 63], table[v & 63]};
  }
  if (i + 1 == bytes.size()) {
    const unsigned v = static_cast<unsigned char>(bytes[i]) << 16;
    out += {table[v >> 18], table[(v >> 12) & 63], '=', '='};
  } else if (i + 2 == bytes.size()) {
    const unsigned v = (static_cast<unsigned char>(bytes[i]) << 16) | (static_cast<unsigned char>(bytes[i + 1]) << 8);
    out += {table[v >> 18], table[(v >> 12) & 63], table[(v >> 6) & 63], '='};
  }
  return out;
}

std::string short_commit(const std::string& c) { return c.size() > 12 ? c.substr(0, 12) : c; }
std::string percent(double ratio) { return fmt::format("{:+.1f}%", (ratio - 1) * 100); }

}  // namespace

std::string series_svg(const Series& s) {
  const double width = 640, height = 170, left = 56, right = 12, top = 12, bottom = 28;
  double lo = 1e300, hi = -1e300;
  for (const auto& v : s.values) lo = std::min(lo, v.q1_ms), hi = std::max(hi, v.q3_ms);
  if (!(hi > lo)) lo -= 0.5, hi += 0.5;
  const double pad = (hi - lo) * 0.08;
  lo -= pad, hi += pad;
  const std::size_t n = s.values.size();
  auto x = [&](std::size_t i) { return left + (n > 1 ? (width - left - right) * i / (n - 1.0) : (width - left - right) / 2); };
  auto y = [&](double v) { return top + (height - top - bottom) * (hi - v) / (hi - lo); };
  std::string svg = fmt::format("<svg class=\"trend{}\" xmlns=\"http://www.w3.org/2000/svg\" width=\"{}\" height=\"{}\" "
                                "viewBox=\"0 0 {} {}\" role=\"img\" aria-label=\"{}\">\n",
                                s.headline ? " headline" : "", width, height, width, height, escape(s.point_id));
  svg += fmt::format("<rect x=\"{}\" y=\"{}\" width=\"{}\" height=\"{}\" fill=\"#fafafa\" stroke=\"#ccc\"/>\n", left, top,
                     width - left - right, height - top - bottom);
  for (int t = 0; t <= 4; ++t) {  // value ticks
    const double v = lo + (hi - lo) * t / 4;
    svg += fmt::format("<text x=\"{}\" y=\"{:.1f}\" font-size=\"10\" text-anchor=\"end\">{:.4g}</text>\n", left - 4, y(v) + 3, v);
  }
  std::string band_top, band_bottom, line;
  for (std::size_t i = 0; i < n; ++i) {
    band_top += fmt::format("{:.1f},{:.1f} ", x(i), y(s.values[i].q3_ms));
    band_bottom = fmt::format("{:.1f},{:.1f} ", x(i), y(s.values[i].q1_ms)) + band_bottom;
    line += fmt::format("{:.1f},{:.1f} ", x(i), y(s.values[i].median_ms));
  }
  svg += "<polygon fill=\"#9ecae1\" fill-opacity=\"0.5\" points=\"" + band_top + band_bottom + "\"/>\n";
  svg += "<polyline fill=\"none\" stroke=\"#08519c\" stroke-width=\"1.5\" points=\"" + line + "\"/>\n";
  for (std::size_t i = 0; i < n; ++i)
    svg += fmt::format("<circle cx=\"{:.1f}\" cy=\"{:.1f}\" r=\"2.5\" fill=\"#08519c\"><title>{}: {} {:.4g} {} [{:.4g}-{:.4g}]{}, "
                       "{} run(s)</title></circle>\n",
                       x(i), y(s.values[i].median_ms), escape(short_commit(s.values[i].commit)), s.headline ? "value" : "median",
                       s.values[i].median_ms, escape(s.unit), s.values[i].q1_ms, s.values[i].q3_ms,
                       !s.headline ? " IQR" : s.values[i].has_interval ? " 95% interval" : " over runs", s.values[i].runs);
  for (const auto& step : s.steps) {  // the step lies between the commit before and the one after
    const double sx = (x(step.index - 1) + x(step.index)) / 2;
    svg += fmt::format("<line class=\"change-point\" x1=\"{0:.1f}\" x2=\"{0:.1f}\" y1=\"{1}\" y2=\"{2}\" stroke=\"#d62728\" "
                       "stroke-dasharray=\"4 3\" stroke-width=\"1.5\"/>\n",
                       sx, top, height - bottom);
    svg += fmt::format("<text x=\"{:.1f}\" y=\"{}\" font-size=\"10\" fill=\"#d62728\">{} at {} (p {:.3f})</text>\n", sx + 3,
                       top + 11, percent(step.ratio), escape(short_commit(step.commit)), step.p_value);
  }
  svg += fmt::format("<text x=\"{}\" y=\"{}\" font-size=\"10\">{} commits, oldest to newest</text>\n", left,
                     height - 8, n);
  return svg + "</svg>\n";
}

std::string html_report(const HtmlReportInput& in) {
  std::string html;
  html += "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n<title>bokehbench history</title>\n";
  html += "<style>body{font-family:sans-serif;margin:1.5em;max-width:1100px}table{border-collapse:collapse;font-size:13px}"
          "td,th{border:1px solid #ccc;padding:2px 6px;text-align:left}.slower{color:#b00}.faster{color:#070}"
          "section.series{margin:1em 0}h3{font-size:14px;margin:.2em 0;font-family:monospace}img.plot{max-width:100%}</style>\n";
  html += "</head>\n<body>\n<h1>bokehbench: history of every run</h1>\n";
  std::set<std::string> machines, commits;
  for (const auto& r : in.runs) machines.insert(r.machine), commits.insert(r.commit);
  html += fmt::format("<p>Store <code>{}</code>: {} runs, {} commits, {} machine(s). Series: {}, one per point and "
                      "machine (runs on different machines are never pooled). Change points: E-divisive means "
                      "(Matteson &amp; James 2014) on the log of each commit's median, permutation test, p &le; {} "
                      "({} permutations), at least {} commits a side.</p>\n",
                      escape(in.store_url), in.runs.size(), commits.size(), machines.size(), metric_name(in.metric),
                      in.change_points.max_p_value, in.change_points.permutations, in.change_points.min_segment);

  // The latest verdicts: for each series, its newest commit against the one before and its last step.
  html += "<h2>Latest verdicts</h2>\n<table id=\"verdicts\">\n<tr><th>point</th><th>machine</th><th>latest commit</th>"
          "<th>median ms, or figure</th><th>vs previous commit</th><th>last change point</th></tr>\n";
  std::vector<const Series*> order;
  for (const auto& s : in.series) order.push_back(&s);
  std::stable_sort(order.begin(), order.end(), [](const Series* a, const Series* b) {
    const std::size_t sa = a->steps.empty() ? 0 : a->steps.back().index + 1, sb = b->steps.empty() ? 0 : b->steps.back().index + 1;
    return sa > sb;  // series with the most recent steps first
  });
  for (const Series* s : order) {
    const CommitValue& last = s->values.back();
    std::string vs = "-";
    if (s->values.size() > 1) {
      const double r = last.median_ms / s->values[s->values.size() - 2].median_ms;
      vs = fmt::format("<span class=\"{}\">{}</span>", r > 1 ? "slower" : "faster", percent(r));
    }
    std::string step = "none";
    if (!s->steps.empty()) {
      const Step& st = s->steps.back();
      step = fmt::format("<span class=\"{}\">{}</span> at {} (p {:.3f}, {} commit(s) ago)", st.ratio > 1 ? "slower" : "faster",
                         percent(st.ratio), escape(short_commit(st.commit)), st.p_value, s->values.size() - st.index);
    }
    html += fmt::format("<tr><td><code>{}</code></td><td>{}</td><td>{}</td><td>{:.4g}{} [{:.4g}-{:.4g}]</td><td>{}</td><td>{}</td></tr>\n",
                        escape(s->point_id), escape(s->machine), escape(short_commit(last.commit)), last.median_ms,
                        s->headline ? " " + escape(s->unit) : "", last.q1_ms, last.q3_ms, vs, step);
  }
  html += "</table>\n";

  html += "<h2>Latest run's plots</h2>\n";
  if (in.plot_files.empty()) html += "<p>No plots found.</p>\n";
  for (const auto& path : in.plot_files) {
    std::ifstream file(path, std::ios::binary);
    std::ostringstream bytes;
    bytes << file.rdbuf();
    html += fmt::format("<figure><img class=\"plot\" alt=\"{0}\" src=\"data:image/png;base64,{1}\"><figcaption>{0}</figcaption></figure>\n",
                        escape(std::filesystem::path(path).filename().string()), base64(bytes.str()));
  }

  // Headline figures first: a paired ratio's interval is a few percent wide, where a point's own
  // median moves 12-17% between single runs, so steps of 5-10% show here first.
  html += "<h2>Headline figures over commits</h2>\n<p>What each run derived (figure9's naive/FLAG ratios and growth "
          "exponents, adaptive's speed-ups, ab's paired new/old ratio per point, stability's safe ranges): the value "
          "per commit (line) and the run's 95% interval (band; where a run gave none, the spread over the commit's "
          "runs), change points as below.</p>\n";
  std::size_t headlines = 0;
  for (const Series* s : order)
    if (s->headline) {
      ++headlines;
      html += fmt::format("<section class=\"series headline\"><h3>{} <small>({}; {}; {})</small></h3>\n", escape(s->point_id),
                          escape(s->unit), escape(s->sweep), escape(s->machine));
      html += series_svg(*s) + "</section>\n";
    }
  if (headlines == 0) html += "<p>No headline figures in the store.</p>\n";

  html += "<h2>Trends over commits</h2>\n<p>Median per commit (line), interquartile range of its samples (band), change "
          "points (red, dashed: the step lies between two commits; the label names the first commit after it).</p>\n";
  for (const Series* s : order) {
    if (s->headline) continue;
    html += fmt::format("<section class=\"series\"><h3>{} <small>({}; {})</small></h3>\n", escape(s->point_id), escape(s->sweep),
                        escape(s->machine));
    html += series_svg(*s) + "</section>\n";
  }

  html += "<h2>Runs</h2>\n<table id=\"runs\">\n<tr><th>id</th><th>date (UTC)</th><th>commit</th><th>sweep</th><th>shard</th>"
          "<th>status</th><th>machine</th></tr>\n";
  for (auto it = in.runs.rbegin(); it != in.runs.rend(); ++it)
    html += fmt::format("<tr><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td></tr>\n", it->id,
                        escape(it->date_utc), escape(short_commit(it->commit)), escape(it->sweep),
                        escape(it->shard.empty() ? "all" : it->shard), escape(it->status), escape(it->machine));
  html += "</table>\n";
  // A self-check the browser test reads: every plot image decoded, every trend drawn.
  html += "<script>\nwindow.addEventListener('load', function () {\n"
          "  var imgs = Array.from(document.images), bad = imgs.filter(function (i) { return !i.complete || i.naturalWidth === 0; });\n"
          "  bad.forEach(function (i) { console.error('plot did not load: ' + i.alt); });\n"
          "  document.body.setAttribute('data-rendered', 'trends:' + document.querySelectorAll('svg.trend').length + "
          "' headlines:' + document.querySelectorAll('svg.trend.headline').length + "
          "' images:' + (imgs.length - bad.length) + '/' + imgs.length);\n});\n</script>\n";
  return html + "</body>\n</html>\n";
}

}  // namespace bokeh::history
