"""Statics of the `strata` rendering: how far the two-way time of one trace jumps from its
neighbour's where no fault separates them, with and without ``[output] velocity_median_m``.

For the first ``--runs`` done runs of a store with particle snapshots (a DEM store), every
rendered snapshot's strata columns are built again (the engine's state, then
:func:`demseis.generator.render.section.imaging_input`) once per ``--window-m`` value (the
store's config with ``velocity_median_m`` replaced). The two-way time down each trace comes from
the interval velocity the labels are taken to time with (``vp_cell``). A pair of neighbouring
traces with no fault label in either trace (and none in the trace beyond either) is *unfaulted*;
its jump is the difference of the two traces' two-way times at the bottom of the grid. One
JSON line per window: the median over unfaulted pairs of ``|jump|`` (ms), the share of them
jumping by half a sample and by a whole sample or more, pooled over the snapshots, and the same
for the undeformed snapshots alone (no fault anywhere).

    PYTHONPATH=$PWD python benchmarks/strata_statics.py STORE [--runs 8] [--window-m 0 200]
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np


def pair_jumps(vp_cell: np.ndarray, cell_m: float, fault: np.ndarray) -> np.ndarray:
    """``|t_j - t_{j+1}|`` (s) of the two-way time at the grid's bottom, over the unfaulted
    pairs: neither trace, nor the trace beyond either, holds a fault label."""
    twt = 2.0 * np.sum(cell_m / vp_cell, axis=0)
    faulted = (fault > 0).any(axis=0)
    near = faulted.copy()
    near[1:] |= faulted[:-1]
    near[:-1] |= faulted[1:]
    ok = ~(near[:-1] | near[1:])
    return np.abs(np.diff(twt))[ok]


def measure(store: Path, runs: int, windows: list[float]) -> list[dict]:
    """One result per window (see the module docstring)."""
    from demseis.datasets import open_store, shard_status
    from demseis.generator.config.layout import grid_of
    from demseis.generator.engines import get_engine
    from demseis.generator.render.section import imaging_input, renders_by_snapshot, state_maps
    from demseis.generator.render.survey import labels_at_traces
    from demseis.generator.sweep.rerender import dem_attempts, look_config, stored_run

    source = dict(open_store(store).attrs)["config"]
    attempts = dem_attempts(store)
    todo = [int(r) for r in np.flatnonzero(shard_status(store) == 1)[:runs]]
    out = []
    for w in windows:
        cfg = look_config(source, {"output": {"velocity_median_m": float(w)}})
        engine = get_engine(cfg.model.engine)
        cell = grid_of(cfg).cell_m
        dt = float(cfg.output.dt_s)
        jumps, flat = [], []
        t0 = time.perf_counter()
        for run in todo:
            res = stored_run(store, run, cfg, attempts)
            for state in engine.states(cfg, res, [k for k, _ in renders_by_snapshot(res.spec)]):
                maps = labels_at_traces(cfg, state_maps(state, {}))
                img = imaging_input(cfg, state, maps, res.spec.params)
                j = pair_jumps(img.vp_cell, cell, maps["fault"])
                jumps.append(j)
                if state.snapshot == 0:
                    flat.append(j)
        out.append({"window_m": float(w), **_summary(np.concatenate(jumps), dt),
                    "undeformed": _summary(np.concatenate(flat) if flat else np.zeros(0), dt),
                    "seconds": round(time.perf_counter() - t0, 1)})
    return out


def _summary(j: np.ndarray, dt: float) -> dict:
    if j.size == 0:
        return {"pairs": 0}
    return {"pairs": int(j.size), "median_ms": round(float(np.median(j)) * 1e3, 3),
            "p90_ms": round(float(np.percentile(j, 90)) * 1e3, 3),
            "share_half_sample": round(float(np.mean(j >= 0.5 * dt)), 4),
            "share_one_sample": round(float(np.mean(j >= dt)), 4)}


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("store", type=Path)
    ap.add_argument("--runs", type=int, default=8)
    ap.add_argument("--window-m", type=float, nargs="+", default=[0.0, 200.0])
    a = ap.parse_args(argv)
    if not a.store.exists():
        print(f"strata_statics: no store at {a.store}", file=sys.stderr)
        return 2
    for r in measure(a.store, a.runs, a.window_m):
        print(json.dumps({"benchmark": "strata_statics", "store": a.store.name,
                          "runs": a.runs, **r}))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
