#!/usr/bin/python3
"""Plot results/circular_kernels.json: radial profiles of the 1..6-component circular separable
kernels (Niemitalo 2010, Garcia 2018) against the ideal disc.

usage: plot_circular_kernels.py CIRCULAR_KERNELS_JSON OUT_PREFIX   (writes OUT_PREFIX.png and OUT_PREFIX.svg)

Left: the profiles K(r) over r / disc radius, with the ideal unit disc and the transition band
(u in (1, 1.2), i.e. r / disc radius in (0.909, 1.091)) shaded. Right: |K - ideal| on a log scale
outside the transition band, where the equiripple fit's max error is the published figure
(dotted line per component count). The legend gives measured vs published max ripple.
"""

import bokehplot
import matplotlib.pyplot as plt

COLOURS = ["#2ca02c", "#9467bd", "#8c564b", "#e377c2", "#7f7f7f", "#bcbd22"]  # as plot_figure9.py's circularN


def main(doc, prefix):
    cfg = doc["config"]
    edge = cfg["disc_edge_u"]
    pass_end, stop_start = cfg["passband_end_u"] / edge, cfg["stopband_start_u"] / edge
    fig, (ax, ax_err) = plt.subplots(1, 2, figsize=(13, 5.2), constrained_layout=True)

    r_ideal = [0.0, 1.0, 1.0, max(k["profile"]["r_over_disc_radius"][-1] for k in doc["kernels"])]
    ax.plot(r_ideal, [1.0, 1.0, 0.0, 0.0], color="black", lw=1.2, ls="--", label="ideal disc (height 1)")
    for a in (ax, ax_err):
        a.axvspan(pass_end, stop_start, color="#000000", alpha=0.07, lw=0)
    ax.text(stop_start + 0.02, 1.22, "shaded: transition band\nu in (1, 1.2)", ha="left", va="top", fontsize=8)

    for k, colour in zip(doc["kernels"], COLOURS):
        n = k["components"]
        r, v = k["profile"]["r_over_disc_radius"], k["profile"]["K"]
        worst = max(k["max_ripple_passband"], k["max_ripple_stopband"])
        ax.plot(r, v, color=colour, lw=1.4,
                label=f"{n} component{'s' if n > 1 else ''}: ripple {worst:.4f} (published {k['published_max_ripple']:.4g})")
        err_r, err = [], []
        for ri, vi in zip(r, v):
            if pass_end < ri < stop_start:
                err_r.append(ri), err.append(float("nan"))  # break the line over the transition band
            else:
                err_r.append(ri), err.append(max(abs(vi - (1.0 if ri <= pass_end else 0.0)), 1e-6))
        ax_err.plot(err_r, err, color=colour, lw=1.1, label=f"{n} comp.")
        ax_err.axhline(k["published_max_ripple"], color=colour, lw=0.9, ls=":")

    ax.set_xlabel("radius r / disc radius (disc edge at u = 1.1)")
    ax.set_ylabel("kernel value K(r) (ideal disc = 1 inside, 0 outside)")
    ax.set_title("Radial profile of the circular separable kernels")
    ax.set_ylim(-0.3, 1.3)
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8, loc="lower left", title="measured max |K - ideal| outside the transition band",
              title_fontsize=8)

    ax_err.set_yscale("log")
    ax_err.set_ylim(1e-4, 1.0)
    ax_err.set_xlabel("radius r / disc radius")
    ax_err.set_ylabel("|K(r) - ideal disc| (log; dotted: published max ripple)")
    ax_err.set_title("Ripple outside the transition band (equiripple fit)")
    ax_err.grid(True, which="both", alpha=0.3)
    ax_err.legend(fontsize=8, loc="lower right", ncol=2)

    costs = "; ".join(
        f"{k['components']}: {k['kernel_radius_px']} / {k['taps_per_pixel']}"
        for k in doc["kernels"])
    fig.suptitle(
        f"Circular separable DoF kernels (Niemitalo 2010 / Garcia 2018), {bokehplot.context_line(doc)}\n"
        f"at disc radius {cfg['disc_radius_px']:g} px, components: kernel radius R (px) / taps per pixel and channel, "
        f"both passes:  {costs}",
        fontsize=9)
    bokehplot.save(fig, prefix)


if __name__ == "__main__":
    bokehplot.run(main, __doc__)
