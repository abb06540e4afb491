"""Sweep throughput with 1 and 2 dask workers, and where the time goes (one JSON line).

Runs ``run_sweep`` alternately with 1 and 2 LocalCluster workers (``--workers 1,2``),
``--repeats`` times each, into fresh stores, and reports medians of: samples/s end to end
(cluster start-up included, as ``demseis generate`` sees it) and in the compute phase (first
task submitted to last task done); the ratios to one worker; and per phase, the driver's wall
seconds (prepare the store, start the cluster with the overlapped Numba warm-up, compute,
close the cluster, finalize) and the tasks' seconds (DEM, render, store write), the task
overhead (compute time × workers − task time: scheduling, worker imports and Numba cache loads
in the first task, and imbalance at the end), and the tail (compute end − the first worker to
go idle). The machine is shared: compare the ratios, not the absolute numbers.

``--ceiling`` also measures what the hardware allows, without dask or a store: one run's
computation (``run_shard``) timed alone in one process, then the same computation in N
processes at once; ``ceiling_N = N x t_alone / t_together`` is the best speedup N workers could
reach on this machine (cores that share caches, memory bandwidth or a hypervisor's time slow
each other down).

    python benchmarks/sweep.py [--repeats 3] [--preset quick] [--workers 1,2] [--ceiling]
"""

from __future__ import annotations

import argparse
import json
import shutil
import statistics
import tempfile
from pathlib import Path

from demseis.generator.config import load_config
from demseis.generator.sweep import run_sweep


def _profile(s, workers: int) -> dict[str, float]:
    n = s.n_samples_written
    tasks = s.tasks
    last_end_per_worker = {}
    for t in tasks:
        last_end_per_worker[t["pid"]] = max(last_end_per_worker.get(t["pid"], 0.0), t["end"])
    task_s = sum(t["seconds"] for t in tasks)
    out = {
        "e2e_samples_per_s": n / s.seconds,
        "compute_samples_per_s": n / s.compute_seconds,
        "wall_s": s.seconds,
        **{f"{k}_s": v for k, v in s.phase_seconds.items()},
        "task_dem_s": sum(t["dem_s"] for t in tasks),
        "task_render_s": sum(t["render_s"] for t in tasks),
        "task_write_s": sum(t["write_s"] for t in tasks),
        "task_overhead_s": workers * s.compute_seconds - task_s,
        "tail_s": (max(last_end_per_worker.values()) - min(last_end_per_worker.values()))
        if len(last_end_per_worker) > 1 else 0.0,
        "first_task_s": max(t["seconds"] for t in tasks) if tasks else 0.0,
    }
    return out


def _timed_run(cfg_dict: dict, run: int, barrier) -> float:
    """Seconds of ``run_shard(run)`` in this process, after a warm-up run (Numba caches)."""
    import time

    from demseis.generator.config import parse_config
    from demseis.generator.pipeline import run_shard

    cfg = parse_config(cfg_dict)
    run_shard(cfg, run)
    if barrier is not None:
        barrier.wait()  # start the timed runs together
    t0 = time.perf_counter()
    run_shard(cfg, run)
    return time.perf_counter() - t0


def _ceiling(cfg, n: int, repeats: int) -> dict[str, float]:
    """Median ``n x t_alone / t_together`` over ``repeats`` rounds (see the module doc)."""
    import multiprocessing as mp

    ctx = mp.get_context("spawn")
    ratios, alone, together = [], [], []
    for rep in range(repeats):
        with ctx.Pool(1) as pool:
            t1 = pool.apply(_timed_run, (cfg.to_dict(), rep % cfg.sweep.n_runs, None))
        with ctx.Manager() as manager:
            barrier = manager.Barrier(n)
            with ctx.Pool(n) as pool:
                tn = max(pool.starmap(_timed_run, [(cfg.to_dict(), rep % cfg.sweep.n_runs, barrier)] * n))
        alone.append(t1)
        together.append(tn)
        ratios.append(n * t1 / tn)
    return {f"ceiling_{n}": round(statistics.median(ratios), 3),
            "ceiling_run_alone_s": round(statistics.median(alone), 3),
            f"ceiling_run_{n}_together_s": round(statistics.median(together), 3)}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=2)
    ap.add_argument("--preset", default="quick")
    ap.add_argument("--config", default=None, help="a TOML config layered on --preset")
    ap.add_argument("--workers", default="1,2", help="comma-separated worker counts")
    ap.add_argument("--ceiling", action="store_true",
                    help="also measure the hardware's best speedup for the largest worker count")
    args = ap.parse_args()
    cfg = load_config(args.config, preset=args.preset)
    counts = [int(w) for w in args.workers.split(",")]
    results: dict[int, list[dict[str, float]]] = {w: [] for w in counts}
    tmp = Path(tempfile.mkdtemp(prefix="demseis-sweep-bench-"))
    try:
        for rep in range(args.repeats):
            for workers in counts:
                out = tmp / f"w{workers}-r{rep}.zarr"
                s = run_sweep(cfg, out, workers=workers, progress=False)
                if s.failed:
                    raise SystemExit(f"sweep failed: {s.failed}")
                results[workers].append(_profile(s, workers))
                shutil.rmtree(out)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    med = {w: {k: round(statistics.median(r[k] for r in rs if k in r), 3)
               for k in rs[0]} for w, rs in results.items()}
    base = counts[0]
    line = {"benchmark": "sweep", "preset": args.preset, "config": args.config,
            "samples": cfg.n_samples, "runs": cfg.sweep.n_runs, "repeats": args.repeats,
            "medians": {str(w): m for w, m in med.items()}}
    for w in counts[1:]:
        line[f"speedup_{w}_vs_{base}"] = round(med[w]["e2e_samples_per_s"] / med[base]["e2e_samples_per_s"], 3)
        line[f"compute_speedup_{w}_vs_{base}"] = round(
            med[w]["compute_samples_per_s"] / med[base]["compute_samples_per_s"], 3)
    if args.ceiling:
        line.update(_ceiling(cfg, max(counts), args.repeats))
    print(json.dumps(line))


if __name__ == "__main__":
    main()
