#!/usr/bin/python3
"""Checks on a command's results file beyond its JSON schema: what the schema cannot say.

usage: check_results.py gbench|adaptive|injected|intervals|figure9|roofline FILE
"""
import json
import math
import statistics
import sys


def gbench(d):
    """Google Benchmark's JSON: names stable across runs (compare.py matches them)."""
    b = d["benchmarks"]
    assert b and d["context"]["library_build_type"]
    unstable = [x["name"] for x in b if "iterations:" in x["name"] or "repetitions:" in x["name"]]
    assert not unstable, f"names must be stable across runs for compare.py: {unstable}"
    print(len(b), "gbench entries")


def adaptive(d):
    """Every method that declares `adaptive` is compared, off against on, and the modes keep their promises."""
    declared = {m["name"] for m in d["methods"] if any(o["key"] == "adaptive" for o in m["options"])}
    compared = {c["method"] for c in d["comparisons"]}
    assert {"naive", "flag"} <= declared == compared, (declared, compared)
    assert len(d["comparisons"]) == len(d["points"]) // 2, "every on point has its off twin"
    for c in d["comparisons"]:
        assert c["speedup"] > 0
        if c["method"] == "naive":
            assert c["error_on"] == c["error_off"], c
        if c["method"] == "flag":
            assert c["memory_saved_fraction"] > 0, c
            assert c["scene_stats"]["layers"] < c["scene_stats"]["layers_worst_case"], c
    print(len(d["comparisons"]), "comparisons of", sorted(compared))


def injected(d):
    """--inject-slowdown-pct 25 is recorded, and every sample's frames are a multiple of 4 (25% is whole frames)."""
    assert d["config"]["injected_slowdown_pct"] == 25, d["config"]
    assert d["measurement"]["extra_work_fraction"] == 0.25
    frames = [p["frames_per_sample"] for p in d["points"]]
    assert frames and all(x % 4 == 0 for x in frames), frames
    print("frames per sample", frames)


def median_interval(values):
    """The median and its distribution-free 95% interval, computed here from the binomial directly: the
    order statistics x(k), x(n + 1 - k), k the largest with P(Binomial(n, 1/2) < k) <= 2.5% (k >= 1)."""
    x, n = sorted(values), len(values)
    below = lambda k: sum(math.comb(n, j) for j in range(k)) / 2 ** n  # P(B < k)
    k = max([1] + [k for k in range(1, n // 2 + 1) if below(k) <= 0.025])
    median = (x[(n - 1) // 2] + x[n // 2]) / 2
    return median, x[k - 1], x[n - k]


def close(a, b, relative=1e-9):
    return abs(a - b) <= relative * max(1.0, abs(b))


# Figures widened by Student's t: the table's 6 decimals against the C++ quantile's numerical integration.
T_TABLE_CLOSE = 1e-6


def intervals(d):
    """Every point's frame_ms_interval (and each pass's pass_ms_interval) is the median of its samples with
    the order-statistic interval, (buffers) every streamed/full ratio is the median of the same-round ratios
    with theirs, and the run's measurement.noise follows from them."""
    for p in d["points"]:
        got, want = p["frame_ms_interval"], median_interval(p["samples_ms"])
        assert all(close(g, w) for g, w in zip((got["estimate"], got["low"], got["high"]), want)), (p["id"], got, want)
        assert got["low"] <= got["estimate"] <= got["high"], p["id"]
        assert set(p["pass_ms_interval"]) == set(p.get("samples_pass_ms", {})), p["id"]
        for name, samples in p.get("samples_pass_ms", {}).items():
            got = p["pass_ms_interval"][name]
            want = median_interval(samples)
            assert all(close(g, w) for g, w in zip((got["estimate"], got["low"], got["high"]), want)), (p["id"], name)
    by_id = {p["id"]: p for p in d["points"]}
    ratios = 0
    for p in d["points"]:
        r = p.get("streamed_vs_full")
        if not r:
            continue
        base = p["id"].split("/layer_buffer:")[0]
        full = by_id.get(base + "/layer_buffer:\"full\"") or by_id[base]  # the 3D buffer, named since auto
        full_ms = dict(zip(full["sample_rounds"], full["samples_ms"]))
        same_round = [ms / full_ms[r_] for r_, ms in zip(p["sample_rounds"], p["samples_ms"]) if r_ in full_ms]
        want = median_interval(same_round)
        got = (r["frame_ms_ratio_median"], r["low"], r["high"])
        assert all(close(g, w) for g, w in zip(got, want)) and r["rounds"] == len(same_round), (p["id"], got, want)
        ratios += 1
    if "shards" in d:  # written by merge: the noise is a run's, and each shard's run is its own
        print(len(d["points"]), "points' median intervals and", ratios, "streamed/full ratio intervals check (merged)")
        return
    # The run's noise: the median point's relative half-width, the widest, and the verdict.
    widths = sorted((p["frame_ms_interval"]["high"] - p["frame_ms_interval"]["low"]) / 2 / p["frame_ms_interval"]["estimate"]
                    for p in d["points"])
    noise = d["measurement"]["noise"]
    median = (widths[(len(widths) - 1) // 2] + widths[len(widths) // 2]) / 2
    assert close(noise["median_relative_half_width"], median) and close(noise["widest"]["relative_half_width"], widths[-1]), noise
    assert noise["noisy"] == (median > noise["noisy_above"]), noise
    assert noise["probe_drift"] == {k: v["drift"] for k, v in d["measurement"]["probes"].items()}, noise
    print(len(d["points"]), "points' median intervals,", ratios, "streamed/full ratio intervals and the run's noise "
          f"(+-{100 * median:.1f}%, {'noisy' if noise['noisy'] else 'not noisy'}) check")


# Student's t distribution, 97.5% quantile by degrees of freedom (published tables).
STUDENT_T_975 = {1: 12.706205, 2: 4.302653, 3: 3.182446, 4: 2.776445, 5: 2.570582, 6: 2.446912, 7: 2.364624,
                 8: 2.306004, 9: 2.262157, 10: 2.228139, 11: 2.200985, 12: 2.178813, 13: 2.160369, 14: 2.144787,
                 15: 2.131450, 16: 2.119905, 17: 2.109816, 18: 2.100922, 19: 2.093024, 20: 2.085963}


def student_t_975(dof):
    """The published table, and past it the expansion of t in 1/dof about the normal quantile (Abramowitz &
    Stegun 26.7.5; within 1e-6 from 20 degrees of freedom on)."""
    if dof in STUDENT_T_975:
        return STUDENT_T_975[dof]
    z, v = 1.959964, float(dof)
    return (z + (z ** 3 + z) / (4 * v) + (5 * z ** 5 + 16 * z ** 3 + 3 * z) / (96 * v ** 2)
            + (3 * z ** 7 + 19 * z ** 5 + 17 * z ** 3 - 15 * z) / (384 * v ** 3)
            + (79 * z ** 9 + 776 * z ** 7 + 1482 * z ** 5 - 1920 * z ** 3 - 945 * z) / (92160 * v ** 4))


def exponent_interval(curve, rounds):
    """A curve's larger-half growth exponent: the least-squares slope of log t on log N fitted to each round that
    holds every point of the larger half, the median of those with its interval. curve: [(N, {round: ms})]."""
    curve = sorted(curve)[len(curve) // 2:]
    xs = [math.log(n) for n, _ in curve]
    mx = sum(xs) / len(xs)
    slopes = []
    for r in curve[0][1]:
        ys = [v.get(r, 0) for _, v in curve]
        if r in rounds and all(y > 0 for y in ys):
            ly = [math.log(y) for y in ys]
            my = sum(ly) / len(ly)
            slopes.append(sum((x - mx) * (y - my) for x, y in zip(xs, ly)) / sum((x - mx) ** 2 for x in xs))
    return median_interval(slopes) if slopes else None


def figure_variant(d):
    """p -> the curve figure9 draws point p on: its options off their defaults (its variant), and its precision
    where the run holds several of its method's, but for the plain curve's (the series whose variant names no
    precision: the method's default, or the first of its list the run holds; figure9.cpp, figure_variant)."""
    held = {}
    for p in d["points"]:
        held.setdefault(p["method"], set()).add(p["precision"])
    plain = {s["method"]: s.get("precision") for s in d["series"] if "/precision:" not in s.get("variant", "")}

    def variant(p):
        several = len(held[p["method"]]) > 1 and p["precision"] != plain.get(p["method"])
        return p.get("variant", "") + ("/precision:" + p["precision"] if several else "")
    return variant


def headline_figures(d, lead, rounds):
    """The run's headline figures from `rounds` alone, by name: naive/FLAG at each N and backend (a ratio, judged in
    logs) and each curve's larger-half exponent: {name: (backend, is_ratio, (estimate, low, high))}."""
    software = (d["context"].get("device") or {}).get("type", "cpu") == "cpu"
    field = lambda backend: "samples_cpu_ms" if lead and (backend == "cpu" or software) else "samples_ms"
    by_round = lambda p: {r: ms for r, ms in zip(p["sample_rounds"], p[field(p["backend"])]) if r in rounds}
    out, curves, variant = {}, {}, figure_variant(d)
    for p in d["points"]:
        curves.setdefault((p["method"], variant(p), p["backend"]), []).append((p["N"], by_round(p)))
    for (method, variant, backend), curve in curves.items():
        if len(curve) - len(curve) // 2 >= 2 and (e := exponent_interval(curve, rounds)):
            out[f"{method}{variant} {backend} larger_half"] = (backend, False, e)
    for (method, variant, backend), curve in curves.items():
        if method != "naive" or variant:
            continue
        flag = dict(curves.get(("flag", "", backend), []))
        for n, a in curve:
            paired = [ms / flag[n][r] for r, ms in a.items() if r in flag.get(n, {})]
            if paired:
                out[f"naive/FLAG {backend} N={n}"] = (backend, True, median_interval(paired))
    return out


def baseline_figures(d, lead, rounds):
    """FLAG (default options, GPU) over each CPU baseline at its N from `rounds` alone, both sides in the GPU
    points' time (figure9 --cpu-baseline): {name: ("gpu", True, (estimate, low, high))}. Widened by a run's
    processes like the headlines, but not pooled into their spread."""
    software = (d["context"].get("device") or {}).get("type", "cpu") == "cpu"
    field = "samples_cpu_ms" if lead and software else "samples_ms"
    by_round = lambda p: {r: ms for r, ms in zip(p["sample_rounds"], p[field]) if r in rounds}
    variant = figure_variant(d)
    flag = {p["N"]: by_round(p) for p in d["points"] if p["method"] == "flag" and not variant(p) and p["backend"] == "gpu"}
    out = {}
    for b in d.get("baselines", []):
        base = by_round(b)
        paired = [ms / base[r] for r, ms in flag.get(b["N"], {}).items() if r in base]
        if paired:
            out[f"FLAG/{b['baseline']} gpu N={b['N']}"] = ("gpu", True, median_interval(paired))
    return out


def widened_by_processes(d, lead):
    """A run of several processes (measurement.round_process): each headline figure's interval recomputed from
    the samples as derive_figure9 widens it. Per process, each figure from its rounds alone, with its standard
    error (half-width / 1.96; ratios in logs); per backend, the processes' spread against those errors pooled
    over its figures (lambda^2 = sum of (n - 1) s^2 / mean variance over sum of (n - 1)); each side of the whole
    run's interval at least t * lambda * sqrt(mean variance / n). {name: (estimate, low, high)} and
    {backend: (lambda, degrees of freedom)}; both empty for one process."""
    owner = d["measurement"].get("round_process")
    if not owner or max(owner) == 0:
        return {}, {}
    processes = max(owner) + 1
    every_round = set(range(len(owner)))
    whole = headline_figures(d, lead, every_round)
    widened = {**whole, **baseline_figures(d, lead, every_round)}
    parts = [{**headline_figures(d, lead, rounds), **baseline_figures(d, lead, rounds)}
             for rounds in ({r for r, k in enumerate(owner) if k == p} for p in range(processes))]
    scale = lambda ratio, x: math.log(x) if ratio else x
    pooled, stats = {}, {}
    for name, (backend, ratio, _) in widened.items():
        estimates, variances = [], []
        for part in parts:
            if name in part:
                est, low, high = part[name][2]
                se = (scale(ratio, high) - scale(ratio, low)) / (2 * 1.96)
                if se > 0:
                    estimates.append(scale(ratio, est))
                    variances.append(se * se)
        if len(estimates) < 2:
            continue
        n, mean_variance = len(estimates), sum(variances) / len(variances)
        mean = sum(estimates) / n
        if name in whole:  # the headlines alone make the spread
            z2, dof = pooled.get(backend, (0.0, 0))
            pooled[backend] = (z2 + sum((x - mean) ** 2 for x in estimates) / mean_variance, dof + n - 1)
        stats[name] = (n, mean_variance)
    out = {}
    for name, (backend, ratio, (est, low, high)) in widened.items():
        if name not in stats or backend not in pooled:
            continue
        z2, dof = pooled[backend]
        n, mean_variance = stats[name]
        half_width = student_t_975(dof) * math.sqrt(z2 / dof) * math.sqrt(mean_variance / n)
        back = math.exp if ratio else (lambda x: x)
        out[name] = (est, min(low, back(scale(ratio, est) - half_width)), max(high, back(scale(ratio, est) + half_width)))
    return out, {backend: (math.sqrt(z2 / dof), dof) for backend, (z2, dof) in pooled.items()}


def figure9(d):
    """Each backend's figures are in the time the CPU's share of the work calls for (process CPU time for the CPU
    references and on a CPU device such as lavapipe, else wall-clock; headlines.wall_time always wall-clock), and
    each naive/FLAG ratio and curve median is recomputed here from the points' samples in that time: the median of
    the ratios within each round with its order-statistic interval, and the repeat-run interval sqrt(2) wider (or
    by the spread of the machine's earlier runs, measurement.run_to_run, where that is wider)."""
    software = (d["context"].get("device") or {}).get("type", "cpu") == "cpu"
    field = {"process CPU time": "samples_cpu_ms", "wall-clock time": "samples_ms"}
    variant = figure_variant(d)
    points = {(p["method"], p["backend"], p["N"]): p for p in d["points"] if not variant(p)}
    spread = d["measurement"].get("run_to_run", {})
    checked = widened = between = 0
    for figures, lead in ((d, True), (d["headlines"]["wall_time"], False)):
        processes, spread_between = widened_by_processes(d, lead)
        if lead:  # the spread the run reports is the one its samples give
            reported = d["headlines"].get("between_processes", {}).get("backends", {})
            assert sorted(reported) == sorted(spread_between), (reported, spread_between)
            for backend, (ratio_of_spreads, dof) in spread_between.items():
                got = reported[backend]
                assert got["degrees_of_freedom"] == dof, (backend, got, dof)
                assert close(got["spread_over_rounds"], ratio_of_spreads, T_TABLE_CLOSE), (backend, got, ratio_of_spreads)
                assert abs(got["t"] - student_t_975(dof)) < 1e-5, (backend, got)
        for s in figures["series"]:  # a run of several processes: its exponents widened as derive_figure9 does
            name = f"{s['method']}{s.get('variant', '')} {s['backend']} larger_half"
            if name in processes:
                fit = s["fits"]["larger_half"]
                got = (fit["exponent"], fit["low"], fit["high"])
                assert all(close(g, w, T_TABLE_CLOSE) for g, w in zip(got, processes[name])), \
                    (name, fit, processes[name])
                between += 1
        for r in figures["naive_over_flag"]:
            want_time = "process CPU time" if lead and (r["backend"] == "cpu" or software) else "wall-clock time"
            assert r["time"] == want_time, (r, want_time)
            a, b = (points[(m, r["backend"], r["N"])] for m in ("naive", "flag"))
            b_ms = dict(zip(b["sample_rounds"], b[field[r["time"]]]))
            paired = [ms / b_ms[k] for k, ms in zip(a["sample_rounds"], a[field[r["time"]]]) if k in b_ms]
            est, low, high = processes.get(f"naive/FLAG {r['backend']} N={r['N']}", median_interval(paired))
            assert all(close(g, w, T_TABLE_CLOSE) for g, w in zip((r["naive_over_flag"], r["low"], r["high"]), (est, low, high))), (r, est)
            # The repeat-run interval: sqrt(2) wider, or sqrt(2) * t * the spread of this machine's earlier runs
            # of the same points where that is wider (measurement.run_to_run; ratios' spread is of their logs; t:
            # Student's 97.5% quantile for its degrees of freedom, from the published table).
            # A figure's own spread or its family's (pooled over its backend's ratios), whichever reaches wider.
            sd = t = 0
            name = f"naive_over_flag/{r['backend']}/N:{r['N']}" + ("/cpu_time" if r["time"] == "process CPU time" else "")
            spread_of = spread.get("figures", {}).get(name)
            candidates = [spread_of, spread.get("families", {}).get((spread_of or {}).get("family"))]
            usable = [c for c in candidates if lead and c and c["degrees_of_freedom"] >= spread["min_degrees_of_freedom"]]
            if usable:
                use = max(usable, key=lambda c: student_t_975(c["degrees_of_freedom"]) * c["sd"])
                sd = use["sd"] * est
                t = r["run_to_run_t"]
                assert abs(t - student_t_975(use["degrees_of_freedom"])) < 1e-5, r
                widened += 1
            assert close(r.get("run_to_run_sd", 0), sd), (r, sd)
            assert close(r["repeat_low"], est - math.sqrt(2) * max(est - low, t * sd), T_TABLE_CLOSE), r
            assert close(r["repeat_high"], est + math.sqrt(2) * max(high - est, t * sd), T_TABLE_CLOSE), r
            checked += 1
            between += f"naive/FLAG {r['backend']} N={r['N']}" in processes
        for s in figures["series"]:
            if s.get("variant"):
                continue
            for n, median in zip(s["N"], s["median_ms"]):
                p = points[(s["method"], s["backend"], int(n))]
                assert close(median, median_interval(p[field[s["time"]]])[0]), (s["method"], s["backend"], n)
    assert checked, "no naive/FLAG ratio to check"
    baselines = check_baselines(d, field, software)
    owner = d["measurement"].get("round_process", [0])
    assert (max(owner) > 0) == (between > 0), "a run of several processes widens its figures by their spread"
    print(checked, "naive/FLAG ratios (", widened, "repeat-run intervals by the spread of earlier runs,", between,
          "figures widened by the spread between", max(owner) + 1, "processes ) and the curves' "
          "medians check against the samples, in",
          sorted({s["time"] + " (" + s["backend"] + ")" for s in d["series"]}), "; CPU baselines:", baselines)


def check_baselines(d, field, software):
    """figure9 --cpu-baseline filter2d (the default): a baseline for every N of the GPU points, measured or skipped
    with its reason (a build without OpenCV); each FLAG (GPU) / baseline ratio recomputed from the samples of the
    same rounds in the GPU points' time (process CPU time on a CPU device such as lavapipe), widened by a run's
    processes as the headlines are, its repeat-run interval sqrt(2) wider; each baseline curve's medians from its
    samples."""
    if d["config"].get("cpu_baseline", "none") == "none":
        assert not d.get("baselines") and not d.get("flag_over_baseline"), "no baseline was asked for"
        return "none asked for"
    gpu_n = sorted({p["N"] for p in d["points"] if p["backend"] == "gpu"})
    measured = {b["N"]: b for b in d["baselines"]}
    skipped = {b["N"]: b for b in d["skipped_baselines"]}
    assert sorted(set(measured) | set(skipped)) == gpu_n, (sorted(measured), sorted(skipped), gpu_n)
    for b in skipped.values():
        assert b["reason"], b
    variant = figure_variant(d)
    flag_at = {p["N"]: p for p in d["points"] if p["method"] == "flag" and not variant(p) and p["backend"] == "gpu"}
    flag_n = set(flag_at)

    def cores_busy(p):  # process CPU time over wall-clock time, medians over the samples
        return statistics.median(p["samples_cpu_ms"]) / statistics.median(p["samples_ms"])

    checked = busy = 0
    for figures, lead in ((d, True), (d["headlines"]["wall_time"], False)):
        time = "process CPU time" if lead and software else "wall-clock time"
        processes, _ = widened_by_processes(d, lead)
        want = baseline_figures(d, lead, set(range(len(d["measurement"]["round_order"]))))
        ratios = {r["N"]: r for r in figures["flag_over_baseline"]}
        assert sorted(ratios) == sorted(flag_n & set(measured)), (sorted(ratios), flag_n, sorted(measured))
        for n, r in ratios.items():
            assert r["time"] == time and r["backend"] == "gpu", (r, time)
            name = f"FLAG/{r['baseline']} gpu N={n}"
            est, low, high = processes.get(name, want[name][2])
            got = (r["flag_over_baseline"], r["low"], r["high"])
            assert all(close(g, w, T_TABLE_CLOSE) for g, w in zip(got, (est, low, high))), (r, (est, low, high))
            assert close(r["repeat_low"], est - math.sqrt(2) * (est - low), T_TABLE_CLOSE), r
            assert close(r["repeat_high"], est + math.sqrt(2) * (high - est), T_TABLE_CLOSE), r
            if "flag_cores_busy" in r:  # absent in files from before 2026-12-06
                assert close(r["flag_cores_busy"], cores_busy(flag_at[n])), (r, cores_busy(flag_at[n]))
                assert close(r["baseline_cores_busy"], cores_busy(measured[n])), (r, cores_busy(measured[n]))
                busy += 1
            checked += 1
        for s in figures["baseline_series"]:
            assert s["time"] == time, (s, time)
            for n, median in zip(s["N"], s["median_ms"]):
                assert close(median, median_interval(measured[int(n)][field[time]])[0]), (s["baseline"], n)
    return f"{len(measured)} measured, {len(skipped)} skipped, {checked} FLAG/baseline ratios check against the " \
           f"samples ({busy} with cores busy)"


def roofline(d):
    """Each pass against the run's probes, recomputed from the point's median pass time, its declared work and the
    probes' own medians (measurement.probes: bytes or FLOPs over the median ms), not from the limits written."""
    probes = d["measurement"]["probes"]
    unfused = 0
    def limit(name, per):
        p = probes[name]
        return p[per] / (p["ms"]["median"] * 1e-3)
    checked = 0
    for p in d["points"]:
        b, passes = p["backend"], p["work"]["passes"]
        copy_bytes_per_s, fma_flops_per_s = limit(f"{b}_copy", "bytes"), limit(f"{b}_fma", "flops")
        for name, t in p["throughput"].items():
            works = list(passes.values()) if name == "frame" else [passes[name]]
            ms = p["frame_ms"]["median"] if name == "frame" else p["pass_ms"][name]
            taps = sum(w["taps"] for w in works)
            moved = sum(w["bytes_read"] + w["bytes_written"] for w in works)
            assert close(t["fraction_of_copy_bandwidth"], moved / (ms * 1e-3) / copy_bytes_per_s), (p["id"], name, t)
            assert close(t["fraction_of_fma_taps"], taps / (ms * 1e-3) / (fma_flops_per_s / 8)), (p["id"], name, t)
            assert moved == 0 or close(t["taps_per_byte"], taps / moved), (p["id"], name, t)
            kept = sum(w.get("bytes_kept", 0) for w in works)  # a fused pass's layers, counted as unfused
            assert ("fraction_of_copy_unfused" in t) == (kept > 0), (p["id"], name, t)
            if kept:
                assert close(t["fraction_of_copy_unfused"], (moved + kept) / (ms * 1e-3) / copy_bytes_per_s), (p["id"], name, t)
                unfused += 1
            checked += 1
    assert checked, "no pass with a throughput"
    print(checked, "passes' roofline fractions check against their work, times and the probes,", unfused,
          "counted as unfused too")


if __name__ == "__main__":
    checks = {"gbench": gbench, "adaptive": adaptive, "injected": injected, "intervals": intervals, "figure9": figure9,
              "roofline": roofline}
    if len(sys.argv) != 3 or sys.argv[1] not in checks:
        sys.exit(__doc__)
    with open(sys.argv[2]) as f:
        checks[sys.argv[1]](json.load(f))
