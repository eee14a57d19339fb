#!/usr/bin/python3
"""Plot results/figure9.json like the FLAG paper's Figure 9: frame time vs gather size.

usage: plot_figure9.py FIGURE9_JSON OUT_PREFIX   (writes OUT_PREFIX.png and OUT_PREFIX.svg)

Left: linear axes, as in the paper. Right: log-log, where a power law is a straight line and the
fitted exponent (legend) is its slope. Markers are medians; bars span the interquartile range;
the pale band spans min..max over repetitions.
"""

import bokehplot
import matplotlib.pyplot as plt
from matplotlib.ticker import NullLocator

STYLE = {  # method -> colour; backend -> line style and marker
    "naive": "#d62728", "flag": "#1f77b4",
    "circular1": "#2ca02c", "circular2": "#9467bd", "circular3": "#8c564b",
    "circular4": "#e377c2", "circular5": "#7f7f7f", "circular6": "#bcbd22",
}
BACKEND = {"gpu": ("-", "o"), "cpu": ("--", "s")}


def label(series):
    fits = series.get("fits", {})
    fit = fits.get("larger_half") or fits.get("all_sizes")
    text = f"{series['method']} ({series['backend']}"
    if series["method"] == "flag":
        text += f", {series['precision']} layers"
    text += ")"
    if fit:
        text += f"  ~N^{fit['exponent']:.2f}"
    return text


def main(doc, prefix):
    cfg = doc["config"]
    fig, axes = plt.subplots(1, 2, figsize=(13, 5.2), constrained_layout=True)
    for ax, loglog in zip(axes, (False, True)):
        for s in doc["series"]:
            pts = s["points"]
            if not pts:
                continue
            n = [p["N"] for p in pts]
            med = [p["frame_ms"]["median"] for p in pts]
            lo = [p["frame_ms"]["median"] - p["frame_ms"]["q1"] for p in pts]
            hi = [p["frame_ms"]["q3"] - p["frame_ms"]["median"] for p in pts]
            colour = STYLE.get(s["method"], None)
            ls, marker = BACKEND.get(s["backend"], ("-", "o"))
            ax.errorbar(n, med, yerr=[lo, hi], color=colour, ls=ls, marker=marker, ms=4, capsize=3, label=label(s))
            ax.fill_between(n, [p["frame_ms"]["min"] for p in pts], [p["frame_ms"]["max"] for p in pts],
                            color=colour, alpha=0.12, lw=0)
        ax.set_xlabel(f"gather pattern size N (N x N samples at k = {cfg['spacing_px']} px; max CoC radius = k(N-1)/2)")
        ax.set_ylabel("frame time (ms, median; bars: IQR, band: min-max)")
        ax.grid(True, which="both", alpha=0.3)
        if loglog:
            ax.set_xscale("log")
            ax.set_yscale("log")
            ax.set_xticks(cfg["sizes"], [str(n) for n in cfg["sizes"]])
            ax.xaxis.set_minor_locator(NullLocator())
            ax.set_title("log-log: slope = growth exponent (fit over the larger half of N)")
        else:
            ax.set_title("Frame time vs filter size (cf. FLAG paper Fig. 9)")
            ax.set_ylim(bottom=0)
    axes[0].legend(fontsize=8, loc="upper left")
    fig.suptitle(f"{cfg['scene']} {cfg['width_px']}x{cfg['height_px']}: {bokehplot.context_line(doc)}", fontsize=9)
    bokehplot.save(fig, prefix)


if __name__ == "__main__":
    bokehplot.run(main, __doc__)
