"""Helpers shared by the slip-trace tests: kinematic faults on a 2000 m x 1000 m section of
10 m cells, labelled from the displacement between two snapshots."""

from __future__ import annotations

import numpy as np

from demseis.labels import LabelConfig, displacement_history, label_maps, strain_history
from demseis.types import Grid, Snapshot
from demseis_dev.toys import fault_signed_distance

W, H, XF, CELL = 2000.0, 1000.0, 1200.0, 10.0


def snap_of(xy, r, index):
    n = xy.shape[0]
    return Snapshot(index, index, 0.0, np.arange(n, dtype=np.int64), xy, r,
                    np.zeros(n, np.int16), np.zeros(n, bool))


def labels_of(xy, cur, r, config=None, grid=None):
    grid = grid or Grid.covering(W, H, CELL)
    cfg = config or LabelConfig()
    snaps = [snap_of(xy, r, 0), snap_of(cur, r, 1)]
    hist = strain_history(snaps, cfg)
    disp = displacement_history(snaps)
    return label_maps(snaps[1], hist[1], grid, cfg, displacement=disp[1]), grid


def centres(grid):
    zz, xx = np.meshgrid(grid.y_centres(), grid.x_centres(), indexing="ij")
    return xx, zz


def planar_line(grid, dip, x_m=XF, direction="right"):
    """(distance of every cell centre to the plane in cells, rasterised trace)."""
    xx, zz = centres(grid)
    d = np.abs(fault_signed_distance(np.column_stack([xx.ravel(), zz.ravel()]), x_m, dip,
                                     direction)).reshape(xx.shape) / grid.cell_m
    th = np.radians(dip)
    half = 0.5 * (abs(np.cos(th)) + abs(np.sin(th)))
    return d, d <= half
