"""The fault core: the shear band's width at half maximum around the traces (step 5 of
:mod:`demseis.labels.traces`; ``damage`` class 2 of the targets)."""

from __future__ import annotations

import numpy as np
from scipy import ndimage

from demseis.labels.direction import DIRECTION_WINDOW, along_trace_mean
from demseis.labels.masks import fill_small_holes


#: Gaussian sigma (cells) of the displacement smoothing of the band-core field
CORE_SIGMA_CELLS = 0.7

#: the shortest core extent (cells, mean along the trace) on one side of a trace: a sharp
#: step reaches 1, and 2-3 where its raster steps around a grain
CORE_MIN_EXTENT_CELLS = 2.0

#: rounding tolerance (cells) of the core's comparisons (a box mean of extents is not exact)
_TOL = 1e-9

#: holes of at most this many cells inside the core are core (the gaps between the strands
#: of one band)
CORE_HOLE_CELLS = 12

#: a cell next to a trace is band core where its fine shear strain is at least this share of
#: the crest's (half maximum: the band's full width at half maximum)
CORE_FRACTION = 0.5


def band_core(trace: np.ndarray, t_r: np.ndarray, t_c: np.ndarray, field: np.ndarray,
              rock: np.ndarray, cohort: np.ndarray | None, max_halfwidth: int,
              fraction: float = CORE_FRACTION, hole_cells: int = CORE_HOLE_CELLS) -> np.ndarray:
    """The core of the shear band around the traces: the band's width at half maximum.

    1. **Extent.** From every trace cell p, with unit tangent (t_r, t_c) and normal
       n = (t_c, -t_r), the cells p + k n (k = 1..``max_halfwidth``, rounded to the nearest
       cell) are read on either side while they are rock of p's cohort; the side's extent is
       the largest such k where ``field`` is at least ``fraction`` of the crest value (the
       largest of ``field`` at p and p +- n), 0 if none. A granular band slips on several
       grain boundaries, so its shear dips between them: the extent is the band's outer
       half-maximum, not its first dip.
    2. **Along the trace.** Each side's extent is averaged over the trace cells in a
       DIRECTION_WINDOW-square box (the extents of neighbouring cells differ by the grain
       stepping); a mean below CORE_MIN_EXTENT_CELLS is 0.
    3. **Cells.** A cell within ``max_halfwidth`` + 0.5 of a trace, rock of the cohort of its
       nearest trace cell q, is core when its offset along q's normal lies within q's extent
       on that side + 0.5 cell. Holes of at most ``hole_cells`` cells in the result are
       filled (rock cells only): the gaps between the strands of one band.

    A slip surface as sharp as the grid (``field`` a Gaussian of sigma ``CORE_SIGMA_CELLS``
    across it) has a half-maximum one cell to one side (2-3 cells where its raster steps
    around a grain), below CORE_MIN_EXTENT_CELLS along the trace: its core is the trace. A
    band at least 5 cells wide keeps its width, up to 2 ``max_halfwidth`` + 1 cells.

    Returns
    -------
    (nz, nx) bool: the trace cells and their core cells.
    """
    trace = np.asarray(trace, dtype=bool)
    core = trace.copy()
    if max_halfwidth <= 0 or not trace.any():
        return core
    nz, nx = trace.shape
    rows, cols = np.nonzero(trace)
    n_r, n_c = t_c[rows, cols], -t_r[rows, cols]
    coh = np.zeros(trace.shape, np.int64) if cohort is None else np.asarray(cohort)

    def at(k: float) -> tuple[np.ndarray, np.ndarray]:
        r = np.clip(np.rint(rows + k * n_r).astype(np.int64), 0, nz - 1)
        c = np.clip(np.rint(cols + k * n_c).astype(np.int64), 0, nx - 1)
        return r, c

    crest = field[rows, cols]
    for k in (-1.0, 1.0):
        crest = np.maximum(crest, field[at(k)])
    level = fraction * crest
    extent = {}
    for side in (-1.0, 1.0):
        alive = crest > 0
        last = np.zeros(rows.size)
        for k in range(1, int(max_halfwidth) + 1):
            r, c = at(side * k)
            alive &= rock[r, c] & (coh[r, c] == coh[rows, cols])
            last = np.where(alive & (field[r, c] >= level), float(k), last)
        on_trace = np.zeros(trace.shape)
        on_trace[rows, cols] = last
        mean = along_trace_mean(trace, on_trace, trace, DIRECTION_WINDOW)
        # a step as sharp as the grid is a half-maximum 1 cell wide on one side (the two
        # cells of the step), and its raster follows the grains 1-2 cells either side of
        # the surface: only a band wider than that along the trace has a core
        extent[side] = np.where(mean >= CORE_MIN_EXTENT_CELLS - _TOL, mean, 0.0)
    dist, idx = ndimage.distance_transform_edt(~trace, return_indices=True)
    near = (dist > 0) & (dist <= max_halfwidth + 0.5) & rock
    near &= coh == coh[idx[0], idx[1]]
    r, c = np.nonzero(near)
    qr, qc = idx[0][r, c], idx[1][r, c]
    off = (r - qr) * t_c[qr, qc] - (c - qc) * t_r[qr, qc]
    reach = np.where(off >= 0, extent[1.0][qr, qc], extent[-1.0][qr, qc])
    keep = np.abs(off) <= reach + 0.5 + _TOL
    core[r[keep], c[keep]] = True
    return fill_small_holes(core, hole_cells, rock)
