"""Seconds per DEM run with and without the pack library (``[model] pack_library``), by preset.

For each preset that runs the DEM engine, runs ``--runs`` runs (0, 1, ...) of it in this
process (no dask, no store writing) through :func:`demseis.generator.sweep.pipeline.run_shard`, once
with ``pack_library = 0`` (every run settles its own pack: the behaviour before the library)
and once with ``pack_library = K`` from a warm library (its packs settled beforehand into a
temporary ``DEMSEIS_PACK_CACHE``, timed separately), alternating run by run. Prints one JSON
line per (preset, K): the median and every run's DEM seconds (``engine_s``: assembly and
faulting) and rendering seconds, and for the library the seconds to settle each of its packs
once, so the amortised cost of a store of N runs is ``median + K * settle / N``.

Set ``NUMBA_NUM_THREADS=1`` for one core (the script sets it when unset, before Numba loads).

    NUMBA_NUM_THREADS=1 PYTHONPATH=$PWD python benchmarks/pack_library.py \\
        --presets tiny quick variety field --runs 3 --k 8
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import os
import platform
import statistics
import tempfile
import time

os.environ.setdefault("NUMBA_NUM_THREADS", "1")

DEM_PRESETS = ("tiny", "quick", "variety", "field", "seed")


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--presets", nargs="+", default=list(DEM_PRESETS[:4]), choices=DEM_PRESETS)
    ap.add_argument("--runs", type=int, default=3, help="runs timed per preset and mode")
    ap.add_argument("--k", type=int, default=8, help="packs in the library")
    args = ap.parse_args(argv)

    from demseis.generator.config.settings import load_config
    from demseis.generator.engines.dem import PACK_CACHE_ENV, pack_index, run_pack
    from demseis.generator.sweep.pipeline import run_shard

    with tempfile.TemporaryDirectory() as cache:
        os.environ[PACK_CACHE_ENV] = cache
        for preset in args.presets:
            base = load_config(preset=preset)
            cfgs = {k: dataclasses.replace(base, model=dataclasses.replace(
                base.model, pack_library=k)) for k in (0, args.k)}
            run_shard(cfgs[0], 0)  # warm-up: Numba caches, imports (not timed)
            settle = []
            for run in range(args.k):   # runs 0 .. K-1 take every pack once
                t0 = time.perf_counter()
                run_pack(cfgs[args.k], run)
                settle.append(time.perf_counter() - t0)
            dem: dict[int, list[float]] = {k: [] for k in cfgs}
            render: dict[int, list[float]] = {k: [] for k in cfgs}
            for run in range(args.runs):
                for k, cfg in cfgs.items():
                    t: dict[str, float] = {}
                    run_shard(cfg, run, timings=t)
                    dem[k].append(t["engine_s"])
                    render[k].append(t["render_s"])
            for k in cfgs:
                row = {"benchmark": "pack_library", "preset": preset, "pack_library": k,
                       "runs": args.runs, "median_dem_s": round(statistics.median(dem[k]), 3),
                       "dem_s": [round(x, 3) for x in dem[k]],
                       "median_render_s": round(statistics.median(render[k]), 3)}
                if k:
                    row["packs_taken"] = [pack_index(cfgs[k], r) for r in range(args.runs)]
                    row["median_settle_once_s"] = round(statistics.median(settle), 3)
                row.update(numba_threads=os.environ["NUMBA_NUM_THREADS"],
                           cpu=platform.processor() or platform.machine())
                print(json.dumps(row), flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
