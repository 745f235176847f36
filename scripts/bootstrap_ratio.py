#!/usr/bin/env python3
"""Paired bootstrap of the ratio of two placement methods' relative RMSE.

Reads the per-point files that `placement_target --dump DIR` writes
(`x,y,z,se,st`: squared error and squared truth of each evaluation point, in
the evaluation's order) for two methods, each over one or more placement
seeds, all on the same evaluation points:

    python3 scripts/bootstrap_ratio.py --a 'DIR/adaptive_105_s*.csv' \
        --b 'DIR/grid_421_s*.csv' [--reps 1000] [--seed 1] [--json]

The figure is the one BENCHMARKS.md reports: the mean over A's files of
`rel_rmse = sqrt(sum se / sum st)`, divided by the same mean over B's files.
The bootstrap resamples the evaluation *points* with replacement (the same
draw for every file, so the comparison stays paired) and prints the ratio's
5th, 50th and 95th percentiles: how much of a difference between two
methods a set of this many uniform points can resolve. On scenes whose
error sits in a few points next to small lights this interval is wide.
With `--stratified` (files of `placement_target --near-lights`), every
row counts with its weight `w` (the free space it stands for), and the
bootstrap resamples within each stratum `s` (uniform points; each light's
ball): the same population figure with far less variance.
Standard library only.
"""

import argparse
import glob
import json
import random
import sys


def rows(path, stratified):
    """The rows of one `--dump` file as `((x, y, z), w·se, w·st, stratum,
    over)`: uniform rows only, unweighted, unless `stratified` (then every
    row, weighted). `over` is whether the blend's mean irradiance over the
    colour channels exceeds the truth's (columns `pe`, `te`), `None` in files
    without them. Also used by `error_by_distance.py`."""
    with open(path) as f:
        header = f.readline().strip().split(",")
        if header[3:5] != ["se", "st"]:
            sys.exit(f"{path}: expected columns x,y,z,se,st[,w,s], found {header}")
        weighted = header[5:7] == ["w", "s"]
        signed = weighted and header[7:9] == ["pe", "te"]
        if stratified and not weighted:
            sys.exit(f"{path}: --stratified needs the w and s columns (--near-lights)")
        for line in f:
            cols = line.split(",")
            w, s = (float(cols[5]), int(cols[6])) if weighted else (1.0, 0)
            if not stratified:
                if s != 0:
                    continue
                w = 1.0
            p = (float(cols[0]), float(cols[1]), float(cols[2]))
            over = float(cols[7]) > float(cols[8]) if signed else None
            yield p, w * float(cols[3]), w * float(cols[4]), s, over


def load(path, stratified):
    """Weighted terms `w·se`, `w·st` and the stratum of each row (`rows`)."""
    se, st, strata = [], [], []
    for _, e, t, s, _ in rows(path, stratified):
        se.append(e)
        st.append(t)
        strata.append(s)
    return se, st, strata


def rel_rmse(se, st, counts=None):
    if counts is None:
        a, b = sum(se), sum(st)
    else:
        a = sum(c * x for c, x in zip(counts, se) if c)
        b = sum(c * x for c, x in zip(counts, st) if c)
    return (a / b) ** 0.5 if b > 0 else 0.0


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--a", required=True, help="glob of method A's files")
    ap.add_argument("--b", required=True, help="glob of method B's files")
    ap.add_argument("--reps", type=int, default=1000)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--json", action="store_true")
    ap.add_argument(
        "--stratified",
        action="store_true",
        help="all rows with their weights (files of --near-lights); "
        "the bootstrap resamples within each stratum",
    )
    args = ap.parse_args()
    files = {k: sorted(glob.glob(g)) for k, g in (("a", args.a), ("b", args.b))}
    for k, f in files.items():
        if not f:
            sys.exit(f"--{k}: no file matches")
    data = {k: [load(p, args.stratified) for p in f] for k, f in files.items()}
    strata = data["a"][0][2]
    n = len(strata)
    if any(s != strata for d in data.values() for _, _, s in d):
        sys.exit("the files hold different points")
    groups = {}
    for i, s in enumerate(strata):
        groups.setdefault(s, []).append(i)

    def ratio(counts):
        m = {
            k: sum(rel_rmse(se, st, counts) for se, st, _ in d) / len(d)
            for k, d in data.items()
        }
        return m["a"], m["b"], (m["a"] / m["b"] if m["b"] > 0 else float("inf"))

    a, b, r = ratio(None)
    rng = random.Random(args.seed)
    reps = []
    for _ in range(args.reps):
        counts = [0] * n
        for idx in groups.values():
            for _ in idx:
                counts[idx[rng.randrange(len(idx))]] += 1
        reps.append(ratio(counts)[2])
    reps.sort()
    q = lambda p: reps[min(len(reps) - 1, int(p * len(reps)))]
    out = {
        "points": n,
        "a_files": len(data["a"]),
        "b_files": len(data["b"]),
        "a_rel_rmse": a,
        "b_rel_rmse": b,
        "ratio": r,
        "ratio_p05": q(0.05),
        "ratio_p50": q(0.5),
        "ratio_p95": q(0.95),
        "share_a_better": sum(x < 1 for x in reps) / len(reps),
    }
    if args.json:
        print(json.dumps(out))
    else:
        print(
            f"{n} points: A {a:.3f} ({len(data['a'])} files), B {b:.3f} "
            f"({len(data['b'])} files), A/B {r:.3f}; bootstrap 5-50-95 %: "
            f"{out['ratio_p05']:.3f} {out['ratio_p50']:.3f} {out['ratio_p95']:.3f}; "
            f"A better in {100 * out['share_a_better']:.0f} % of resamples"
        )


if __name__ == "__main__":
    main()
