"""Brute-force geometry that the DEM tests check deposits against."""

from __future__ import annotations

import numpy as np


def overlaps(a_xy: np.ndarray, a_r: np.ndarray, b_xy: np.ndarray, b_r: np.ndarray) -> np.ndarray:
    """(m, n) overlap (m) of every disk of ``a`` with every disk of ``b``; < 0 is a gap."""
    d = np.hypot(a_xy[:, None, 0] - b_xy[None, :, 0], a_xy[:, None, 1] - b_xy[None, :, 1])
    return a_r[:, None] + b_r[None, :] - d


def pair_overlaps(xy: np.ndarray, r: np.ndarray) -> np.ndarray:
    """Overlap (m) of every pair i < j of the disks ``xy, r``."""
    return overlaps(xy, r, xy, r)[np.triu_indices(r.size, 1)]
