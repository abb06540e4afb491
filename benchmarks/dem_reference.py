"""Speed and smoothness of the reference-coordinate map (demseis.dem.reference).

1. The last snapshot of ``quick`` run 0 (about 2,000 elements, DEM run here: tens of seconds),
   250 columns x 1 m vertical sampling over the model box: time of ``element_maps`` and
   ``reference_coordinates`` (best of ``--repeat``, after compilation), fraction of points
   inside the assembly, and on horizontal lines every 100 m (1 m spacing) the kinks of
   reference y, |second difference| over three samples of one cohort (fraction over 0.1 m,
   90th and 99th percentiles; faults included), against the owner element's translation alone.
2. A paper-size faulted disk pack (5 km x 2.77 km, about 10,000 elements, kinematic 60 deg
   fault with 100 m slip) and about 1e6 points (500 columns x 1.4 m): the same timings, and
   the largest error against the exact reference.

    NUMBA_NUM_THREADS=1 python benchmarks/dem_reference.py [--repeat 3] [--skip-dem]

Prints ONE JSON line.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # demseis_dev: the checkout's

import numpy as np

from demseis.dem import element_maps, reference_coordinates
from demseis.labels import displacement_history
from demseis_dev.toys import disk_pack, down_dip_vector, fault_signed_distance, kinematic_fault


def _columns(width, height, n_cols, dz):
    xs = np.linspace(0.0, width, n_cols)
    ys = np.arange(0.0, height, dz)
    return np.column_stack([np.repeat(xs, ys.size), np.tile(ys, xs.size)])


def _timed(ref, cur, r, pts, repeat, group=None):
    maps = element_maps(ref[:50], cur[:50], r[:50])          # compile (or load the cache)
    reference_coordinates(cur[:50], r[:50], maps, pts[:10])
    t_maps = t_pts = np.inf
    for _ in range(repeat):
        t0 = time.perf_counter()
        maps = element_maps(ref, cur, r, group=group)
        t1 = time.perf_counter()
        out, owner = reference_coordinates(cur, r, maps, pts, group=group, return_element=True)
        t2 = time.perf_counter()
        t_maps, t_pts = min(t_maps, t1 - t0), min(t_pts, t2 - t1)
    return maps, out, owner, round(t_maps, 4), round(t_pts, 4)


def quick_dem(repeat):
    from demseis.generator.config.sampling import plan_run
    from demseis.generator.config.settings import load_config
    from demseis.generator.engines import get_engine

    cfg = load_config(None, preset="quick")
    snaps = list(get_engine("dem").simulate(cfg, plan_run(cfg, 0)).snapshots)
    s = snaps[-1]
    disp, birth = displacement_history(snaps)[-1]
    cur = np.asarray(s.xy, dtype=np.float64)
    w, h = cfg.model.width_m, cfg.model.height_m
    pts = _columns(w, h, 250, 1.0)
    maps, _, own, t_maps, t_pts = _timed(cur - disp, cur, s.radius, pts, repeat, group=birth)
    x = np.arange(0.0, w, 1.0)
    steps, steps_nearest = [], []
    for y in np.arange(100.0, h - 100.0, 100.0):
        line = np.column_stack([x, np.full_like(x, y)])
        ref, o = reference_coordinates(cur, s.radius, maps, line, group=birth,
                                       return_element=True)
        ok = o >= 0
        near = y - disp[np.maximum(o, 0), 1]
        # kinks: second differences over three samples of one cohort (a tilted bed has a
        # first difference, a step at an element boundary has a second one)
        b = np.where(ok, birth[np.maximum(o, 0)], -1)
        same = ok[2:] & (b[2:] == b[1:-1]) & (b[1:-1] == b[:-2])
        steps.append(np.abs(np.diff(ref[:, 1], 2))[same])
        steps_nearest.append(np.abs(np.diff(near, 2))[same])
    steps = np.concatenate(steps)
    steps_nearest = np.concatenate(steps_nearest)
    return {"elements": int(s.n), "points": int(pts.shape[0]), "throw_m": float(s.throw_m),
            "element_maps_s": t_maps, "reference_coordinates_s": t_pts,
            "inside_fraction": round(float((own >= 0).mean()), 4),
            "line_kinks_over_0.1_m": round(float((steps > 0.1).mean()), 4),
            "line_kinks_nearest_over_0.1_m": round(float((steps_nearest > 0.1).mean()), 4),
            "line_kink_p90_p99_m": [round(float(np.percentile(steps, q)), 3) for q in (90, 99)],
            "line_kink_nearest_p90_p99_m": [round(float(np.percentile(steps_nearest, q)), 3)
                                            for q in (90, 99)]}


def paper_pack(repeat):
    w, h = 5000.0, 2770.0
    xy, r = disk_pack(w, h, np.random.default_rng(0))
    cur = kinematic_fault(xy, x_m=w / 2, dip_deg=60.0, slip_m=100.0)
    pts = _columns(w, h, 500, 1.4)
    _, out, own, t_maps, t_pts = _timed(xy, cur, r, pts, repeat)
    inside = own >= 0
    truth = np.where((fault_signed_distance(pts, w / 2, 60.0) > 0)[:, None],
                     pts - 100.0 * down_dip_vector(60.0), pts)
    far = inside & (np.abs(fault_signed_distance(pts, w / 2, 60.0)) > 2 * r.max())
    return {"elements": int(xy.shape[0]), "points": int(pts.shape[0]),
            "element_maps_s": t_maps, "reference_coordinates_s": t_pts,
            "max_error_beyond_one_diameter_m": float(np.abs(out[far] - truth[far]).max())}


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--skip-dem", action="store_true", help="only the disk-pack case")
    a = ap.parse_args()
    out = {"paper_pack": paper_pack(a.repeat)}
    if not a.skip_dem:
        out["quick_run0_last"] = quick_dem(a.repeat)
    print(json.dumps(out))


if __name__ == "__main__":
    main()
