"""Is the basement-wall speed quasi-static? Fault the same assembly at speed v and v/2.

Usage::

    NUMBA_NUM_THREADS=1 python benchmarks/dem_quasistatic.py [--scale quick|seed] [--speed 5]

Prints ONE JSON line comparing the final snapshot of three runs from the same settled pack:
A (speed v), B (speed v/2) and C (speed v, another sedimentation seed: the run-to-run scatter
that any perturbation causes in a granular model, the floor against which A-B is judged).

Metrics, on the pre-kinematic elements of the final snapshot:
- ``disp_diff_median_m`` / ``_p90_m``: |x_A - x_B| per element (m);
- ``horizon_rms_m``: RMS difference of horizon elevations (mean centre y of each layer in
  100 m columns) between the runs; relative values are divided by the throw.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from demseis.dem import Material, NormalFault, build_assembly, settle_pack, simulate  # noqa


def horizons(snap, n_layers, x_edges):
    pre = ~snap.deposited
    xy, lay = snap.xy[pre], snap.layer[pre]
    out = np.full((n_layers, x_edges.size - 1), np.nan)
    col = np.searchsorted(x_edges, xy[:, 0]) - 1
    for k in range(n_layers):
        for c in range(x_edges.size - 1):
            m = (lay == k) & (col == c)
            if m.sum() >= 2:
                out[k, c] = xy[m, 1].mean()
    return out


def compare(a, b, n_pre, n_layers, x_edges):
    d = np.hypot(*(a.xy[:n_pre] - b.xy[:n_pre]).T)
    ha, hb = horizons(a, n_layers, x_edges), horizons(b, n_layers, x_edges)
    ok = np.isfinite(ha) & np.isfinite(hb)
    return {"disp_diff_median_m": float(np.median(d)), "disp_diff_p90_m": float(np.percentile(d, 90)),
            "horizon_rms_m": float(np.sqrt(np.mean((ha[ok] - hb[ok]) ** 2)))}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--scale", choices=["quick", "seed"], default="quick")
    ap.add_argument("--speed", type=float, default=NormalFault().speed_m_s)
    ap.add_argument("--cache-dir", default=None)
    args = ap.parse_args(argv)
    if args.scale == "seed":
        w, h, nl, throw = 5000.0, 2770.0, 48, 450.0
    else:
        w, h, nl, throw = 2500.0, 1385.0, 24, 225.0
    mat = Material()
    pack = settle_pack(w, h, material=mat, rng=0, cache_dir=args.cache_dir)
    asm = build_assembly(w, h, n_layers=nl, material=mat, pack=pack)
    runs = {}
    times = {}
    for name, speed, seed in (("A", args.speed, 1), ("B", args.speed / 2, 1), ("C", args.speed, 2)):
        c0 = time.process_time()
        snaps = simulate(asm, NormalFault(x_m=w / 2, throw_m=throw, speed_m_s=speed), mat,
                         n_snapshots=6, rng=seed)
        times[name] = round(time.process_time() - c0, 2)
        runs[name] = snaps[-1]
    edges = np.arange(0.0, w + throw + 100.0, 100.0)
    ab = compare(runs["A"], runs["B"], asm.n, nl, edges)
    ac = compare(runs["A"], runs["C"], asm.n, nl, edges)
    res = {"benchmark": "dem_quasistatic", "scale": args.scale, "n": asm.n, "throw_m": throw,
           "speed_m_s": args.speed, "cpu_s": times,
           "v_vs_half_v": ab, "v_vs_other_seed": ac,
           "v_vs_half_v_rel_throw": {k: v / throw for k, v in ab.items()},
           "v_vs_other_seed_rel_throw": {k: v / throw for k, v in ac.items()}}
    print(json.dumps(res))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
