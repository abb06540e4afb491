"""Fault refraction through a strong-weak alternation (seed scale, brittle cover).

Usage::

    NUMBA_NUM_THREADS=1 python benchmarks/dem_refraction.py [--contrast 9] [--unit-layers 2]
        [--base-cohesion N]
        [--save FILE.npz] [--figure FILE.png]

5 km x 2.77 km, 24 layers grouped in units of ``--unit-layers`` layers alternating sandstone
(strong) and shale (weak) from the base, :data:`demseis.dem.BRITTLE` (cohesion ``--base-cohesion``) as the base material and
:func:`demseis.dem.strata.layer_materials` with ``--contrast``; 45 deg basement fault, 450 m
throw. On the final snapshot the master fault is located on every layer's horizon (centre of
the 100 m window with the largest drop, :func:`demseis.dem.measure.fault_crossings`); the dip
of the least-squares line through the crossings of one unit's horizons is that unit's dip.
Prints ONE JSON line: mean dip in strong and weak units and their difference.
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from demseis.dem import BRITTLE, NormalFault, build_assembly, settle_pack, simulate  # noqa
from demseis.dem.measure import unit_dips  # noqa
from demseis.dem.strata import is_strong, layer_materials  # noqa
from _dem_common import finish  # noqa: E402  (benchmarks/ is on sys.path)

W, H, N_LAYERS, THROW = 5000.0, 2770.0, 24, 450.0


def main(argv=None) -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--contrast", type=float, default=9.0)
    ap.add_argument("--unit-layers", type=int, default=2)
    ap.add_argument("--base-cohesion", type=float, default=BRITTLE.cohesion_n)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--save", default=None)
    ap.add_argument("--figure", default=None)
    args = ap.parse_args(argv)
    u = args.unit_layers
    lith = [("sandstone" if (k // u) % 2 == 0 else "shale") for k in range(N_LAYERS)]
    import dataclasses

    base = dataclasses.replace(BRITTLE, cohesion_n=args.base_cohesion)
    mats = layer_materials(lith, base, args.contrast)
    t0 = time.process_time()
    pack = settle_pack(W, H, rng=args.seed)
    asm = build_assembly(W, H, n_layers=N_LAYERS, pack=pack)
    snaps = simulate(asm, NormalFault(), base, n_snapshots=6, rng=args.seed,
                     layer_materials=mats)
    units = [tuple(range(f, min(f + u, N_LAYERS))) for f in range(0, N_LAYERS, u)]
    strong = np.array([is_strong(lith[un[0]]) for un in units])
    per_snap = []
    for snap in snaps[1:]:
        dip, _, mis = unit_dips(snaps[0], snap, units, W / 2)
        ok = np.isfinite(dip)
        per_snap.append({"throw_m": round(float(snap.throw_m), 1),
                         "dips_deg": [round(float(d), 1) for d in dip],
                         "misfit": [round(float(m), 2) for m in mis],
                         "mean_strong_deg": round(float(np.mean(dip[ok & strong])), 1),
                         "mean_weak_deg": round(float(np.mean(dip[ok & ~strong])), 1)})
    last = per_snap[-1]
    res = {"benchmark": "dem_refraction", "contrast": args.contrast, "unit_layers": u,
           "base_cohesion_n": base.cohesion_n, "strong_units": strong.astype(int).tolist(),
           "mean_dip_strong_deg": last["mean_strong_deg"],
           "mean_dip_weak_deg": last["mean_weak_deg"],
           "per_snapshot": per_snap,
           "cpu_s": round(time.process_time() - t0, 1)}
    res["difference_deg"] = round(res["mean_dip_strong_deg"] - res["mean_dip_weak_deg"], 1)
    return finish(res, snaps, args, f"strong/weak units of {u} layers, contrast "
                  f"{args.contrast:g}")


if __name__ == "__main__":
    raise SystemExit(main())
