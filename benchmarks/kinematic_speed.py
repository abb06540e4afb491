"""Samples/s of the kinematic engine against the DEM engine on the same grid, side by side.

Generates the ``quick`` preset (or ``--runs`` runs of it) in this process (no dask) with
``[model] engine = "dem"`` and ``"kinematic"``, alternating, ``--repeats`` times each, and
prints one JSON line: median end-to-end samples/s of each (what ``demseis generate`` reports),
their ratio, and the median time of one run's computation alone (``run_shard``, no store
writing) of each and that ratio.

    PYTHONPATH=$PWD python benchmarks/kinematic_speed.py --repeats 3
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import platform
import tempfile
import time
from pathlib import Path

import numpy as np


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--runs", type=int, help="n_runs (default: the preset's)")
    args = ap.parse_args(argv)

    from demseis.generator.config.settings import load_config
    from demseis.generator.sweep.driver import run_sweep
    from demseis.generator.sweep.pipeline import run_shard

    base = load_config(preset="quick")
    if args.runs:
        base = dataclasses.replace(base, sweep=dataclasses.replace(base.sweep, n_runs=args.runs))
    cfgs = {e: dataclasses.replace(base, model=dataclasses.replace(base.model, engine=e))
            for e in ("dem", "kinematic")}
    rates: dict[str, list[float]] = {e: [] for e in cfgs}
    per_run: dict[str, list[float]] = {e: [] for e in cfgs}
    with tempfile.TemporaryDirectory() as tmp:
        for e, cfg in cfgs.items():  # warm-up: Numba caches, imports
            run_shard(cfg, 0)
        for r in range(args.repeats):
            for e, cfg in cfgs.items():
                t0 = time.perf_counter()
                s = run_sweep(cfg, Path(tmp) / f"{e}{r}.zarr", workers=0, progress=False)
                wall = time.perf_counter() - t0
                rates[e].append(cfg.sweep.n_runs * cfg.samples_per_run / wall)
                assert not s.failed, s.failed
                t0 = time.perf_counter()
                run_shard(cfg, r % cfg.sweep.n_runs)
                per_run[e].append(time.perf_counter() - t0)
    med = {e: float(np.median(v)) for e, v in rates.items()}
    run = {e: float(np.median(v)) for e, v in per_run.items()}
    print(json.dumps({
        "benchmark": "kinematic_speed", "preset": "quick", "n_runs": base.sweep.n_runs,
        "samples": base.sweep.n_runs * base.samples_per_run, "repeats": args.repeats,
        "dem_samples_per_s": round(med["dem"], 3),
        "kinematic_samples_per_s": round(med["kinematic"], 3),
        "ratio_end_to_end": round(med["kinematic"] / med["dem"], 2),
        "dem_run_compute_s": round(run["dem"], 4),
        "kinematic_run_compute_s": round(run["kinematic"], 4),
        "ratio_compute": round(run["dem"] / run["kinematic"], 1),
        "cpu": platform.processor() or platform.machine()}))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
