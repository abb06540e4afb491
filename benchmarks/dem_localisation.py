"""How sharply does the cover fault? Horizon step across the master fault for one material.

Usage::

    NUMBA_NUM_THREADS=1 python benchmarks/dem_localisation.py [--scale quick|seed]
        [--cohesion N] [--friction MU] [--kn N/M] [--bond-strain R0] [--model frictional|bonded]
        [--speed M/S] [--save FILE.npz] [--figure FILE.png]

Runs one basement normal fault (seed: 5 km x 2.77 km, 48 layers, 45 deg, 450 m throw at
x = 2.5 km; quick: half of every length, 24 layers, 225 m throw), then measures on the final
snapshot the drop of the mid-depth horizon (layer n_layers // 2) across the best 100 m-wide
window near the fault (:func:`demseis_dev.measure.horizon_step`) and the same over 400 m.
Prints ONE JSON line with the material, the drops, their ratio to the throw, and timings.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from _dem_common import finish  # noqa: E402  (benchmarks/ is on sys.path)

from demseis.dem import Material, NormalFault, build_assembly, settle_pack, simulate  # noqa
from demseis_dev.measure import horizon_step  # noqa

SCALES = {"seed": (5000.0, 2770.0, 48, 450.0), "quick": (2500.0, 1385.0, 24, 225.0)}


def mid_horizon_step(snap, n_layers: int, height_m: float, x_m: float, dip_deg: float,
                     throw_m: float, window_m: float = 100.0) -> float:
    """Drop of the mid-depth horizon over ``window_m`` near the fault (m)."""
    y_h = 0.5 * height_m
    reach = 0.5 * y_h / math.tan(math.radians(dip_deg))
    return horizon_step(snap, n_layers // 2, x_m - reach, window_m=window_m,
                        search_m=reach + 300.0)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--scale", choices=tuple(SCALES), default="quick")
    d = Material()
    ap.add_argument("--cohesion", type=float, default=d.cohesion_n)
    ap.add_argument("--friction", type=float, default=d.friction)
    ap.add_argument("--kn", type=float, default=d.kn_n_m)
    ap.add_argument("--ks-ratio", type=float, default=d.ks_ratio)
    ap.add_argument("--bond-strain", type=float, default=d.bond_strain)
    ap.add_argument("--model", default=d.model)
    ap.add_argument("--damping", type=float, default=d.damping_scale)
    ap.add_argument("--speed", type=float, default=5.0)
    ap.add_argument("--dip", type=float, default=45.0)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--save", default=None)
    ap.add_argument("--figure", default=None)
    args = ap.parse_args(argv)
    W, H, n_layers, throw = SCALES[args.scale]
    mat = Material(kn_n_m=args.kn, ks_ratio=args.ks_ratio, friction=args.friction,
                   cohesion_n=args.cohesion, bond_strain=args.bond_strain, model=args.model,
                   damping_scale=args.damping)
    t0, c0 = time.perf_counter(), time.process_time()
    pack = settle_pack(W, H, material=Material(), rng=args.seed)
    asm = build_assembly(W, H, n_layers=n_layers, material=mat, pack=pack)
    res = {"benchmark": "dem_localisation", "scale": args.scale, "cohesion_n": mat.cohesion_n,
           "friction": mat.friction, "kn_n_m": mat.kn_n_m, "ks_ratio": mat.ks_ratio,
           "bond_strain": mat.bond_strain, "model": mat.model, "damping_scale": mat.damping_scale,
           "dip_deg": args.dip, "throw_m": throw}
    try:
        snaps = simulate(asm, NormalFault(x_m=0.5 * W, dip_deg=args.dip, throw_m=throw,
                                          speed_m_s=args.speed), mat, n_snapshots=6,
                         rng=np.random.default_rng(args.seed))
    except Exception as e:  # report instability as a result
        res.update(stable=False, error=str(e)[:300])
        print(json.dumps(res))
        return 1
    last = snaps[-1]
    s100 = mid_horizon_step(last, n_layers, H, 0.5 * W, args.dip, throw, 100.0)
    s400 = mid_horizon_step(last, n_layers, H, 0.5 * W, args.dip, throw, 400.0)
    res.update(stable=True, step_100m_m=round(s100, 1), step_400m_m=round(s400, 1),
               step_100m_over_throw=round(s100 / throw, 3),
               steps=last.step, wall_s=round(time.perf_counter() - t0, 1),
               cpu_s=round(time.process_time() - c0, 1))
    return finish(res, snaps, args, f"C0={mat.cohesion_n:.2g} N, mu={mat.friction}, "
                  f"{mat.model}: 100 m step {s100:.0f} m of {throw:.0f} m")


if __name__ == "__main__":
    raise SystemExit(main())
