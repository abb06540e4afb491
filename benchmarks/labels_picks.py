"""The picked fault target against kinematic faults of known geometry, and its shape on DEM stores.

For each sampling (4 ms time with small throws tapering to zero, 4 ms with large throws, 10 m
depth cells), renders kinematic runs with one planar fault (dips 35-80 deg, normal and
reverse, 25 m traces) and prints one JSON line with the pooled share of label pixels within
one pixel of the true trace and of the true trace (throw >= min_throw_samples) within one
pixel of a label (demseis_dev.picks.kinematic_agreement). With --store, one more line
with the loops and rungs of every sample's labels there (shape_counts).

    PYTHONPATH=$PWD python benchmarks/labels_picks.py [--runs 8] [--store quick.zarr]
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # demseis_dev: the checkout's

import numpy as np

CASES = {"time_small_throws": ("time", (3.0, 30.0), 1.0),
         "time_large_throws": ("time", (20.0, 200.0), 0.5),
         "depth": ("depth", (5.0, 60.0), 1.0)}


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--runs", type=int, default=8)
    ap.add_argument("--store", help="a store whose labels' loops and rungs are counted")
    args = ap.parse_args(argv)
    from demseis_dev.picks import kinematic_agreement, planar_fault_sweep, shape_counts

    for name, (domain, throw, taper) in CASES.items():
        t0 = time.perf_counter()
        rows = kinematic_agreement(planar_fault_sweep(domain, throw, taper, args.runs),
                                   list(range(args.runs)))
        lab = sum(r["label_px"] for r in rows)
        vis = sum(r["visible_px"] for r in rows)
        print(json.dumps({
            "benchmark": "labels_picks", "case": name, "runs": args.runs, "samples": len(rows),
            "label_px": lab, "visible_px": vis,
            "on_trace": round(sum(r["on_trace"] * r["label_px"] for r in rows) / max(lab, 1), 4),
            "found": round(sum(r["found"] * r["visible_px"] for r in rows) / max(vis, 1), 4),
            "worst_found": round(min(r["found"] for r in rows if r["visible_px"]), 4),
            "seconds": round(time.perf_counter() - t0, 2)}))
    if args.store:
        import demseis

        store = demseis.open(args.store)
        counts = [shape_counts(s["fault"], s["fault_id"])
                  for s in (store.sample(i) for i in range(len(store.params["run_id"])))]
        print(json.dumps({
            "benchmark": "labels_picks", "case": "store_shape", "store": args.store,
            "samples": len(counts),
            "instance_loops": int(sum(c["instance_loops"] for c in counts)),
            "samples_with_a_loop_of_the_union": int(sum(c["loops"] > 0 for c in counts)),
            "max_instance_rung_fraction": float(np.max([c["instance_rung_fraction"]
                                                        for c in counts])),
            "max_rung_fraction_of_the_union": float(np.max([c["rung_fraction"]
                                                            for c in counts]))}))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
