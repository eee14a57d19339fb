#!/usr/bin/python3
"""Plot results/adaptive.json: what each method's adaptive mode buys against its worst case, per scene.

usage: plot_adaptive.py ADAPTIVE_JSON OUT_PREFIX   (writes OUT_PREFIX.png and OUT_PREFIX.svg)

One group of bars per scene and largest CoC radius, one bar per method (colour: method, registry
order). Panels: speed-up (worst-case over adaptive frame time of the samples both took in the same
round, so the machine's drift cancels: median, bars its 95% interval; 1 = no gain); memory
each mode allocated for the scene (log scale: methods differ by orders of magnitude; hatched =
adaptive); PSNR of each mode against the exact energy-sum scatter (hatched = adaptive).
"""

import bokehplot
import matplotlib.pyplot as plt
from matplotlib.patches import Patch

WIDTH = 0.8


def group_label(c):
    return f"{c['scene']}\nmax CoC {c['max_coc_px']:g} px"


def main(doc, prefix):
    comps = doc["comparisons"]
    colours = bokehplot.method_colours(doc)
    methods = [m for m in colours if any(c["method"] == m for c in comps)]
    groups = []
    for c in comps:
        if group_label(c) not in groups:
            groups.append(group_label(c))
    by_key = {(group_label(c), c["method"]): c for c in comps}
    fig, axes = plt.subplots(3, 1, figsize=(max(12, 1.2 * len(groups) * max(1, len(methods)) + 3), 11),
                             constrained_layout=True)
    ax_speed, ax_mem, ax_err = axes
    bar = WIDTH / max(1, len(methods))

    def x_of(g, m, half=0):
        return groups.index(g) + (methods.index(m) - (len(methods) - 1) / 2) * bar + half * bar / 4

    for (g, m), c in by_key.items():
        colour = colours[m]
        paired = c.get("speedup_same_round")
        speedup = paired["median"] if paired else c["speedup"]
        yerr = [[speedup - paired["low"]], [paired["high"] - speedup]] if paired else None
        ax_speed.bar(x_of(g, m), speedup, bar * 0.9, color=colour, yerr=yerr, capsize=3)
        ax_speed.annotate(f"{speedup:.2f}x\n{c['frame_ms_off']:.3g} -> {c['frame_ms_on']:.3g} ms",
                          (x_of(g, m), paired["high"] if paired else speedup), ha="center", va="bottom", fontsize=7)
        for half, key, hatch in ((-1, "allocated_bytes_off", None), (1, "allocated_bytes_on", "//")):
            if c[key] > 0:  # a log axis has no 0: say it instead
                ax_mem.bar(x_of(g, m, half), c[key] / 2**20, bar * 0.45, color=colour, hatch=hatch, edgecolor="black",
                           lw=0.3)
            else:
                ax_mem.annotate("0 B", (x_of(g, m, half), 0), xycoords=("data", "axes fraction"), ha="center",
                                va="bottom", fontsize=7, color=colour)
        saved = c["memory_saved_fraction"]
        if saved is not None:
            text = (f"saved {100 * saved:.0f}%" if c["memory_saved_bytes"] >= 0
                    else f"+{-c['memory_saved_bytes'] / 1024:.0f} KiB")  # the mode's own map, nothing saved
            ax_mem.annotate(text, (x_of(g, m), c["allocated_bytes_off"] / 2**20), ha="center", va="bottom", fontsize=7)
        for half, key, hatch in ((-1, "error_off", None), (1, "error_on", "//")):
            p = c[key]["psnr_db"]
            if p is not None:
                ax_err.bar(x_of(g, m, half), p, bar * 0.45, color=colour, hatch=hatch, edgecolor="black", lw=0.3)
    ax_speed.axhline(1.0, color="grey", lw=0.8, ls=":")
    tops = [(c["speedup_same_round"] or {}).get("high", c["speedup"]) for c in comps]
    ax_speed.set_ylim(0, max(tops + [1.0]) * 1.25)
    ax_speed.set_ylabel("speed-up (worst case / adaptive,\npaired per round: median, 95% interval)")
    ax_mem.set_yscale("log")
    ax_mem.set_ylabel("allocated for the scene (MiB, log)")
    ax_err.set_ylabel("PSNR vs exact scatter (dB)")
    finite = [c[k]["psnr_db"] for c in comps for k in ("error_off", "error_on") if c[k]["psnr_db"] is not None]
    if finite:
        ax_err.set_ylim(max(0, min(finite) - 5), max(finite) + 3)
    for ax in axes:
        ax.set_xticks(range(len(groups)))
        ax.set_xticklabels(groups, fontsize=8)
        ax.grid(True, axis="y", which="both", alpha=0.3)
    handles = [Patch(color=colours[m], label=m) for m in methods]
    handles += [Patch(facecolor="white", edgecolor="black", label="worst case (adaptive = off)"),
                Patch(facecolor="white", edgecolor="black", hatch="//", label="adaptive = on")]
    ax_speed.legend(handles=handles, fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    cfg = doc["config"]
    ax_speed.set_title(f"Adaptive vs worst case: {cfg['width_px']}x{cfg['height_px']}, pattern {cfg['pattern']}, "
                       f"GPU\n{bokehplot.context_line(doc)}", fontsize=9)
    bokehplot.save(fig, prefix)


if __name__ == "__main__":
    bokehplot.run(main, __doc__)
