#!/usr/bin/env python3
"""Where a cloud's relative RMSE comes from: its squared error and squared
truth by distance to the nearest positional light.

Reads the per-point files of `placement_target --dump DIR` (`x,y,z,se,st[,w,s[,pe,te]]`)
and the scene file's `[[light]]` tables (sphere and point lights; directional
ones have no position):

    python3 scripts/error_by_distance.py SCENE.toml 'DIR/grid_421_s*.csv' \
        'DIR/adaptive_105_s*.csv' [--bands 0,0.15,0.2,0.3,0.5,1,2] [--stratified] [--json]

For each glob (files pooled: e.g. several placement seeds on the same
points) and each band `[a, b)` of distance to the nearest light it prints the
band's point count, its share of the pooled squared error `Σse / Σst` and its
share of the squared truth `Σst_band / Σst` (both divided by the total
squared truth, so a method's shares of error add up to its `rel_rmse²`),
and, where the files have the `pe` and `te` columns, the part of the error
share at points the blend over-lights (its mean irradiance above the
truth's): light carried too far, from a probe next to a lamp, say, as against
light missed.
Uniform rows only, unweighted, unless `--stratified` (then every row with
its weight `w`; the files are read by `bootstrap_ratio.rows`, so both scripts
take the same rows). Standard library only (Python 3.11 for `tomllib`).
"""

import argparse
import glob
import json
import math
import sys
import tomllib

from bootstrap_ratio import rows


def lights(scene):
    """Positions of the scene file's sphere and point lights."""
    try:
        with open(scene, "rb") as f:
            doc = tomllib.load(f)
    except OSError as e:
        sys.exit(f"{scene}: {e.strerror}")
    except tomllib.TOMLDecodeError as e:
        sys.exit(f"{scene}: not a TOML scene file: {e}")
    out = []
    for light in doc.get("light", []):
        if light.get("kind", "point") != "directional" and "position" in light:
            out.append(tuple(float(x) for x in light["position"]))
    return out


def bands_of(pattern, positions, bands, stratified):
    """(count, Σw·se, Σw·st, Σw·se where over-lit or None) per band, and
    the total Σw·st, over the files."""
    files = sorted(glob.glob(pattern))
    if not files:
        sys.exit(f"{pattern}: no file matches")
    n = len(bands)
    count, se, st, over = [0] * n, [0.0] * n, [0.0] * n, [0.0] * n
    signed = True
    for path in files:
        for p, e, t, _, o in rows(path, stratified):
            d = min((math.dist(p, q) for q in positions), default=math.inf)
            k = max(i for i, a in enumerate(bands) if d >= a)
            count[k] += 1
            se[k] += e
            st[k] += t
            if o is None:
                signed = False
            elif o:
                over[k] += e
    return count, se, st, over if signed else None, sum(st)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("scene")
    ap.add_argument("globs", nargs="+")
    ap.add_argument("--bands", default="0,0.15,0.2,0.3,0.5,1,2")
    ap.add_argument("--stratified", action="store_true")
    ap.add_argument("--json", action="store_true")
    a = ap.parse_args()
    bands = [float(x) for x in a.bands.split(",")]
    if bands[0] != 0 or bands != sorted(bands):
        sys.exit("--bands: increasing distances starting at 0")
    positions = lights(a.scene)
    if not positions:
        sys.exit(f"{a.scene}: no sphere or point light")
    report = []
    for pattern in a.globs:
        count, se, st, over, total = bands_of(pattern, positions, bands, a.stratified)
        rows = []
        for i, lo in enumerate(bands):
            hi = bands[i + 1] if i + 1 < len(bands) else math.inf
            rows.append(
                {
                    "from": lo,
                    "to": None if hi == math.inf else hi,
                    "points": count[i],
                    "error_share": se[i] / total,
                    "truth_share": st[i] / total,
                    "over_share": None if over is None else over[i] / total,
                }
            )
        report.append(
            {"files": pattern, "rel_rmse": math.sqrt(sum(se) / total), "bands": rows}
        )
    if a.json:
        print(json.dumps(report))
        return
    for r in report:
        print(f"{r['files']}: rel_rmse {r['rel_rmse']:.3f}")
        print("   distance (m)   points  error/Σst  truth/Σst  over-lit")
        for b in r["bands"]:
            span = f"{b['from']:.2f}+" if b["to"] is None else f"{b['from']:.2f}-{b['to']:.2f}"
            o = "" if b["over_share"] is None else f"  {b['over_share']:8.3f}"
            print(
                f"   {span:>12} {b['points']:8d}  {b['error_share']:9.3f}  {b['truth_share']:9.3f}{o}"
            )


if __name__ == "__main__":
    main()
