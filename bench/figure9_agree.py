#!/usr/bin/python3
"""Do two figure9 runs agree? Each headline figure of A against B: exponents (larger half of N) within
0.1, naive/FLAG ratios within 10%, and each run's repeat-run interval covering the other's estimate.

A repeat-run interval (repeat_low/high) is where a repeat run on the same machine would put its
estimate, at 95%. The plain 95% interval (low/high) covers another run's estimate only about 83% of
the time even when it is calibrated (so ~3 of 18 figures miss by chance); its coverage is shown too.
Repeat-run intervals that hold still miss about 1 figure in 20, so two runs agree on all 18 only about
40% of the time: the last line says how often calibrated intervals would cover as few as these did.
Results written before repeat intervals existed are held to their plain intervals.
The runs' calibration probes are compared too: a probe more than 1.3x apart (figure9's own rule for an
unusual machine state) means the machine was in another state, and the figures can differ by more than
any interval drawn from one run (the CPU references' ratios follow the memory rate).

usage: bench/figure9_agree.py A.json B.json   (exit 0 when every figure agrees, 1 otherwise)
"""
import json
import math
import sys

REPEAT_COVERAGE = 0.95
PROBES = {"cpu_copy_gb_per_s": "CPU copy", "cpu_fma_gflop_per_s": "CPU FMA", "gpu_copy_gb_per_s": "GPU copy",
          "gpu_fma_gflop_per_s": "GPU FMA"}
UNUSUAL_RATIO = 1.3  # for results written before measurement.machine_state carried its unusual_ratio


def in_time(figure):
    """A figure in process CPU time is named so (figure9 takes lavapipe's and the CPU references' figures in it);
    one in wall-clock time, or from a run before figures had a time, is not: the two are different figures."""
    return " (CPU time)" if figure.get("time") == "process CPU time" else ""


def headlines(doc):
    out = {}
    for s in doc["series"]:
        fit = s["fits"].get("larger_half")
        if fit:
            out[f"exponent {s['method']} {s['backend']}{in_time(s)}"] = (fit["exponent"], fit, "abs", 0.1)
    for r in doc["naive_over_flag"]:
        out[f"naive/FLAG {r['backend']} N={r['N']}{in_time(r)}"] = (r["naive_over_flag"], r, "rel", 0.10)
    return out


def repeat(interval):
    """(low, high) of the repeat-run interval, or of the plain one in results without it."""
    return interval.get("repeat_low", interval["low"]), interval.get("repeat_high", interval["high"])


def at_most(k, n, p=REPEAT_COVERAGE):
    """P(X <= k) for X ~ Binomial(n, p)."""
    return sum(math.comb(n, i) * p ** i * (1 - p) ** (n - i) for i in range(k + 1))


def machine_states(doc_a, doc_b):
    """A line comparing the two runs' calibration probes (each probe's median rate over its run's rounds)."""
    rates_a, rates_b = (d.get("measurement", {}).get("limits", {}) for d in (doc_a, doc_b))
    unusual = max(d.get("measurement", {}).get("machine_state", {}).get("unusual_ratio", UNUSUAL_RATIO)
                  for d in (doc_a, doc_b))
    shown, apart = [], []
    for key, name in PROBES.items():
        if key in rates_a and key in rates_b:
            ratio = rates_a[key] / rates_b[key]
            shown.append(f"{name} {rates_a[key]:.1f} vs {rates_b[key]:.1f} ({ratio:.2f}x)")
            if max(ratio, 1 / ratio) > unusual:
                apart.append(name)
    if not shown:
        return "machine state: the runs carry no calibration probes"
    verdict = (f"ANOTHER MACHINE STATE ({', '.join(apart)} more than {unusual}x apart): figures can differ by "
               "more than their intervals" if apart else f"every probe within {unusual}x")
    return f"machine state, A vs B: {'; '.join(shown)}; {verdict}"


def main(a_path, b_path):
    doc_a, doc_b = (json.load(open(p)) for p in (a_path, b_path))
    a, b = headlines(doc_a), headlines(doc_b)
    failures = plain_covered = repeat_covered = 0
    print(f"{'figure':<37} {'A [repeat run]':>22} {'B [repeat run]':>22} {'difference':>11}  covered  "
          f"95% covered  verdict")
    for key in sorted(set(a) & set(b)):
        (ea, ia, kind, limit), (eb, ib, _, _) = a[key], b[key]
        (la, ha), (lb, hb) = repeat(ia), repeat(ib)
        diff = abs(ea - eb) if kind == "abs" else abs(ea / eb - 1)
        covered = la <= eb <= ha and lb <= ea <= hb
        plain = ia["low"] <= eb <= ia["high"] and ib["low"] <= ea <= ib["high"]
        plain_covered += plain
        repeat_covered += covered
        ok = diff <= limit and covered
        failures += not ok
        shown = f"{diff:.3f}" if kind == "abs" else f"{100 * diff:.1f}%"
        print(f"{key:<37} {ea:>7.3f} [{la:.3f}, {ha:.3f}] {eb:>7.3f} [{lb:.3f}, {hb:.3f}] {shown:>11}  "
              f"{'both' if covered else 'no':<7}  {'both' if plain else 'no':<11}  {'agree' if ok else 'DIFFER'}")
    missing = set(a) ^ set(b)
    if missing:
        print("in one run only:", ", ".join(sorted(missing)))
    shared = len(set(a) & set(b))
    print(f"{shared - failures} of {shared} figures agree (exponents within 0.1, ratios within 10%, each repeat-run "
          f"interval covering the other's estimate); each plain 95% interval covers the other's estimate for "
          f"{plain_covered} of {shared} (about 83% expected by chance alone)")
    if shared:
        print(f"repeat-run intervals covered {repeat_covered} of {shared}; intervals that hold cover "
              f"{REPEAT_COVERAGE * shared:.1f} on average and {repeat_covered} or fewer for "
              f"{100 * at_most(repeat_covered, shared):.0f}% of pairs of runs (figures taken as independent)")
    print(machine_states(doc_a, doc_b))
    return 1 if failures or missing else 0


if __name__ == "__main__":
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    sys.exit(main(sys.argv[1], sys.argv[2]))
