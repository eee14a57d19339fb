#!/usr/bin/python3
"""Plot results/tradeoff.json: frame time against accuracy, with the Pareto front.

usage: plot_tradeoff.py TRADEOFF_JSON OUT_PREFIX   (writes OUT_PREFIX.png and OUT_PREFIX.svg)

x: median frame time (log scale; bars: its 95% interval, frame_ms_interval). y: PSNR against the exact
energy-sum scatter (higher is better). Colour: method (registry order); marker: intermediate
precision; hollow markers: intermediates at reduced resolution (marker size shrinks with the
scale). A staircase (one per aperture, each scored against its own shape) joins the Pareto front,
labelled: for a time budget on the x axis, the best accuracy any configuration offers. Exact results (PSNR infinite) sit on the dotted line at the top.
"""

import itertools

import bokehplot
import plot_roofline
import matplotlib.pyplot as plt
from matplotlib.lines import Line2D

SIZE = {1: 8, 2: 6.5, 4: 5}


def short_id(c):
    """The id without what every point of this plot shares (backend, scene, resolution)."""
    parts = c["id"].split("/")
    return "/".join([parts[0]] + parts[4:])


def aperture_of(c):
    """The aperture a point drew (files from before apertures: the disc)."""
    return c.get("aperture", {}).get("name", "disc")


def psnr_of(c, cap):
    p = c["error"]["vs_energy_sum"]["psnr_db"]
    return cap if p is None else p  # null PSNR with a finite RMSE: exact


def main(doc, prefix):
    cfg = doc["config"]
    # A result with inf/NaN has no metrics (all null): it cannot be placed, so it is counted instead.
    configs = [c for c in doc["points"] if c["error"]["vs_energy_sum"]["rmse"] is not None]
    unplaced = len(doc["points"]) - len(configs)
    COLOURS = bokehplot.method_colours(doc)
    MARKERS = bokehplot.markers_for(c["precision"] for c in doc["points"])
    finite = [c["error"]["vs_energy_sum"]["psnr_db"] for c in configs
              if c["error"]["vs_energy_sum"]["psnr_db"] is not None]
    cap = (max(finite) + 5) if finite else 60
    fig, ax = plt.subplots(figsize=(13, 6.5), constrained_layout=True)
    for c in configs:
        t = c["frame_ms_interval"]
        scale = c["buffer_scale"]
        colour = COLOURS.get(c["method"], "k")
        ax.errorbar([t["estimate"]], [psnr_of(c, cap)], xerr=[[t["estimate"] - t["low"]], [t["high"] - t["estimate"]]],
                    color=colour, marker=MARKERS.get(c["precision"], "o"), ms=SIZE.get(scale, 5), capsize=2,
                    ls="none", mfc=colour if scale == 1 else "none", alpha=0.85)
    ids = {c["id"]: c for c in configs}
    front = [ids[i] for i in doc["pareto_front"] if i in ids]
    # One staircase per aperture: each is scored against its own shape's exact reference.
    apertures = list(dict.fromkeys(aperture_of(c) for c in front))
    styles = dict(zip(apertures, itertools.cycle(["-", "--", ":", "-."])))
    for aperture, style in styles.items():
        xs, ys = [], []
        for c in (c for c in front if aperture_of(c) == aperture):
            if xs:
                xs.append(c["frame_ms"]["median"])
                ys.append(ys[-1])
            xs.append(c["frame_ms"]["median"])
            ys.append(psnr_of(c, cap))
        ax.plot(xs, ys, color="black", lw=1.2, alpha=0.6, ls=style)
    if front:
        for c in front:
            ax.annotate(f"{short_id(c)}\n{c['frame_ms']['median']:.1f} ms, {psnr_of(c, cap):.1f} dB",
                        (c["frame_ms"]["median"], psnr_of(c, cap)), textcoords="offset points", xytext=(6, -18),
                        fontsize=7)
    if len(finite) < len(configs):
        ax.axhline(cap, color="grey", ls=":", lw=0.8)
        ax.text(ax.get_xlim()[0], cap, " exact (PSNR = inf)", va="bottom", fontsize=8, color="grey")
    ax.set_xscale("log")
    ax.set_xlabel("frame time (ms, median over rounds; bars: its 95% interval) - log scale")
    ax.set_ylabel("PSNR vs exact energy-sum scatter (dB, higher is better)")
    ax.grid(True, which="both", alpha=0.3)

    methods = [m for m in COLOURS if any(c["method"] == m for c in configs)]
    precisions = [p for p in MARKERS if any(c["precision"] == p for c in configs)]
    handles = [Line2D([], [], color=COLOURS[m], marker="o", ls="none", label=m) for m in methods]
    handles += [Line2D([], [], color="grey", marker=MARKERS[p], ls="none", label=p) for p in precisions]
    handles += [Line2D([], [], color="grey", marker="o", mfc="none", ls="none", ms=SIZE.get(s, 5),
                       label=f"intermediates at 1/{s} resolution")
                for s in sorted({c["buffer_scale"] for c in configs} - {1})]
    for aperture, style in styles.items():
        handles.append(Line2D([], [], color="black", alpha=0.6, ls=style,
                              label="Pareto front" + (f" ({aperture})" if len(apertures) > 1 else "")))
    ax.legend(handles=handles, fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0), title="colour / marker")
    ax.set_title(f"Speed vs accuracy: {cfg['scene']} {cfg['width_px']}x{cfg['height_px']}, max CoC {cfg['max_coc_px']} px, "
                 f"patterns {' '.join(cfg['patterns'])}"
                 + (f", {unplaced} with non-finite output not shown" if unplaced else "")
                 + f"\n{bokehplot.context_line(doc)}", fontsize=9)
    bokehplot.save(fig, prefix)
    plot_roofline.roofline_figure(doc, prefix + "_roofline")


if __name__ == "__main__":
    bokehplot.run(main, __doc__)
