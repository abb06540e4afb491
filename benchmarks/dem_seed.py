"""Seed-scale normal fault end to end: 5 km x 2.77 km, 48 layers, 45 deg, 450 m throw, 6 snaps.

Usage::

    NUMBA_NUM_THREADS=1 python benchmarks/dem_seed.py [--speed 5.0] [--figure FILE.png]
        [--save FILE.npz] [--no-cache] [--dip 45] [--throw 450]

Prints ONE JSON line: element counts, wall and CPU seconds of settling (or the cache hit),
layering and faulting, and the peak resident memory of the process.
"""

from __future__ import annotations

import argparse
import resource
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from demseis.dem import Material, NormalFault, build_assembly, settle_pack, simulate  # noqa
from _dem_common import finish  # noqa: E402  (benchmarks/ is on sys.path)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--speed", type=float, default=NormalFault().speed_m_s)
    ap.add_argument("--dip", type=float, default=45.0)
    ap.add_argument("--throw", type=float, default=450.0)
    ap.add_argument("--figure", default=None)
    ap.add_argument("--save", default=None)
    ap.add_argument("--cache-dir", default=None)
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args(argv)
    mat = Material()
    t0, c0 = time.perf_counter(), time.process_time()
    pack = settle_pack(5000.0, 2770.0, material=mat, rng=args.seed, cache_dir=args.cache_dir)
    t1, c1 = time.perf_counter(), time.process_time()
    asm = build_assembly(5000.0, 2770.0, n_layers=48, material=mat, pack=pack)
    fault = NormalFault(x_m=2500.0, dip_deg=args.dip, throw_m=args.throw, speed_m_s=args.speed)
    snaps = simulate(asm, fault, mat, n_snapshots=6, rng=np.random.default_rng(args.seed))
    t2, c2 = time.perf_counter(), time.process_time()
    peak_mib = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    res = {"benchmark": "dem_seed", "n_initial": asm.n, "n_final": snaps[-1].n,
           "n_deposited": int(snaps[-1].deposited.sum()),
           "growth_layers": int(snaps[-1].layer.max()) + 1 - asm.n_layers,
           "steps": snaps[-1].step, "speed_m_s": args.speed, "throw_m": snaps[-1].throw_m,
           "settle_wall_s": round(t1 - t0, 2), "settle_cpu_s": round(c1 - c0, 2),
           "fault_wall_s": round(t2 - t1, 2), "fault_cpu_s": round(c2 - c1, 2),
           "total_wall_s": round(t2 - t0, 2), "total_cpu_s": round(c2 - c0, 2),
           "peak_rss_mib": round(peak_mib, 1), "cached_pack": args.cache_dir is not None}
    return finish(res, snaps, args, f"demseis DEM: {args.dip:.0f} deg normal fault, "
                  f"{asm.n} elements, 48 layers")


if __name__ == "__main__":
    raise SystemExit(main())
