#!/usr/bin/python3
"""Do two figure9 runs agree? Each headline figure of A against B: exponents (larger half of N) within
0.1, naive/FLAG ratios within 10%, and each run's 95% interval covering the other's estimate.

usage: bench/figure9_agree.py A.json B.json   (exit 0 when every figure agrees, 1 otherwise)
"""
import json
import sys


def headlines(doc):
    out = {}
    for s in doc["series"]:
        fit = s["fits"].get("larger_half")
        if fit:
            out[f"exponent {s['method']} {s['backend']}"] = (fit["exponent"], fit["low"], fit["high"], "abs", 0.1)
    for r in doc["naive_over_flag"]:
        out[f"naive/FLAG {r['backend']} N={r['N']}"] = (r["naive_over_flag"], r["low"], r["high"], "rel", 0.10)
    return out


def main(a_path, b_path):
    a, b = (headlines(json.load(open(p))) for p in (a_path, b_path))
    failures = 0
    print(f"{'figure':<26} {'A [95%]':>22} {'B [95%]':>22} {'difference':>11}  covered  verdict")
    for key in sorted(set(a) & set(b)):
        (ea, la, ha, kind, limit), (eb, lb, hb, _, _) = a[key], b[key]
        diff = abs(ea - eb) if kind == "abs" else abs(ea / eb - 1)
        covered = la <= eb <= ha and lb <= ea <= hb
        ok = diff <= limit and covered
        failures += not ok
        shown = f"{diff:.3f}" if kind == "abs" else f"{100 * diff:.1f}%"
        print(f"{key:<26} {ea:>7.3f} [{la:.3f}, {ha:.3f}] {eb:>7.3f} [{lb:.3f}, {hb:.3f}] {shown:>11}  "
              f"{'both' if covered else 'no':<7}  {'agree' if ok else 'DIFFER'}")
    missing = set(a) ^ set(b)
    if missing:
        print("in one run only:", ", ".join(sorted(missing)))
    print(f"{len(set(a) & set(b)) - failures} of {len(set(a) & set(b))} figures agree "
          f"(exponents within 0.1, ratios within 10%, each interval covering the other's estimate)")
    return 1 if failures or missing else 0


if __name__ == "__main__":
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    sys.exit(main(sys.argv[1], sys.argv[2]))
