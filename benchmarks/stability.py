"""How many DEM runs of a preset go unstable: simulate runs only (no rendering) and count the
runs that finished as configured, on a stabilised try, or not at all. One JSON line.

Usage::

    NUMBA_NUM_THREADS=1 python benchmarks/stability.py --preset variety --runs 500 \\
        [--start 0] [--workers 16] [--max-seconds 0] [--config FILE]

Runs ``start .. start + runs - 1`` of the preset (``--config``: a TOML file over the preset,
as ``demseis generate`` reads it) are simulated exactly as a sweep simulates them
(:meth:`demseis.generator.engines.dem.DemEngine.simulate`: the stabilised tries included; a
run's values depend only on the seed and its index, not on ``n_runs``), ``--workers``
processes at a time, one Numba thread each. ``--max-seconds`` (0: no limit) stops starting runs
after that many seconds; ``runs`` in the output is the number that finished.

Output keys: ``preset``, ``seed``, ``runs``, ``as_configured`` (finished on the first try),
``stabilised`` (finished on a stabilised try: ``dem_attempt`` >= 1), ``failed`` (unstable on
every try), ``stabilised_runs`` (run -> its try), ``failed_runs`` (run -> the error),
``cpu_s`` (the runs' CPU seconds, summed), ``wall_s``.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time

os.environ.setdefault("NUMBA_NUM_THREADS", "1")


def _config(preset: str, path: str | None, n_runs: int):
    from demseis.generator.config.settings import load_config, parse_config

    raw = load_config(path, preset=preset).to_dict()
    raw["sweep"]["n_runs"] = n_runs
    return parse_config(raw)


def _one(args: tuple[str, str | None, int, int]) -> dict:
    """Simulate run ``run``: its ``dem_attempt``, or the error of a run unstable on every try."""
    from demseis.errors import SimulationError
    from demseis.generator.config.sampling import plan_run
    from demseis.generator.engines import get_engine

    preset, path, n_runs, run = args
    cfg = _config(preset, path, n_runs)
    c0 = time.process_time()
    try:
        result = get_engine(cfg.model.engine).simulate(cfg, plan_run(cfg, run))
        out = {"run": run, "attempt": int(result.info.values.get("dem_attempt", 0))}
    except SimulationError as exc:
        out = {"run": run, "error": str(exc)}
    out["cpu_s"] = time.process_time() - c0
    return out


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--preset", default="variety")
    ap.add_argument("--config", help="TOML file over the preset")
    ap.add_argument("--runs", type=int, default=48)
    ap.add_argument("--start", type=int, default=0)
    ap.add_argument("--workers", type=int, default=1)
    ap.add_argument("--max-seconds", type=float, default=0.0)
    a = ap.parse_args(argv)
    n_runs = a.start + a.runs
    cfg = _config(a.preset, a.config, n_runs)   # checks the config once, in the driver
    jobs = [(a.preset, a.config, n_runs, r) for r in range(a.start, n_runs)]
    t0 = time.perf_counter()
    results: list[dict] = []

    def out_of_time() -> bool:
        return a.max_seconds > 0 and time.perf_counter() - t0 > a.max_seconds

    if a.workers <= 1:
        for job in jobs:
            if out_of_time():
                break
            results.append(_one(job))
    else:
        from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait

        with ProcessPoolExecutor(a.workers) as pool:
            queue = iter(jobs)
            running = {pool.submit(_one, j) for _, j in zip(range(a.workers), queue)}
            while running:
                done, running = wait(running, return_when=FIRST_COMPLETED)
                results += [f.result() for f in done]
                if not out_of_time():
                    running |= {pool.submit(_one, j) for _, j in zip(range(len(done)), queue)}
    stabilised = {r["run"]: r["attempt"] for r in results if r.get("attempt")}
    failed = {r["run"]: r["error"] for r in results if "error" in r}
    print(json.dumps({
        "benchmark": "stability", "preset": a.preset, "config": a.config, "seed": cfg.sweep.seed,
        "start": a.start, "runs": len(results),
        "as_configured": len(results) - len(stabilised) - len(failed),
        "stabilised": len(stabilised), "failed": len(failed),
        "stabilised_runs": dict(sorted(stabilised.items())),
        "failed_runs": dict(sorted(failed.items())),
        "cpu_s": round(sum(r["cpu_s"] for r in results), 1),
        "wall_s": round(time.perf_counter() - t0, 1), "workers": a.workers,
    }))
    return 0


if __name__ == "__main__":
    sys.exit(main())
