"""Milliseconds per rendered snapshot/section of the seismic stage; prints one JSON line.

Usage: ``PYTHONPATH=. python benchmarks/seismic_render.py [--nx 512 --nz 288 --repeats 7]``
(the same measurement as ``python -m demseis_dev.bench seismic``). Set NUMBA_NUM_THREADS=1 to match the
sweep's workers; the kernels are serial anyway.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # demseis_dev: the checkout's

from demseis_dev.bench import seismic_benchmark as run_benchmark


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__)
    p.add_argument("--nx", type=int, default=512)
    p.add_argument("--nz", type=int, default=288)
    p.add_argument("--repeats", type=int, default=7)
    p.add_argument("--npz", default=None, help="snapshots .npz (e.g. from a DEM run)")
    a = p.parse_args()
    print(json.dumps(run_benchmark(nx=a.nx, nz=a.nz, repeats=a.repeats, npz=a.npz)))


if __name__ == "__main__":
    main()
