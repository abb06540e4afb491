"""Local geometry of one-cell-wide line masks: tangent, dip and means along the line.

The tangent of a line cell is the principal axis of the line cells in a box around it
(:func:`local_direction`); the box filters behind it and :func:`along_trace_mean` run on the
mask's bounding box only (:func:`box_support`), with the same bits as on the whole grid.
"""

from __future__ import annotations

import numpy as np
from scipy import ndimage


#: window (cells) over which a trace's local direction is fitted (also the rung definition)
DIRECTION_WINDOW = 9


def local_direction(skel: np.ndarray, window: int = DIRECTION_WINDOW) -> tuple[np.ndarray, np.ndarray]:
    """Unit tangent (row, col) of a line mask, fitted over a ``window`` x ``window`` box.

    Principal axis of the coordinates of the mask cells in the box centred on each cell (the
    box sums are box filters of the cell moments). Values off the mask are meaningless (the
    filters run on the mask's bounding box only, see :func:`box_support`; (1, 0) outside it).
    """
    s_full = np.asarray(skel, dtype=np.float64)
    t_r = np.ones(s_full.shape)
    t_c = np.zeros(s_full.shape)
    box_sl = box_support(s_full != 0, window)
    if box_sl is None:
        return t_r, t_c
    s = s_full[box_sl]
    rr, cc = np.mgrid[box_sl].astype(np.float64)  # absolute coordinates, as on the whole grid

    def box(a: np.ndarray) -> np.ndarray:
        return ndimage.uniform_filter(a, size=window, mode="constant") * window * window

    n = np.maximum(box(s), 1e-12)
    mr, mc = box(s * rr) / n, box(s * cc) / n
    crr = box(s * rr * rr) / n - mr * mr
    ccc = box(s * cc * cc) / n - mc * mc
    crc = box(s * rr * cc) / n - mr * mc
    phi = 0.5 * np.arctan2(2.0 * crc, crr - ccc)  # angle of the major axis from the row axis
    t_r[box_sl] = np.cos(phi)
    t_c[box_sl] = np.sin(phi)
    return t_r, t_c


def dip_of(t_row: np.ndarray, t_col: np.ndarray) -> np.ndarray:
    """Dip (degrees from horizontal, 0..90) of a tangent (row, col) on square cells."""
    return np.degrees(np.arctan2(np.abs(t_row), np.abs(t_col)))


def along_trace_mean(cells: np.ndarray, values: np.ndarray, ok: np.ndarray,
                      size: int = 5) -> np.ndarray:
    """Mean of ``values`` over the ``ok`` cells of ``cells`` in a size x size box (NaN if none;
    the value at a cell of ``cells`` is exact, elsewhere it may be NaN: see :func:`box_support`)."""
    m = cells & ok
    out = np.full(cells.shape, np.nan)
    box_sl = box_support(m, size)
    if box_sl is None:
        return out
    w = m[box_sl].astype(np.float64)
    num = ndimage.uniform_filter(values[box_sl] * w, size=size, mode="constant")
    den = ndimage.uniform_filter(w, size=size, mode="constant")
    with np.errstate(invalid="ignore", divide="ignore"):
        out[box_sl] = np.where(den > 1e-9, num / np.maximum(den, 1e-12), np.nan)
    return out


def box_support(mask: np.ndarray, size: int) -> tuple[slice, slice] | None:
    """Bounding box of ``mask`` grown by ``size // 2 + 1`` cells (clipped to the grid); None
    if the mask is empty.

    A box filter (``ndimage.uniform_filter``, mode "constant" 0) of an array that is 0 off
    the mask gives, inside this box, the same bits as on the whole grid: scipy runs a sum
    along each line, and the box starts where the running sum is still exactly 0 (its window
    holds only zeros) and ends after the last non-zero input, so every value inside sees the
    same additions in the same order. (Only the values at mask cells are used: outside the
    mask but inside the box they are the same too.)
    """
    rows = np.flatnonzero(mask.any(axis=1))
    if rows.size == 0:
        return None
    cols = np.flatnonzero(mask.any(axis=0))
    m = size // 2 + 1
    return (slice(max(int(rows[0]) - m, 0), min(int(rows[-1]) + m + 1, mask.shape[0])),
            slice(max(int(cols[0]) - m, 0), min(int(cols[-1]) + m + 1, mask.shape[1])))
