"""Issue 13's DEM coverage of the slip-trace labels, per preset. Prints one JSON line.

Coverage = share of the cells whose displacement jump (:func:`demseis.labels.coverage.jump_field`,
from the particles, independent of the extraction) is >= 2 x min_slip_m that lie within 2
cells of a fault label, pooled over the snapshots after the first of each run. Also per run:
rungs (worst snapshot), loops, whether every labelled cell slips >= min_slip_m, and the median
``label_maps`` time per snapshot (seed preset: the figure to compare).

    python benchmarks/labels_dem_coverage.py [--runs quick:0,1 seed:0] [--cache DIR]

``--cache DIR`` pickles the DEM snapshots of each run there and reuses them (the DEM of a
``seed`` run takes minutes; the labels are what is measured).
"""

from __future__ import annotations

import argparse
import json
import os
import pickle
import time

import numpy as np


def _snapshots(preset: str, run: int, cache: str | None):
    path = os.path.join(cache, f"{preset}_{run}.pkl") if cache else None
    if path and os.path.exists(path):
        with open(path, "rb") as fh:
            return pickle.load(fh)
    from demseis.generator.config import load_config
    from demseis.generator.pipeline import simulate_run
    from demseis.generator.sampling import plan_run

    cfg = load_config(None, preset=preset)
    snaps, _ = simulate_run(cfg, plan_run(cfg, run))
    if path:
        os.makedirs(cache, exist_ok=True)
        with open(path, "wb") as fh:
            pickle.dump(snaps, fh)
    return snaps


def measure(preset: str, run: int, cache: str | None) -> dict:
    """Coverage, rungs, loops, slip floor and label_maps time of one DEM run."""
    from demseis.generator.config import load_config
    from demseis.generator.pipeline import grid_of
    from demseis.labels import label_maps, strain_history
    from demseis.labels.coverage import jump_coverage, jump_field
    from demseis.labels.traces import displacement_history, loop_count, rung_fraction

    cfg = load_config(None, preset=preset)
    grid = grid_of(cfg)
    lc = cfg.labels
    min_slip = lc.min_slip_for(grid.cell_m)
    snaps = _snapshots(preset, run, cache)
    hist = strain_history(snaps, lc)
    disp = displacement_history(snaps)
    n_hi = n_near = loops = 0
    rungs, times, slip_ok = [], [], True
    per_snap = []
    for k, snap in enumerate(snaps):
        t0 = time.perf_counter()
        maps = label_maps(snap, hist[k], grid, lc, displacement=disp[k])
        times.append(time.perf_counter() - t0)
        if k == 0:
            continue
        f = maps["fault"].astype(bool)
        jump, rock = jump_field(snap, disp[k][0], disp[k][1], grid)
        hi, near = jump_coverage(f, jump, rock, min_slip)
        n_hi += hi
        n_near += near
        per_snap.append(round(near / hi, 3) if hi else None)
        if f.any():
            rungs.append(rung_fraction(f))
            loops += loop_count(f)
            slip_ok &= bool((maps["slip_m"][f] >= min_slip).all())
    return {"preset": preset, "run": run, "coverage": round(n_near / n_hi, 4) if n_hi else None,
            "n_high_jump_cells": n_hi, "per_snapshot": per_snap,
            "max_rungs": round(max(rungs), 4) if rungs else None, "loops": loops,
            "slip_floor_ok": slip_ok,
            "label_maps_s_median": round(float(np.median(times[1:] or times)), 3)}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--runs", nargs="+", default=["quick:0,1,2,3", "seed:0"],
                    help="PRESET:RUN[,RUN...] items")
    ap.add_argument("--cache", default=None, help="directory for pickled DEM snapshots")
    args = ap.parse_args()
    out: dict = {"benchmark": "labels_dem_coverage", "runs": []}
    for item in args.runs:
        preset, _, runs = item.partition(":")
        for r in (runs or "0").split(","):
            out["runs"].append(measure(preset, int(r), args.cache))
    by: dict = {}
    for r in out["runs"]:
        by.setdefault(r["preset"], []).append(r)
    out["coverage"] = {p: round(sum(x["coverage"] * x["n_high_jump_cells"] for x in rs)
                                / max(sum(x["n_high_jump_cells"] for x in rs), 1), 4)
                       for p, rs in by.items()}
    print(json.dumps(out))


if __name__ == "__main__":
    main()
