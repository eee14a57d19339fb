#!/usr/bin/python3
"""Plot results/tradeoff.json: frame time against accuracy, with the Pareto front.

usage: plot_tradeoff.py TRADEOFF_JSON OUT_PREFIX   (writes OUT_PREFIX.png and OUT_PREFIX.svg)

x: median frame time (log scale; bars span the interquartile range). y: PSNR against the exact
energy-sum scatter (higher is better). The staircase joins the Pareto front: for a time budget on
the x axis, the best accuracy any configuration offers. Exact results (PSNR infinite) sit on top.
"""

import bokehplot
import matplotlib.pyplot as plt

COLOURS = {"naive": "#d62728", "flag": "#1f77b4", "circular1": "#2ca02c", "circular2": "#9467bd",
           "circular3": "#8c564b", "circular4": "#e377c2", "circular5": "#7f7f7f", "circular6": "#bcbd22"}
MARKERS = {"f32": "o", "f16": "s", "bracketed10": "^", "r11g11b10f": "v", "unorm10_bracketed": "D",
           "unorm16_bracketed": "P"}


def psnr_of(c, cap):
    p = c["error"]["vs_energy_sum"]["psnr_db"]
    return cap if p is None else p


def main(doc, prefix):
    configs, cfg = doc["configurations"], doc["config"]
    finite = [c["error"]["vs_energy_sum"]["psnr_db"] for c in configs if c["error"]["vs_energy_sum"]["psnr_db"] is not None]
    cap = (max(finite) + 5) if finite else 60
    fig, ax = plt.subplots(figsize=(11, 6.5), constrained_layout=True)
    seen = set()
    for c in configs:
        t = c["frame_ms"]
        y = psnr_of(c, cap)
        key = (c["method"], c["precision"])
        ax.errorbar([t["median"]], [y], xerr=[[t["median"] - t["q1"]], [t["q3"] - t["median"]]],
                    color=COLOURS.get(c["method"], "k"), marker=MARKERS.get(c["precision"], "o"), ms=7, capsize=2,
                    ls="none", label=None if key in seen else f"{c['method']} ({c['precision']})")
        seen.add(key)
        ax.annotate(f"{c['N']}x{c['k']}" if c["method"] in ("naive", "flag") else "", (t["median"], y),
                    textcoords="offset points", xytext=(5, 4), fontsize=7)
    ids = {c["id"]: c for c in configs}
    front = [ids[i] for i in doc["pareto_front"] if i in ids]
    if front:
        xs, ys = [], []
        for c in front:
            if xs:
                xs.append(c["frame_ms"]["median"])
                ys.append(ys[-1])
            xs.append(c["frame_ms"]["median"])
            ys.append(psnr_of(c, cap))
        ax.plot(xs, ys, color="black", lw=1.2, alpha=0.6, label="Pareto front")
        for c in front:
            ax.annotate(c["id"], (c["frame_ms"]["median"], psnr_of(c, cap)), textcoords="offset points",
                        xytext=(6, -10), fontsize=7, color="black")
    if len(finite) < len(configs):
        ax.axhline(cap, color="grey", ls=":", lw=0.8)
        ax.text(ax.get_xlim()[0], cap, " exact (PSNR = inf)", va="bottom", fontsize=8, color="grey")
    ax.set_xscale("log")
    ax.set_xlabel("frame time (ms, median over repetitions; bars: IQR) - log scale")
    ax.set_ylabel("PSNR vs exact energy-sum scatter (dB, higher is better)")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8, loc="lower right", ncol=2)
    ax.set_title(f"Speed vs accuracy: {cfg['scene']} {cfg['width_px']}x{cfg['height_px']}, max CoC {cfg['max_coc_px']} px\n"
                 f"{bokehplot.context_line(doc)}", fontsize=9)
    bokehplot.save(fig, prefix)


if __name__ == "__main__":
    bokehplot.run(main, __doc__)
