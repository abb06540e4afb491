"""Speed of the labels stage on a seed-scale-sized synthetic model (no DEM needed)."""

from __future__ import annotations

import time

import numpy as np


def _snapshots(n_snapshots: int, seed: int):
    from demseis.dem.types import Snapshot
    from demseis.labels.synthetic import disk_pack, kinematic_fault

    xy, r = disk_pack(5000.0, 2770.0, np.random.default_rng(seed), packing_fraction=0.88)
    n = xy.shape[0]
    layer = np.minimum(xy[:, 1] // (2770.0 / 48), 47).astype(np.int16)
    snaps = []
    for k in range(n_snapshots):
        slip = 450.0 / np.sin(np.radians(45.0)) * k / max(n_snapshots - 1, 1)
        cur = kinematic_fault(xy, x_m=2500.0, dip_deg=45.0, slip_m=0.6 * slip,
                              zone_width_m=200.0)
        cur = kinematic_fault(cur, x_m=2500.0, dip_deg=45.0, slip_m=0.4 * slip)
        snaps.append(Snapshot(k, 100 * k, 450.0 * k / max(n_snapshots - 1, 1),
                              np.arange(n, dtype=np.int64), cur, r, layer, np.zeros(n, bool)))
    return snaps


def run_benchmark(n_snapshots: int = 6, repeats: int = 5, seed: int = 0) -> dict:
    """Median wall times of :func:`strain_history` and of :func:`label_maps` per snapshot.

    Returns a dict ready for one JSON line.
    """
    from demseis.labels import LabelConfig, label_maps, strain_history
    from demseis.seismic.grid import Grid

    snaps = _snapshots(n_snapshots, seed)
    cfg = LabelConfig()
    grid = Grid.covering(5000.0, 2770.0, 10.0)
    from demseis.labels.traces import displacement_history

    hist = strain_history(snaps[:2], cfg)  # JIT warm-up
    label_maps(snaps[1], hist[1], grid, cfg, displacement=displacement_history(snaps[:2])[1])
    t_hist, t_maps = [], []
    for _ in range(repeats):
        t0 = time.perf_counter()
        hist = strain_history(snaps, cfg)
        t_hist.append(time.perf_counter() - t0)
        t0 = time.perf_counter()
        for s, h, d in zip(snaps, hist, displacement_history(snaps)):
            label_maps(s, h, grid, cfg, displacement=d)
        t_maps.append((time.perf_counter() - t0) / len(snaps))
    return {
        "benchmark": "labels",
        "n_elements": int(snaps[0].n),
        "n_snapshots": n_snapshots,
        "grid": list(grid.shape),
        "strain_history_s_median": round(float(np.median(t_hist)), 4),
        "label_maps_s_per_snapshot_median": round(float(np.median(t_maps)), 4),
        "repeats": repeats,
    }
