"""Shape measures of line and band masks: length, thickness, closed loops and flat "rungs".

Diagnostics of fault labels (benchmarks, tests, the generator's run statistics); no label
depends on them.
"""

from __future__ import annotations

import numpy as np
from scipy import ndimage

from demseis.labels.direction import DIRECTION_WINDOW, dip_of, local_direction
from demseis.labels.masks import skeletonize


def skeleton_length_cells(skel: np.ndarray) -> float:
    """Length (cells) of a one-cell-wide skeleton: sum of its 8-neighbour links, each once.

    Side links are counted only where they do not close a diagonal short-cut (a 2x2 L of
    three cells counts two side links, not a side and a diagonal).
    """
    s = np.asarray(skel, dtype=bool)
    side = (s[:, 1:] & s[:, :-1]).sum() + (s[1:, :] & s[:-1, :]).sum()
    # diagonals that are not bridged by a side path through a third cell
    d1 = s[1:, 1:] & s[:-1, :-1] & ~s[:-1, 1:] & ~s[1:, :-1]
    d2 = s[1:, :-1] & s[:-1, 1:] & ~s[:-1, :-1] & ~s[1:, 1:]
    return float(side) + np.sqrt(2.0) * float(d1.sum() + d2.sum())


def mask_thickness_cells(mask: np.ndarray) -> float:
    """Mean thickness of a banded mask in cells: area / centre-line length.

    The centre line is the Guo-Hall skeleton; its length sums the links between 8-connected
    skeleton cells (1 for side neighbours, sqrt 2 for diagonal ones, each link once). Returns
    NaN for an empty mask.
    """
    mask = np.asarray(mask, dtype=bool)
    if not mask.any():
        return float("nan")
    dist = ndimage.distance_transform_edt(mask)
    pad = int(np.ceil(dist.max())) + 2
    skel = skeletonize(np.pad(mask, pad, mode="edge"))[pad:-pad, pad:-pad]
    length = skeleton_length_cells(skel)
    if length <= 0:
        return float(mask.sum())
    return float(mask.sum()) / length


def loop_count(skel: np.ndarray) -> int:
    """Number of closed loops of a line mask: background regions it encloses (4-connected)."""
    s = np.asarray(skel, dtype=bool)
    holes = ndimage.binary_fill_holes(s) & ~s
    return int(ndimage.label(holes)[1])


def rung_fraction(skel: np.ndarray, window: int = DIRECTION_WINDOW, max_deg: float = 12.0) -> float:
    """Share of skeleton cells whose direction fitted over ``window`` x ``window`` is within
    ``max_deg`` of horizontal (flat "rungs" between two traces). NaN for an empty skeleton."""
    s = np.asarray(skel, dtype=bool)
    if not s.any():
        return float("nan")
    t_r, t_c = local_direction(s, window)
    return float((dip_of(t_r, t_c)[s] <= max_deg).mean())
