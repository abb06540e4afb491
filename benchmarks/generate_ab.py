"""`demseis generate` of several checkouts, run alternately (A B C A B C ...), wall and CPU time.

Each ``--exe NAME=PATH`` is a ``demseis`` executable (a checkout's venv/bin/demseis). Every
round runs each of them once, in order, into a fresh store in a scratch folder, with
``--preset``/``--workers 0 --quiet`` (one process: the DEM, render, labels and store writer in
series, plus start-up). The wall time is measured around the child; the CPU time is the
child's user + system time. Prints medians, ratios to the first executable (> 1: faster than
it) and the 1-minute load average before each run, as ONE JSON line.

    python benchmarks/generate_ab.py --exe base=/path/a/.venv/bin/demseis \
        --exe new=/path/b/.venv/bin/demseis [--preset quick] [--rounds 3] [--workers 0]
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import shutil
import statistics
import subprocess
import tempfile
import time


def run_once(exe: str, preset: str, workers: int, out: str) -> tuple[float, float]:
    """(wall s, CPU s) of one ``generate`` into ``out`` (removed first)."""
    shutil.rmtree(out, ignore_errors=True)
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    subprocess.run([exe, "generate", "--preset", preset, "--workers", str(workers), "--quiet",
                    "--out", out], check=True, stdout=subprocess.DEVNULL)
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return wall, cpu


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--exe", action="append", required=True, help="NAME=path to demseis")
    ap.add_argument("--preset", default="quick")
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--workers", type=int, default=0)
    a = ap.parse_args(argv)
    exes = dict(e.split("=", 1) for e in a.exe)
    first = next(iter(exes))
    wall = {n: [] for n in exes}
    cpu = {n: [] for n in exes}
    load = []
    with tempfile.TemporaryDirectory(prefix="demseis-generate-ab-") as tmp:
        for _ in range(a.rounds):
            for name, exe in exes.items():
                load.append(os.getloadavg()[0])
                w, c = run_once(exe, a.preset, a.workers, os.path.join(tmp, name + ".zarr"))
                wall[name].append(w)
                cpu[name].append(c)
    mw = {n: statistics.median(v) for n, v in wall.items()}
    mc = {n: statistics.median(v) for n, v in cpu.items()}
    print(json.dumps({
        "benchmark": "generate_ab", "preset": a.preset, "workers": a.workers,
        "rounds": a.rounds, "exes": exes, "wall_s": wall, "cpu_s": cpu,
        "wall_s_median": mw, "cpu_s_median": mc,
        f"speed_vs_{first}_wall": {n: mw[first] / v for n, v in mw.items()},
        f"speed_vs_{first}_cpu": {n: mc[first] / v for n, v in mc.items()},
        "load_avg_1min": [min(load), max(load)],
    }))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
