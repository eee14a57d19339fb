#!/usr/bin/python3
"""Plot results/buffers.json: FLAG's 3D buffer (or a method's declared buffer scales), memory against error, per resolution.

usage: plot_buffers.py BUFFERS_JSON OUT_PREFIX   (writes OUT_PREFIX.png and OUT_PREFIX.svg)

Top row, one panel per resolution: RMSE against the full-resolution f32 FLAG result vs the 3D
buffer's size (driver's MiB, log-log), one marker per precision, one colour per buffer scale
(purple: the streamed layers, full resolution through a ring of rows),
filled for the largest gather size N and hollow for smaller ones; dotted verticals are the memory
budgets (64 and 16 MiB by default). Exact results (RMSE 0) sit on the bottom edge, marked "exact".
Configurations skipped for the memory budget appear as grey x's on the bottom edge at their size.
Bottom left: RMSE vs gather size N per precision at full scale (solid), at the largest resolution
with data: which precision fails first as radii grow; grey dashed lines are f32 at the reduced
scales, the error that reduced resolution alone costs (it dwarfs every precision's).
Bottom middle: RMSE against the exact scatter (energy sum) of the same radii vs buffer MiB, with
full-res f32 FLAG's own error against it as horizontal lines: context for the top row, since
full-res FLAG carries the pattern of its k-px sample grid and the reduced pipelines do not.
Bottom right: GPU time of the FLAG passes (downsample, bracket, horizontal, vertical, upsample: the
frame without the CoC pass, which every configuration shares) vs buffer MiB at that resolution.
A run with methods other than FLAG (`buffers --methods ./my_dof`) has no full-res f32 FLAG for them: its
error panels read against the exact scatter, and a marker stands for a method and precision.
"""
import sys

import bokehplot
import matplotlib.pyplot as plt

SCALE_COLOURS = {1: "#1f77b4", 2: "#ff7f0e", 4: "#2ca02c"}
STREAMED_COLOUR = "#9467bd"  # layer_buffer = streamed: full resolution through a ring of rows


def streamed(p):
    return p.get("options", {}).get("layer_buffer") == "streamed"


def colour_of(p):
    return STREAMED_COLOUR if streamed(p) else SCALE_COLOURS.get(p["buffer_scale"], "k")


def mib(p):
    """The point's FLAG buffers as allocated (3D image from the driver, plus bracket and low-res buffers)."""
    return p["memory"]["bytes"] / 2**20


def rmse(p, reference):
    return p["error"][reference]["rmse"]


def filter_ms(p):
    """The frame without the CoC pass (flag_passes_ms in results from before packages entered buffers)."""
    return p["filter_passes_ms"] if "filter_passes_ms" in p else p["flag_passes_ms"]


def rmse_floor(points, reference):
    positive = [rmse(p, reference) for p in points if rmse(p, reference) > 0]
    return min(positive) / 10 if positive else 1e-8


def spacing_text(points, cfg):
    """The spacing k of the points measured (sizes given as NxK carry their own), e.g. "k = 1"."""
    ks = sorted({p["k"] for p in points}) or [cfg["spacing_px"]]
    return "k = " + ", ".join(str(k) for k in ks)


def legend_if_labelled(ax, **kwargs):
    """A legend only where something carries a label (a run without f32 or reduced scales has none)."""
    if ax.get_legend_handles_labels()[0]:
        ax.legend(**kwargs)


def res_key(p):
    return (p["width_px"], p["height_px"])


def main(doc, prefix):
    cfg = doc["config"]
    points, skipped = doc["points"], doc.get("skipped", [])
    methods = list(dict.fromkeys(p["method"] for p in points))
    flag_only = methods == ["flag"]
    # Full-res f32 FLAG is a reference for FLAG's points only: with another method, the exact scatter for all.
    reference = "vs_flag_f32" if flag_only else "vs_energy_sum"
    reference_text = "full-res f32 FLAG" if flag_only else "exact scatter (energy sum)"
    key = (lambda p: p["precision"]) if len(methods) < 2 else (lambda p: f"{p['method']} {p['precision']}")
    resolutions = sorted({res_key(p) for p in points} | {res_key(s) for s in skipped}, key=lambda r: r[0] * r[1])
    if not resolutions:
        sys.exit("no points to plot")
    floor = rmse_floor(points, reference)
    budgets = cfg.get("budget_lines_mib", [64, 16])
    largest_n = max(cfg["sizes"])
    precisions = list(dict.fromkeys(key(p) for p in points))
    scales = sorted({p["buffer_scale"] for p in points})
    MARKERS = bokehplot.markers_for(precisions)
    PRECISION_COLOURS = {name: plt.get_cmap("tab10")(i) for i, name in enumerate(precisions)}

    fig = plt.figure(figsize=(max(15, 4.6 * len(resolutions)), 9.8), constrained_layout=True)
    outer = fig.add_gridspec(2, 1)
    top, bottom = outer[0].subgridspec(1, len(resolutions)), outer[1].subgridspec(1, 3)
    for i, res in enumerate(resolutions):
        ax = fig.add_subplot(top[0, i])
        for p in (p for p in points if res_key(p) == res):
            err = rmse(p, reference)
            colour = colour_of(p)
            filled = p["N"] == largest_n
            ax.scatter(mib(p), err if err > 0 else floor, marker=MARKERS.get(key(p), "o"),
                       s=42, color=colour if filled else "none", edgecolors=colour, linewidths=1.2, zorder=3)
            if err == 0:
                ax.annotate("exact", (mib(p), floor), fontsize=7, xytext=(3, 3),
                            textcoords="offset points")
        for s in (s for s in skipped if res_key(s) == res and s["memory"]):
            ax.scatter(mib(s), floor, marker="x", color="0.6", s=30, zorder=2)
        for budget in budgets:
            ax.axvline(budget, color="0.3", ls=":", lw=1)
            ax.annotate(f"{budget:g} MiB", (budget, 1), xycoords=("data", "axes fraction"), fontsize=7, rotation=90,
                        va="top", ha="right")
        if cfg.get("max_buffer_mb"):
            ax.axvline(cfg["max_buffer_mb"], color="#d62728", ls="--", lw=0.8)
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_title(f"{res[0]}x{res[1]}: error vs {'3D-' if flag_only else ''}buffer size", fontsize=10)
        ax.set_xlabel("buffers (MiB, driver's allocation)")
        if i == 0:
            ax.set_ylabel(f"RMSE vs {reference_text} (linear RGB)")
        ax.grid(True, which="both", alpha=0.25)
    # Legend: markers = precision, colours = scale, fill = N.
    handles = [plt.Line2D([], [], ls="", marker=m, color="0.2", label=name) for name, m in MARKERS.items()
               if name in precisions]
    handles += [plt.Line2D([], [], ls="", marker="o", color=c, label=f"scale 1/{s}") for s, c in SCALE_COLOURS.items()
                if s in scales]
    if any(streamed(p) for p in points):
        handles.append(plt.Line2D([], [], ls="", marker="o", color=STREAMED_COLOUR, label="streamed (ring of rows)"))
    handles += [plt.Line2D([], [], ls="", marker="o", markerfacecolor="none", color="0.2", label="N < " + str(largest_n)),
                plt.Line2D([], [], ls="", marker="x", color="0.6", label="skipped (over --max-buffer-mb)")]
    fig.axes[0].legend(handles=handles, fontsize=7, loc="lower left")

    # Bottom: at the largest resolution with measured points.
    with_data = [r for r in resolutions if any(res_key(p) == r for p in points)]
    big = with_data[-1] if with_data else resolutions[-1]
    ax = fig.add_subplot(bottom[0, 0])
    def series(precision, scale):
        return sorted((p for p in points if res_key(p) == big and key(p) == precision and p["buffer_scale"] == scale
                       and not streamed(p)),
                      key=lambda p: p["N"])
    for precision in precisions:
        pts = series(precision, 1)
        if pts:
            ax.plot([p["N"] for p in pts], [max(rmse(p, reference), floor) for p in pts], ls="-",
                    marker=MARKERS.get(precision, "o"), color=PRECISION_COLOURS.get(precision), label=f"{precision} 1/1")
    for scale, grey in ((2, "0.45"), (4, "0.7")):
        for precision in (p for p in precisions if p.endswith("f32")):
            pts = series(precision, scale)
            if pts:
                ax.plot([p["N"] for p in pts], [max(rmse(p, reference), floor) for p in pts], ls="--", marker=".",
                        color=grey, label=f"{precision} 1/{scale} (resolution alone)")
    ax.set_yscale("log")
    ax.set_xlabel(f"gather size N ({spacing_text(points, cfg)} px; max CoC radius k(N-1)/2)")
    ax.set_ylabel(f"RMSE vs {reference_text}")
    ax.set_title(f"{big[0]}x{big[1]}: error vs gather size (which precision fails first as radii grow)", fontsize=10)
    ax.grid(True, which="both", alpha=0.25)
    legend_if_labelled(ax, fontsize=7, ncol=2)

    # Against the exact scatter, for context: full-res FLAG's own error (its k-px sample grid) as a line.
    ax = fig.add_subplot(bottom[0, 1])
    exact_points = [p for p in points if res_key(p) == big]
    for p in exact_points:
        colour = colour_of(p)
        filled = p["N"] == largest_n
        ax.scatter(mib(p), rmse(p, "vs_energy_sum"), marker=MARKERS.get(key(p), "o"),
                   s=42, color=colour if filled else "none", edgecolors=colour, linewidths=1.2)
    for p in exact_points:
        if p["method"] == "flag" and p["precision"] == "f32" and p["buffer_scale"] == 1 and not streamed(p):
            ax.axhline(rmse(p, "vs_energy_sum"), color="0.3", ls="--" if p["N"] == largest_n else ":", lw=1,
                       label=f"full-res f32 FLAG, N = {p['N']}")
    for budget in budgets:
        ax.axvline(budget, color="0.3", ls=":", lw=1)
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("buffers (MiB, driver's allocation)")
    ax.set_ylabel("RMSE vs exact scatter (energy sum)")
    ax.set_title(f"{big[0]}x{big[1]}: error vs the exact scatter, for context", fontsize=10)
    ax.grid(True, which="both", alpha=0.25)
    legend_if_labelled(ax, fontsize=7)

    ax = fig.add_subplot(bottom[0, 2])
    for p in (p for p in points if res_key(p) == big):
        colour = colour_of(p)
        filled = p["N"] == largest_n
        ax.scatter(mib(p), filter_ms(p),
                   marker=MARKERS.get(key(p), "o"),
                   s=42, color=colour if filled else "none", edgecolors=colour, linewidths=1.2)
    for budget in budgets:
        ax.axvline(budget, color="0.3", ls=":", lw=1)
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("buffers (MiB, driver's allocation)")
    ax.set_ylabel("GPU time of the filter passes (ms, medians; frame minus CoC)")
    ax.set_title(f"{big[0]}x{big[1]}: time vs buffer size (markers as above)", fontsize=10)
    ax.grid(True, which="both", alpha=0.25)

    fig.suptitle(f"{'FLAG 3D buffer' if flag_only else ', '.join(methods) + ': buffer'} precision x scale, {cfg['scene']}, N {cfg['sizes']}, {spacing_text(points, cfg)}\n"
                 f"{bokehplot.context_line(doc)}", fontsize=9)
    bokehplot.save(fig, prefix)


if __name__ == "__main__":
    bokehplot.run(main, __doc__)
