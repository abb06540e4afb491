"""Kinematically faulted disk packs for benchmarks, figures and tests (not mechanics).

These stand in for DEM snapshots where no DEM run is at hand: a jittered hexagonal pack of
disks with radii uniform in [radius_min_m, radius_max_m] (about the seed-scale density:
10,900 disks over 5 km x 2.77 km), cut into equal horizontal layers, and a normal fault that
moves the hanging wall down-dip rigidly, with growth layers filling the accommodation at each
increment. There is no drag, no damage zone and no force balance: faulting here is geometry.
"""

from __future__ import annotations

import numpy as np

from demseis.dem.types import Snapshot


def _hex_points(x0: float, x1: float, y0: float, y1: float, spacing: float,
                rng: np.random.Generator) -> np.ndarray:
    dy = spacing * np.sqrt(3.0) / 2.0
    rows = int(np.floor((y1 - y0) / dy))
    pts = []
    for r in range(rows):
        y = y0 + (r + 0.5) * dy
        off = 0.5 * spacing if r % 2 else 0.0
        xs = np.arange(x0 + 0.25 * spacing + off, x1, spacing)
        pts.append(np.column_stack([xs, np.full(xs.size, y)]))
    p = np.concatenate(pts) if pts else np.zeros((0, 2))
    return p + rng.uniform(-0.08, 0.08, p.shape) * spacing


def layered_pack(width_m: float = 5000.0, height_m: float = 2770.0, n_layers: int = 48,
                 radius_min_m: float = 12.5, radius_max_m: float = 25.0,
                 rng: np.random.Generator | None = None) -> Snapshot:
    """An undeformed pack: hexagonal lattice (spacing 2.04 x mean radius), jittered, radii
    uniform, layers of equal thickness numbered from the base (0) up."""
    rng = np.random.default_rng(0) if rng is None else rng
    spacing = 2.04 * 0.5 * (radius_min_m + radius_max_m)
    xy = _hex_points(0.0, width_m, 0.0, height_m, spacing, rng)
    radius = rng.uniform(radius_min_m, radius_max_m, xy.shape[0])
    layer = np.minimum((xy[:, 1] / height_m * n_layers).astype(np.int64), n_layers - 1)
    n = xy.shape[0]
    return Snapshot(0, 0, 0.0, np.arange(n, dtype=np.int64), xy, radius,
                       layer.astype(np.int16), np.zeros(n, dtype=bool))


def faulted_sequence(width_m: float = 5000.0, height_m: float = 2770.0, n_layers: int = 48,
                     throw_m: float = 450.0, dip_deg: float = 60.0, x_fault_m: float | None = None,
                     n_snapshots: int = 6, radius_min_m: float = 12.5, radius_max_m: float = 25.0,
                     rng: np.random.Generator | None = None) -> list[Snapshot]:
    """Snapshots of a pack cut by a right-dipping normal fault at throws ``k/(n-1) throw_m``.

    The fault passes through ``(x_fault_m, 0)`` (default 0.6 width) and dips right at
    ``dip_deg`` (it reaches the surface at ``x_fault_m - height_m / tan(dip)``); at every
    increment the hanging wall (all elements right of the fault, growth strata included) moves
    down-dip by the throw increment, and the accommodation below the initial surface is filled
    with a new growth layer (index ``n_layers + k - 1``, ``deposited=True``, new ids).
    """
    rng = np.random.default_rng(0) if rng is None else rng
    x_fault_m = 0.6 * width_m if x_fault_m is None else x_fault_m
    base = layered_pack(width_m, height_m, n_layers, radius_min_m, radius_max_m, rng)
    tan = np.tan(np.radians(dip_deg))
    spacing = 2.04 * 0.5 * (radius_min_m + radius_max_m)
    ids, xy, radius, layer, dep = (base.ids, base.xy.copy(), base.radius, base.layer,
                                   base.deposited)
    # hanging-wall membership is decided once, in the undeformed state, and moves with it
    hanging = xy[:, 0] > x_fault_m - xy[:, 1] / tan
    snaps = [Snapshot(0, 0, 0.0, ids, xy.copy(), radius, layer, dep)]
    done = 0.0
    next_id = int(ids.max()) + 1
    for k in range(1, n_snapshots):
        target = k / (n_snapshots - 1) * throw_m
        d = target - done
        done = target
        xy[hanging] += np.array([d / tan, -d])
        # fill the hanging-wall accommodation between the subsided surface and the datum
        # (the column below moved down by d, so the new space is the top d of the box)
        new = _hex_points(0.0, width_m, height_m - d, height_m, spacing, rng)
        new = new[new[:, 0] > x_fault_m - new[:, 1] / tan + 0.5 * spacing]
        m = new.shape[0]
        if m:
            ids = np.concatenate([ids, np.arange(next_id, next_id + m, dtype=np.int64)])
            next_id += m
            xy = np.concatenate([xy, new])
            radius = np.concatenate([radius, rng.uniform(radius_min_m, radius_max_m, m)])
            layer = np.concatenate([layer, np.full(m, n_layers + k - 1, dtype=np.int16)])
            dep = np.concatenate([dep, np.ones(m, dtype=bool)])
            hanging = np.concatenate([hanging, np.ones(m, dtype=bool)])
        snaps.append(Snapshot(k, 0, target, ids, xy.copy(), radius, layer, dep))
    return snaps
