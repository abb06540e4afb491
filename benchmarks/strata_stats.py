"""Statistics of the default ``strata`` stratigraphy against well-log and F3 figures; one JSON line.

Usage: ``PYTHONPATH=. python benchmarks/strata_stats.py [--seeds 4]``

For each seed, :func:`demseis_dev.strata_stats.default_setup` (48 layers over 1200 m,
5 km wide, default ``PropertyModel`` and ``BedModel``): the reflectivity of the column at
x = 1000 m (0.25 m cells; excess kurtosis in depth, of the interfaces alone and in 1 ms
two-way-time bins; spectral slope of log power vs log frequency over 10-80 Hz) and, for a flat
(undeformed) section with traces every 25 m on 0.5 m cells at 4 ms, the adjacent-trace
correlation and zero crossings per 100 samples at 20, 35 and 60 Hz. Prints the mean and the
range over seeds.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # demseis_dev: the checkout's

import numpy as np

from demseis_dev.strata_stats import (adjacent_trace_correlation, column_reflectivity,
                                      default_setup, flat_section, zero_crossings)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=4)
    args = ap.parse_args()
    rows: dict[str, list[float]] = {}
    for seed in range(args.seeds):
        s = default_setup(seed)
        for k, v in column_reflectivity(s, x_m=1000.0).items():
            rows.setdefault(k, []).append(float(v))
        for f in (20.0, 35.0, 60.0):
            sec = flat_section(s, f)
            rows.setdefault(f"corr_{f:g}hz", []).append(adjacent_trace_correlation(sec))
            rows.setdefault(f"zero_crossings_{f:g}hz", []).append(zero_crossings(sec))
    print(json.dumps({k: {"mean": round(float(np.mean(v)), 3), "min": round(min(v), 3),
                          "max": round(max(v), 3)} for k, v in rows.items()}))


if __name__ == "__main__":
    main()
