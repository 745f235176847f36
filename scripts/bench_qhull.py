#!/usr/bin/env python3
"""Peer benchmark: probekit's tetrahedralize vs SciPy's Qhull on the SAME points.

Runs the Rust example `delaunay_peer` (which writes the point sets as raw
little-endian f32 xyz files and times probekit), then times
scipy.spatial.Delaunay (Qhull, default options "Qbb Qc Qz Q12" + "Qt") on the
same files, best of N runs, and counts Qhull's zero-volume tetrahedra (exact
for the integer grid: volumes of integer points are computed exactly in
float64; for random points |6·vol| < 1e-12 is reported).

Usage: python3 scripts/bench_qhull.py [WORKDIR] [--big]  (--big: also Qhull on 1 M points)   (pip install scipy numpy)

Set PROBEKIT_DELAUNAY_PEER to a built `delaunay_peer` binary to run it instead
of `cargo run` (on a machine without a Rust toolchain).
"""
import json
import os
import subprocess
import sys
import time

import numpy as np
import scipy
from scipy.spatial import Delaunay

args = [a for a in sys.argv[1:] if not a.startswith("--")]
work = args[0] if args else "target/delaunay_peer"
os.makedirs(work, exist_ok=True)
peer = os.environ.get("PROBEKIT_DELAUNAY_PEER")
cmd = [peer] if peer else ["cargo", "run", "--release", "-q", "-p", "probekit", "--example", "delaunay_peer", "--"]
out = subprocess.run(
    cmd + [work],
    check=True, capture_output=True, text=True,
).stdout
ours = {r["set"]: r for r in map(json.loads, out.split())}

print(f"scipy {scipy.__version__}, numpy {np.__version__}")
print("| set | points | probekit s (CPU s) | probekit pts/s | probekit tets | probekit zero-vol | Qhull s (CPU s) | Qhull pts/s | Qhull tets | Qhull zero-vol | speed-up wall (CPU) |")
print("|---|---|---|---|---|---|---|---|---|---|---|")
for name, r in ours.items():
    pts = np.fromfile(os.path.join(work, name + ".f32"), dtype="<f4").reshape(-1, 3).astype(np.float64)
    if len(pts) > 200_000 and "--big" not in sys.argv:
        print(f"| {name} | {len(pts)} | {r['seconds']:.3f} ({r.get('cpu_seconds', float('nan')):.3f}) | {r['points_per_s']:.0f} | {r['tets']} | {r['non_positive_tets']} | (skipped, pass --big) | | | | |")
        continue
    runs = 3 if len(pts) <= 200_000 else 1
    best = best_cpu = float("inf")
    for _ in range(runs):
        c0 = time.process_time()
        t0 = time.perf_counter()
        d = Delaunay(pts)
        best = min(best, time.perf_counter() - t0)
        best_cpu = min(best_cpu, time.process_time() - c0)
    s = d.simplices
    a, b, c, e = (pts[s[:, i]] for i in range(4))
    vol6 = np.einsum("ij,ij->i", b - a, np.cross(c - a, e - a))
    zero = int(np.count_nonzero(np.abs(vol6) < 1e-12))
    cpu = r.get("cpu_seconds", float("nan"))
    print(f"| {name} | {len(pts)} | {r['seconds']:.3f} ({cpu:.3f}) | {r['points_per_s']:.0f} | {r['tets']} | {r['non_positive_tets']} "
          f"| {best:.3f} ({best_cpu:.3f}) | {len(pts)/best:.0f} | {len(s)} | {zero} | {best / r['seconds']:.2f}× ({best_cpu / cpu:.2f}×) |")
