"""Sweep throughput with 1 and 2 dask workers, and where the time goes (one JSON line).

Runs ``demseis.api.generate`` (the path of ``demseis generate``) alternately with 1 and 2
LocalCluster workers (``--workers 1,2``) and with each worker start method of ``--methods``
(``forkserver``, the default, and ``spawn``; see :mod:`demseis.generator.sweep.workers`),
``--repeats`` times each, into fresh stores, each sweep in a fresh Python process (the
forkserver and the Numba kernels are not reused between sweeps). It reports medians of:
samples/s end to end (``run_sweep``, cluster start-up included), for the whole process (its
imports too) and in the compute phase (first task submitted to last task done); the ratios to
one worker; and per phase, the driver's wall seconds (prepare the store, start the cluster,
compute, close the cluster, finalize) and the tasks' seconds (DEM, render, store write) and
CPU seconds (the task threads'), the task overhead (compute time × workers − task time:
scheduling, and imbalance at the end), and the tail (compute end − the first worker to go
idle). The machine is shared: compare the ratios, not the absolute numbers.

``--ceiling`` also measures what the hardware allows, without dask or a store: one run's
computation (``run_shard``) timed alone in one process, then the same computation in N
processes at once; ``ceiling_N = N x t_alone / t_together`` is the best speedup N workers could
reach on this machine (cores that share caches, memory bandwidth or a hypervisor's time slow
each other down).

    python benchmarks/sweep.py [--repeats 3] [--preset quick] [--workers 1,2]
                               [--methods forkserver,spawn] [--ceiling]
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from demseis.generator.config.settings import load_config


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
        "task_engine_s": sum(t["engine_s"] for t in tasks),
        "task_render_s": sum(t["render_s"] for t in tasks),
        "task_write_s": sum(t["write_s"] for t in tasks),
        "task_cpu_s": sum(t.get("cpu_s", 0.0) for t in tasks),
        "task_overhead_s": workers * s.compute_seconds - task_s,
        "tail_s": (max(last_end_per_worker.values()) - min(last_end_per_worker.values()))
        if len(last_end_per_worker) > 1 else 0.0,
        "first_task_s": max(t["seconds"] for t in tasks) if tasks else 0.0,
    }
    return out


def _timed_run(cfg_dict: dict, run: int, barrier) -> float:
    """Seconds of ``run_shard(run)`` in this process, after a warm-up run (Numba caches)."""
    import time

    from demseis.generator.config.settings import parse_config
    from demseis.generator.sweep.pipeline import run_shard

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


def _one_sweep(args: argparse.Namespace) -> None:
    """``--one W``: run one sweep with W workers into ``--out`` (``demseis.api.generate``, the
    path of ``demseis generate``) and print its profile."""
    from demseis.api import generate

    cfg = load_config(args.config, preset=args.preset)
    s = generate(cfg, out=Path(args.out), workers=args.one, progress=False).run_summary
    if s.failed:
        raise SystemExit(f"sweep failed: {s.failed}")
    print(json.dumps(_profile(s, args.one)))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=2)
    ap.add_argument("--preset", default="quick")
    ap.add_argument("--config", default=None, help="a TOML config layered on --preset")
    ap.add_argument("--workers", default="1,2", help="comma-separated worker counts")
    ap.add_argument("--methods", default="forkserver",
                    help="comma-separated worker start methods (forkserver, spawn)")
    ap.add_argument("--ceiling", action="store_true",
                    help="also measure the hardware's best speedup for the largest worker count")
    ap.add_argument("--one", type=int, default=None, help=argparse.SUPPRESS)
    ap.add_argument("--out", default=None, help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.one is not None:
        _one_sweep(args)
        return
    cfg = load_config(args.config, preset=args.preset)
    counts = [int(w) for w in args.workers.split(",")]
    methods = [m.strip() for m in args.methods.split(",")]
    runs = [(m, w) for m in methods for w in counts]
    results: dict[tuple[str, int], list[dict[str, float]]] = {r: [] for r in runs}
    tmp = Path(tempfile.mkdtemp(prefix="demseis-sweep-bench-"))
    try:
        for rep in range(args.repeats):
            for method, workers in runs:
                out = tmp / f"{method}-w{workers}-r{rep}.zarr"
                cmd = [sys.executable, __file__, "--one", str(workers), "--out", str(out),
                       "--preset", args.preset]
                if args.config:
                    cmd += ["--config", args.config]
                env = {**os.environ, "DEMSEIS_WORKER_START": method}
                t0 = time.perf_counter()
                res = subprocess.run(cmd, env=env, capture_output=True, text=True)
                process_s = time.perf_counter() - t0
                if res.returncode != 0:
                    raise SystemExit(f"{method}, {workers} workers: {res.stderr[-2000:]}")
                prof = json.loads(res.stdout.strip().splitlines()[-1])
                prof["process_wall_s"] = process_s  # the whole process: imports included
                prof["process_samples_per_s"] = cfg.n_samples / process_s
                results[(method, workers)].append(prof)
                shutil.rmtree(out)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    med = {r: {k: round(statistics.median(x[k] for x in rs if k in x), 3)
               for k in rs[0]} for r, rs in results.items()}
    base = counts[0]
    line = {"benchmark": "sweep", "preset": args.preset, "config": args.config,
            "samples": cfg.n_samples, "runs": cfg.sweep.n_runs, "repeats": args.repeats,
            "cpus": os.cpu_count(),
            "medians": {f"{m}/{w}": v for (m, w), v in med.items()}}
    for method in methods:
        for w in counts[1:]:
            one, many = med[(method, base)], med[(method, w)]
            line[f"{method}_speedup_{w}_vs_{base}"] = round(
                many["e2e_samples_per_s"] / one["e2e_samples_per_s"], 3)
            line[f"{method}_process_speedup_{w}_vs_{base}"] = round(
                many["process_samples_per_s"] / one["process_samples_per_s"], 3)
            line[f"{method}_compute_speedup_{w}_vs_{base}"] = round(
                many["compute_samples_per_s"] / one["compute_samples_per_s"], 3)
    if len(methods) > 1:
        for w in counts:
            line[f"{methods[0]}_vs_{methods[1]}_e2e_{w}"] = round(
                med[(methods[0], w)]["e2e_samples_per_s"] / med[(methods[1], w)]["e2e_samples_per_s"], 3)
    if args.ceiling:
        line.update(_ceiling(cfg, max(counts), args.repeats))
    print(json.dumps(line))


if __name__ == "__main__":
    main()
