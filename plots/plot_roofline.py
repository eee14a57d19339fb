#!/usr/bin/python3
"""Roofline of a sweep's passes (figure9, tradeoff): each pass's taps a second against its taps per byte
moved (the work its method declares), with the ceilings of the probes measured in the same run.

usage: plot_roofline.py RESULTS_JSON OUT_PREFIX   (writes OUT_PREFIX.png and OUT_PREFIX.svg);
plot_figure9.py and plot_tradeoff.py draw it as <prefix>_roofline.

One panel per backend (its own probes). The slanted line is the copy probe's bandwidth (taps/s = GB/s x
taps/byte), the flat one the FMA probe's rate at one vec4 multiply-add (8 FLOPs) a tap. The copy probe reads
and writes; a pass that mostly reads can pass its line where stores cost more than loads (lavapipe stores
lane by lane: tile_max, which reads a frame and writes a few bytes, reaches 100-110% there). Each pass is one
colour and marker, one point per N joined in N's order (the largest N labelled); the pass furthest below its nearer ceiling, listed first in the legend, is where time is lost.
CPU references are timed whole ("frame"). A fused pass (FLAG's layers kept in registers) is drawn again in
hollow markers at the taps per byte of the unfused passes' bytes (its layers written and read): its speed
against the copy probe counted as the work of the passes it replaces.
"""
import bokehplot
import matplotlib.pyplot as plt

TAP_FLOPS = 8  # bench/runner/roofline.hpp: kTapFlops


def passes_of(doc, backend):
    """{(method variant precision, pass): [(N, taps_per_byte, taps_per_s, fraction of the nearer ceiling,
    (taps per unfused byte, fraction_of_copy_unfused) or None)]}."""
    out = {}
    for p in doc["points"]:
        if p["backend"] != backend:
            continue
        scale = p.get("buffer_scale", 1)
        what = f"{p['method']}{p.get('variant', '')} {p.get('precision', '')}" + (f" 1/{scale}" if scale > 1 else "")
        for name, t in p.get("throughput", {}).items():
            if t.get("taps_per_byte") and t.get("taps_per_s"):
                nearer = max(t.get("fraction_of_copy_bandwidth", 0), t.get("fraction_of_fma_taps", 0))
                unfused = ((t["taps_per_s"] / (t["unfused_gb_per_s"] * 1e9), t.get("fraction_of_copy_unfused", 0))
                           if "unfused_gb_per_s" in t else None)
                out.setdefault((what, name), []).append((p["N"], t["taps_per_byte"], t["taps_per_s"], nearer, unfused))
    return {k: sorted(v) for k, v in out.items()}


def panel(ax, doc, backend):
    limits = doc["measurement"].get("limits", {})
    series = passes_of(doc, backend)
    order = sorted(series, key=lambda k: max(v[3] for v in series[k]))
    markers = bokehplot.markers_for([f"{w} {p}" for w, p in order])
    colours = plt.get_cmap("tab20")
    xs = [x for s in series.values() for v in s for x in (v[1], v[4] and v[4][0]) if x]
    x_lo, x_hi = min(xs) / 3, max(xs) * 3
    copy_gbps, fma_gflops = limits.get(f"{backend}_copy_gb_per_s"), limits.get(f"{backend}_fma_gflop_per_s")
    if copy_gbps:
        ax.plot([x_lo, x_hi], [copy_gbps * 1e9 * x_lo, copy_gbps * 1e9 * x_hi], color="k", lw=1.5,
                label=f"copy probe {copy_gbps:.2f} GB/s")
    if fma_gflops:
        ax.axhline(fma_gflops * 1e9 / TAP_FLOPS, color="k", ls="--", lw=1.5,
                   label=f"FMA probe {fma_gflops:.0f} GFLOP/s = {fma_gflops / TAP_FLOPS:.1f} G taps/s")
    for i, key in enumerate(order):
        pts = series[key]
        label = f"{key[0]} {key[1]} ({100 * max(v[3] for v in pts):.0f}% of a ceiling at best)"
        ax.plot([v[1] for v in pts], [v[2] for v in pts], marker=markers[f"{key[0]} {key[1]}"], ms=5, lw=0.8,
                color=colours(i % 20), label=label)
        unfused = [(v[4][0], v[2], v[4][1]) for v in pts if v[4]]
        if unfused:
            ax.plot([u[0] for u in unfused], [u[1] for u in unfused], marker=markers[f"{key[0]} {key[1]}"], ms=5,
                    lw=0.8, ls=":", mfc="none", color=colours(i % 20),
                    label=f"{key[0]} {key[1]} counted as the unfused passes' bytes "
                          f"({100 * max(u[2] for u in unfused):.0f}% of copy at best)")
        n, x, y = pts[-1][:3]
        ax.annotate(f"N={n}", (x, y), fontsize=6, xytext=(3, 2), textcoords="offset points", color=colours(i % 20))
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlim(x_lo, x_hi)
    ys = [v[2] for s in series.values() for v in s] + ([fma_gflops * 1e9 / TAP_FLOPS] if fma_gflops else [])
    ax.set_ylim(min(ys) / 3, max(ys) * 3)  # the points and the flat ceiling; the slanted one leaves the panel
    ax.set_xlabel("taps per byte moved (declared work)")
    ax.set_ylabel("taps a second")
    ax.set_title(f"{backend}: each pass against this run's probes (furthest from a ceiling first in the legend)",
                 fontsize=9)
    ax.grid(True, which="both", alpha=0.25)
    ax.legend(fontsize=6, loc="upper left", bbox_to_anchor=(1.01, 1), borderaxespad=0)


def roofline_figure(doc, prefix):
    backends = [b for b in ("gpu", "cpu") if passes_of(doc, b)]
    if not backends:
        return
    fig, axes = plt.subplots(1, len(backends), figsize=(9.5 * len(backends), 6.5), constrained_layout=True,
                             squeeze=False)
    for ax, backend in zip(axes[0], backends):
        panel(ax, doc, backend)
    fig.suptitle(f"Roofline per pass, {doc['schema'].removeprefix('bokehbench.')}\n{bokehplot.context_line(doc)}",
                 fontsize=9)
    bokehplot.save(fig, prefix)


if __name__ == "__main__":
    bokehplot.run(roofline_figure, __doc__)
