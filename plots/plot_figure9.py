#!/usr/bin/python3
"""Plot results/figure9.json like the FLAG paper's Figure 9: frame time vs gather size.

usage: plot_figure9.py FIGURE9_JSON OUT_PREFIX
  writes OUT_PREFIX.png/.svg: the paper's figure, naive gather vs FLAG;
  and OUT_PREFIX_methods.png/.svg when the run measured other methods too.

Where the CPU does the work (lavapipe, the CPU references) the times are process CPU time (the cores'
work per frame, which a competing process inflates less than wall-clock), else wall-clock; the axes say which.
The paper's figure has one row per backend (GPU and CPU times differ by orders of magnitude on a
real GPU, so each gets its own axes): frame time on linear axes, as in the paper; the same on log-log
axes, where a power law is a straight line and the fitted exponent (legend) its slope; and naive /
FLAG at each N. Markers are medians, bars and bands their 95% intervals (order statistics of the rounds).
A CPU baseline (figure9 --cpu-baseline: OpenCV's cv::filter2D with one fixed disc, no CoC) is a dashed line
on the GPU axes, in the GPU points' time, with FLAG / baseline in its legend label.
The other methods' figure has a log time axis, so that no curve flattens the rest.
"""

import bokehplot
import plot_roofline
import matplotlib.pyplot as plt
from matplotlib.ticker import NullLocator, ScalarFormatter

PAPER = ("naive", "flag")


def curve_point(doc, series, backend):
    """A point of the curve: its method, backend, precision and options off their defaults (the series'
    variant, less the precision figure9 adds where a run holds several)."""
    options = series.get("variant", "").split("/precision:")[0]
    return next(p for p in doc["points"] if p["method"] == series["method"] and p["backend"] == backend
                and p["precision"] == series.get("precision", p["precision"]) and p.get("variant", "") == options)


def label(series, point):
    fit = series["fits"].get("larger_half") or series["fits"].get("all_sizes")
    name = series["method"] + point.get("variant", "")
    text = f"{name} ({point['precision']})"
    as_run = point.get("work", {}).get("options_as_run", {})
    if "layer_buffer" in as_run:  # what auto became on this device (FLAG: registers on lavapipe)
        text = f"{name} ({point['precision']}, layers: {as_run['layer_buffer']})"
    if fit:
        text += f"  ~N^{fit['exponent']:.2f} [{fit['low']:.2f}, {fit['high']:.2f}]"
    unclipped = series["fits"].get("larger_half_unclipped")
    if unclipped:  # without the frame's clipping of the pattern (figure9.json: frame_clipping)
        text += f", unclipped {unclipped['exponent']:.2f}"
    return text


def draw_curves(ax, doc, backend, methods, colours):
    """Each curve in its method's colour; a method's further variants and precisions dotted and dash-dotted
    (dashed lines are the CPU baselines)."""
    drawn = {}
    for s in doc["series"]:
        if s["backend"] != backend or s["method"] not in methods:
            continue
        point = curve_point(doc, s, backend)
        nth = drawn[s["method"]] = drawn.get(s["method"], -1) + 1
        med = s["median_ms"]
        lo = [m - low for m, low in zip(med, s["median_ms_low"])]
        hi = [high - m for m, high in zip(med, s["median_ms_high"])]
        ax.errorbar(s["N"], med, yerr=[lo, hi], color=colours[s["method"]], marker="osD^v"[nth % 5], ms=4, capsize=3,
                    ls=("-", ":", "-.")[nth % 3], label=label(s, point))


def draw_baselines(ax, doc, backend):
    """The CPU baselines as dashed lines beside the GPU curves (their series are in the GPU points' time)."""
    if backend != "gpu":
        return
    for s in doc.get("baseline_series", []):
        b = next(x for x in doc["baselines"] if x["baseline"] == s["baseline"])
        med = s["median_ms"]
        lo = [m - low for m, low in zip(med, s["median_ms_low"])]
        hi = [high - m for m, high in zip(med, s["median_ms_high"])]
        ratios = [r for r in doc.get("flag_over_baseline", []) if r["baseline"] == s["baseline"]]
        text = f"{b['label']} (CPU, {b['threads']} threads; fixed disc, no CoC)"
        if ratios:
            last = max(ratios, key=lambda r: r["N"])
            text += f"; FLAG / {b['label']} {last['flag_over_baseline']:.2f}x at N={last['N']}"
        ax.errorbar(s["N"], med, yerr=[lo, hi], color="tab:grey", ls="--", marker="s", ms=3, capsize=2, label=text)


def size_axis(ax, cfg, log):
    ax.set_xlabel(f"gather size N (N x N samples at k = {cfg['spacing_px']} px)")
    ax.grid(True, which="both", alpha=0.3)
    if log:
        ax.set_xscale("log")
        ax.set_xticks(cfg["sizes"], [str(n) for n in cfg["sizes"]])
        ax.xaxis.set_minor_locator(NullLocator())


def time_of(doc, backend):
    """What a backend's figures are in: process CPU time where the CPU does the work (all cores' work per
    frame, about cores x wall-clock when they are busy), else wall-clock (cmd_figure9.cpp: cpu_time_leads)."""
    return next((s.get("time") for s in doc["series"] if s["backend"] == backend), None) or "wall-clock time"


def where(doc, backend):
    """A panel's backend, short: the device's full name and driver are in the figure's title line."""
    device = (doc["context"].get("device") or {}).get("name", "").split(" (")[0]
    return f"GPU ({device})" if backend == "gpu" else "CPU references"


def paper_figure(doc, prefix, backends, colours):
    cfg = doc["config"]
    fig, axes = plt.subplots(len(backends), 3, figsize=(17, 4.8 * len(backends)), constrained_layout=True,
                             squeeze=False)
    for row, backend in zip(axes, backends):
        for ax, log in zip(row[:2], (False, True)):
            draw_curves(ax, doc, backend, PAPER, colours)
            draw_baselines(ax, doc, backend)
            size_axis(ax, cfg, log)
            ax.set_ylabel(f"frame time ({time_of(doc, backend)}, ms): median, 95% interval")
            if log:
                ax.set_yscale("log")
                ax.yaxis.set_major_formatter(ScalarFormatter())
                ax.set_title(f"{where(doc, backend)}, log-log: slope = growth exponent (fit: larger half of N)",
                             fontsize=9)
            else:
                ax.set_ylim(bottom=0)
                ax.set_title(f"{where(doc, backend)}: frame time vs filter size (cf. FLAG paper Fig. 9)", fontsize=9)
        row[0].legend(fontsize=8, loc="upper left")
        ratios = sorted((r for r in doc["naive_over_flag"] if r["backend"] == backend), key=lambda r: r["N"])
        ax = row[2]
        if ratios:
            n = [r["N"] for r in ratios]
            ax.fill_between(n, [r["low"] for r in ratios], [r["high"] for r in ratios], color="tab:grey", alpha=0.3,
                            lw=0, label="95% interval")
            ax.plot(n, [r["naive_over_flag"] for r in ratios], "o-", color="black", ms=4,
                    label="naive / FLAG (paired per round)")
            ax.axhline(1, color="tab:red", lw=0.8, ls="--")
            ax.legend(fontsize=8, loc="upper left")
        size_axis(ax, cfg, False)
        ax.set_ylim(bottom=0)
        ax.set_ylabel(f"naive / FLAG frame time ({time_of(doc, backend)})")
        ax.set_title(f"{where(doc, backend)}: FLAG's speed-up over the naive gather", fontsize=9)
    h = doc.get("headlines", {})
    verdict = "settled" if h.get("settled") else f"NOT settled ({h.get('stop_reason', '')})"
    fig.suptitle(f"{cfg['scene']} {cfg['width_px']}x{cfg['height_px']}, {doc['measurement']['rounds']} interleaved "
                 f"rounds, {verdict}: {bokehplot.context_line(doc)}", fontsize=9)
    bokehplot.save(fig, prefix)


def methods_figure(doc, prefix, backends, colours):
    cfg = doc["config"]
    methods = bokehplot.method_names(doc)
    fig, axes = plt.subplots(1, len(backends), figsize=(8 * len(backends), 5.5), constrained_layout=True, squeeze=False)
    for ax, backend in zip(axes[0], backends):
        draw_curves(ax, doc, backend, methods, colours)
        draw_baselines(ax, doc, backend)
        size_axis(ax, cfg, False)
        ax.set_yscale("log")
        ax.yaxis.set_major_formatter(ScalarFormatter())
        ax.set_ylabel(f"frame time ({time_of(doc, backend)}, ms, log): median, 95% interval")
        ax.set_title(f"{where(doc, backend)}: every method measured", fontsize=9)
        ax.legend(fontsize=7, loc="upper left")
    fig.suptitle(f"{cfg['scene']} {cfg['width_px']}x{cfg['height_px']}: {bokehplot.context_line(doc)}", fontsize=9)
    bokehplot.save(fig, prefix + "_methods")


def main(doc, prefix):
    colours = bokehplot.method_colours(doc)
    backends = [b for b in ("gpu", "cpu") if any(s["backend"] == b for s in doc["series"])]
    if not backends:
        raise SystemExit("no measured points to plot")
    if any(s["method"] in PAPER for s in doc["series"]):
        paper_figure(doc, prefix, backends, colours)
    if any(s["method"] not in PAPER for s in doc["series"]):
        methods_figure(doc, prefix, backends, colours)
    plot_roofline.roofline_figure(doc, prefix + "_roofline")


if __name__ == "__main__":
    bokehplot.run(main, __doc__)
