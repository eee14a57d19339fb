#!/usr/bin/python3
"""Plot results/figure9.json like the FLAG paper's Figure 9: frame time vs gather size.

usage: plot_figure9.py FIGURE9_JSON OUT_PREFIX   (writes OUT_PREFIX.png and OUT_PREFIX.svg)

One row per backend (GPU and CPU times differ by orders of magnitude on a real GPU, so each gets
its own axes). Left: linear axes, as in the paper. Right: log-log, where a power law is a straight
line and the fitted exponent (legend) is its slope. Markers are medians over the interleaved
samples; bars span the interquartile range; the pale band spans min..max.
"""

import bokehplot
import matplotlib.pyplot as plt
from matplotlib.ticker import NullLocator


def label(series, point):
    fits = series.get("fits", {})
    fit = fits.get("larger_half") or fits.get("all_sizes")
    text = f"{series['method']} ({point['precision']})"
    if fit:
        text += f"  ~N^{fit['exponent']:.2f}"
    return text


def main(doc, prefix):
    cfg = doc["config"]
    colours = bokehplot.method_colours(doc)
    backends = [b for b in ("gpu", "cpu") if any(s["backend"] == b for s in doc["series"])]
    if not backends:
        raise SystemExit("no measured points to plot")
    fig, axes = plt.subplots(len(backends), 2, figsize=(13, 4.8 * len(backends)), constrained_layout=True,
                             squeeze=False)
    device = (doc["context"].get("device") or {}).get("name", "")
    for row, backend in zip(axes, backends):
        for ax, loglog in zip(row, (False, True)):
            order = bokehplot.method_names(doc)
            for s in sorted((s for s in doc["series"] if s["backend"] == backend), key=lambda s: order.index(s["method"])):
                pts = sorted((p for p in doc["points"] if p["method"] == s["method"] and p["backend"] == backend),
                             key=lambda p: p["N"])
                n = [p["N"] for p in pts]
                med = [p["frame_ms"]["median"] for p in pts]
                lo = [p["frame_ms"]["median"] - p["frame_ms"]["q1"] for p in pts]
                hi = [p["frame_ms"]["q3"] - p["frame_ms"]["median"] for p in pts]
                colour = colours[s["method"]]
                ax.errorbar(n, med, yerr=[lo, hi], color=colour, marker="o", ms=4, capsize=3, label=label(s, pts[0]))
                ax.fill_between(n, [p["frame_ms"]["min"] for p in pts], [p["frame_ms"]["max"] for p in pts],
                                color=colour, alpha=0.12, lw=0)
            ax.set_xlabel(f"gather size N (N x N samples at k = {cfg['spacing_px']} px; max CoC radius = k(N-1)/2)")
            ax.set_ylabel("frame time (ms, median; bars: IQR, band: min-max)")
            ax.grid(True, which="both", alpha=0.3)
            where = f"GPU ({device})" if backend == "gpu" else "CPU references"
            if loglog:
                ax.set_xscale("log")
                ax.set_yscale("log")
                ax.set_xticks(cfg["sizes"], [str(n) for n in cfg["sizes"]])
                ax.xaxis.set_minor_locator(NullLocator())
                ax.set_title(f"{where}, log-log: slope = growth exponent (fit: larger half of N)", fontsize=9)
            else:
                ax.set_title(f"{where}: frame time vs filter size (cf. FLAG paper Fig. 9)", fontsize=9)
                ax.set_ylim(bottom=0)
        row[0].legend(fontsize=8, loc="upper left")
    fig.suptitle(f"{cfg['scene']} {cfg['width_px']}x{cfg['height_px']}, measured interleaved "
                 f"({doc['measurement']['rounds']} rounds): {bokehplot.context_line(doc)}", fontsize=9)
    bokehplot.save(fig, prefix)


if __name__ == "__main__":
    bokehplot.run(main, __doc__)
