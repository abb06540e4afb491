"""Sweep throughput with 1 and 2 dask workers on the quick preset (one JSON line).

Runs ``run_sweep`` on the quick preset alternately with 1 and 2 LocalCluster workers,
``--repeats`` times each, into fresh stores, and reports median samples/s end to end
(cluster start-up included) and in the compute phase (first task submitted to last task done),
and the 2-worker / 1-worker ratios. The machine is shared: compare the ratios, not the absolute
numbers.

    python benchmarks/sweep.py [--repeats 2] [--preset quick]
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


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=2)
    ap.add_argument("--preset", default="quick")
    args = ap.parse_args()
    cfg = load_config(preset=args.preset)
    results: dict[int, dict[str, list[float]]] = {1: {"e2e": [], "compute": []}, 2: {"e2e": [], "compute": []}}
    tmp = Path(tempfile.mkdtemp(prefix="demseis-sweep-bench-"))
    try:
        for rep in range(args.repeats):
            for workers in (1, 2):
                out = tmp / f"w{workers}-r{rep}.zarr"
                s = run_sweep(cfg, out, workers=workers, progress=False)
                if s.failed:
                    raise SystemExit(f"sweep failed: {s.failed}")
                n = s.n_samples_written
                results[workers]["e2e"].append(n / s.seconds)
                results[workers]["compute"].append(n / s.compute_seconds)
                shutil.rmtree(out)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    med = {w: {k: statistics.median(v) for k, v in r.items()} for w, r in results.items()}
    print(json.dumps({
        "benchmark": "sweep",
        "preset": args.preset,
        "samples": cfg.n_samples,
        "runs": cfg.sweep.n_runs,
        "repeats": args.repeats,
        "samples_per_s_1_worker": round(med[1]["e2e"], 3),
        "samples_per_s_2_workers": round(med[2]["e2e"], 3),
        "speedup_2_vs_1": round(med[2]["e2e"] / med[1]["e2e"], 3),
        "compute_samples_per_s_1_worker": round(med[1]["compute"], 3),
        "compute_samples_per_s_2_workers": round(med[2]["compute"], 3),
        "compute_speedup_2_vs_1": round(med[2]["compute"] / med[1]["compute"], 3),
    }))


if __name__ == "__main__":
    main()
