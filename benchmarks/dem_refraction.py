"""Fault refraction through a strong-weak alternation (seed scale, brittle cover).

Usage::

    NUMBA_NUM_THREADS=1 python benchmarks/dem_refraction.py [--contrast 9] [--unit-layers 2]
        [--base-cohesion N] [--bond-strain R0] [--weak-kn F] [--weak-friction MU]
        [--seed S] [--width M] [--fault-x M] [--throw M] [--save FILE.npz] [--figure FILE.png]

5 km x 2.77 km, 24 layers in units of ``--unit-layers`` layers alternating sandstone (strong,
first at the base) and shale (weak) (:func:`demseis.dem.strata.alternation`), a 45 deg
basement normal fault at ``--fault-x`` (default mid-width) with ``--throw`` (450 m), 6
snapshots. The base material is :data:`demseis.dem.BRITTLE` with cohesion ``--base-cohesion``
(default ``BRITTLE.cohesion_n / 3``, so that with the default contrast 9 the strong layers get
exactly BRITTLE's 1.4e9 N) and the layers' materials come from
:func:`demseis.dem.strata.layer_materials` with ``--contrast``; ``--weak-kn`` (a fraction of the
base Kn) and ``--weak-friction`` override the weak layers' stiffness and friction.

On every snapshot each unit's fault dip is fitted in reference coordinates
(:func:`demseis_dev.measure.unit_dips`: the line that best splits the displacement field,
traced up from the basement) and the strong and weak units' mean dips (folded to 0..90 deg,
:func:`demseis_dev.measure.strong_weak_dips`) are compared. Prints ONE JSON line.
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from _dem_common import finish  # noqa: E402  (benchmarks/ is on sys.path)

from demseis.dem import BRITTLE, NormalFault, build_assembly, settle_pack, simulate  # noqa
from demseis.dem.strata import alternation, is_strong, layer_materials  # noqa
from demseis_dev.measure import strong_weak_dips  # noqa

W, H, N_LAYERS, THROW = 5000.0, 2770.0, 24, 450.0


def main(argv=None) -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--contrast", type=float, default=9.0)
    ap.add_argument("--unit-layers", type=int, default=2)
    ap.add_argument("--base-cohesion", type=float, default=BRITTLE.cohesion_n / 3)
    ap.add_argument("--bond-strain", type=float, default=BRITTLE.bond_strain)
    ap.add_argument("--weak-kn", type=float, default=None,
                    help="override: weak-layer Kn as a fraction of the base Kn")
    ap.add_argument("--weak-friction", type=float, default=None,
                    help="override: weak-layer friction coefficient")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--width", type=float, default=W)
    ap.add_argument("--fault-x", type=float, default=None, help="default: half the width")
    ap.add_argument("--throw", type=float, default=THROW)
    ap.add_argument("--save", default=None)
    ap.add_argument("--figure", default=None)
    args = ap.parse_args(argv)
    u = args.unit_layers
    lith = alternation(N_LAYERS, u)
    base = dataclasses.replace(BRITTLE, cohesion_n=args.base_cohesion,
                               bond_strain=args.bond_strain)
    mats = layer_materials(lith, base, args.contrast)
    for k, name in enumerate(lith):
        if not is_strong(name) and args.weak_kn is not None:
            mats[k] = dataclasses.replace(mats[k], kn_n_m=base.kn_n_m * args.weak_kn)
        if not is_strong(name) and args.weak_friction is not None:
            mats[k] = dataclasses.replace(mats[k], friction=args.weak_friction)
    weak = mats[lith.index("shale")]
    t0 = time.process_time()
    x_f = args.width / 2 if args.fault_x is None else args.fault_x
    pack = settle_pack(args.width, H, rng=args.seed)
    asm = build_assembly(args.width, H, n_layers=N_LAYERS, pack=pack)
    snaps = simulate(asm, NormalFault(x_m=x_f, throw_m=args.throw), base, n_snapshots=6,
                     rng=args.seed, layer_materials=mats)
    units = [tuple(range(f, min(f + u, N_LAYERS))) for f in range(0, N_LAYERS, u)]
    strong = np.array([is_strong(lith[un[0]]) for un in units])
    per_snap = []
    for snap in snaps[1:]:
        d_strong, d_weak, angle = strong_weak_dips(snaps[0], snap, units, strong, x_f)
        per_snap.append({"throw_m": round(float(snap.throw_m), 1),
                         "angles_deg": [round(float(a), 1) for a in angle],
                         "mean_dip_strong_deg": round(d_strong, 1),
                         "mean_dip_weak_deg": round(d_weak, 1),
                         "difference_deg": round(d_strong - d_weak, 1)})
    res = {"benchmark": "dem_refraction", "seed": args.seed, "contrast": args.contrast,
           "unit_layers": u, "base_cohesion_n": base.cohesion_n,
           "bond_strain": base.bond_strain, "weak_kn_frac": weak.kn_n_m / base.kn_n_m,
           "weak_friction": weak.friction, "width_m": args.width, "fault_x_m": x_f,
           "throw_m": args.throw, "strong_units": strong.astype(int).tolist(),
           **{k: per_snap[-1][k] for k in ("mean_dip_strong_deg", "mean_dip_weak_deg",
                                           "difference_deg")},
           "per_snapshot": per_snap, "cpu_s": round(time.process_time() - t0, 1)}
    return finish(res, snaps, args, f"strong/weak units of {u} layers, contrast "
                  f"{args.contrast:g}")


if __name__ == "__main__":
    raise SystemExit(main())
