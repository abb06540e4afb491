"""Biaxial calibration of a Material: bulk friction angle and cohesion (Mohr-Coulomb fit).

Usage::

    NUMBA_NUM_THREADS=1 python benchmarks/dem_biaxial.py [--cohesion C0] [--friction MU]
        [--sigma3 5e6 10e6 20e6] [--rate 0.001] [--max-strain 0.15]

Prints ONE JSON line: peak sigma1 per confinement, the fitted friction angle (deg) and
cohesion (Pa). Sample: a settled 400 m x 800 m pack (radii 12.5-25 m, ~240 disks), gravity off,
servo side walls at sigma3, top wall at a constant axial strain rate.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from demseis.dem import Material  # noqa: E402
from demseis_dev.calibrate import biaxial_test, mohr_coulomb_fit  # noqa: E402


def main(argv=None) -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--cohesion", type=float, default=Material().cohesion_n)
    ap.add_argument("--friction", type=float, default=Material().friction)
    ap.add_argument("--sigma3", type=float, nargs="+", default=[5e6, 10e6, 20e6])
    ap.add_argument("--rate", type=float, default=0.001)
    ap.add_argument("--max-strain", type=float, default=0.15)
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args(argv)
    mat = Material(cohesion_n=args.cohesion, friction=args.friction)
    runs = [biaxial_test(mat, s3, strain_rate_s=args.rate, max_axial_strain=args.max_strain,
                         seed=args.seed) for s3 in args.sigma3]
    phi, c = mohr_coulomb_fit([r["sigma3_pa"] for r in runs], [r["peak_sigma1_pa"] for r in runs])
    print(json.dumps({"benchmark": "dem_biaxial", "cohesion_n": args.cohesion,
                      "friction": args.friction, "n": runs[0]["n"],
                      "sigma3_pa": args.sigma3,
                      "peak_sigma1_pa": [r["peak_sigma1_pa"] for r in runs],
                      "axial_strain_at_peak": [r["axial_strain_at_peak"] for r in runs],
                      "friction_angle_deg": phi, "cohesion_pa": c}))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
