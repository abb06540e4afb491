"""A check of a fault label against the particles: does it lie where they show a jump?

The check measures the labels, so it shares none of their extraction code
(:mod:`demseis.labels.traces`): the displacement jump at a cell is computed from the particles.
The element displacements (since first appearance) are rasterised with
:func:`demseis.seismic.rasterise` (mean over the disks containing the cell centre) and the jump
is the largest |u(p + d) - u(p - d)| over the offsets d with |d_row|, |d_col| <= ``reach`` cells
whose two cells are rock of the same deposition cohort (displacements of different cohorts have
different references, so their difference is not a slip).
"""

from __future__ import annotations

import numpy as np
from scipy import ndimage

from demseis.errors import InputError
from demseis.labels import rasterise_strain
from demseis.seismic import rasterise


def jump_field(snapshot, displacement: np.ndarray, birth: np.ndarray, grid,
               reach: int = 2) -> tuple[np.ndarray, np.ndarray]:
    """Displacement jump (m) at every cell of ``grid`` and the rock mask.

    Parameters
    ----------
    snapshot : :class:`demseis.types.Snapshot` (uses ``xy``, ``radius``, ``n``).
    displacement : (n, 2) element displacement since first appearance (m).
    birth : (n,) snapshot of each element's first appearance (its cohort).
    grid : :class:`demseis.types.Grid`. reach : half-width (cells) of the offsets.

    Returns
    -------
    jump : (nz, nx) float64 (0 where no offset pair is measurable); rock : (nz, nx) bool.
    """
    u, _ = rasterise(snapshot.xy, snapshot.radius, displacement, grid)
    _, owner = rasterise_strain(snapshot.xy, snapshot.radius, np.zeros(snapshot.n), grid)
    rock = owner >= 0
    coh = np.where(rock, np.asarray(birth)[np.maximum(owner, 0)], -1)
    nz, nx = grid.shape
    up = np.pad(u, ((reach, reach), (reach, reach), (0, 0)), constant_values=np.nan)
    cp = np.pad(coh, reach, constant_values=-2)
    jump = np.zeros(grid.shape)
    for dr in range(-reach, reach + 1):
        for dc in range(-reach, reach + 1):
            if (dr, dc) <= (0, 0):
                continue
            a = up[reach + dr:reach + dr + nz, reach + dc:reach + dc + nx]
            b = up[reach - dr:reach - dr + nz, reach - dc:reach - dc + nx]
            ca = cp[reach + dr:reach + dr + nz, reach + dc:reach + dc + nx]
            cb = cp[reach - dr:reach - dr + nz, reach - dc:reach - dc + nx]
            m = np.hypot(*(a - b).transpose(2, 0, 1))
            ok = (ca == cb) & (ca >= 0) & np.isfinite(m)
            jump = np.where(ok, np.maximum(jump, np.nan_to_num(m)), jump)
    return jump, rock


def jump_coverage(fault: np.ndarray, jump: np.ndarray, rock: np.ndarray, min_slip_m: float,
                  within_cells: float = 2.0, metric: str = "euclidean") -> tuple[int, int]:
    """(cells with jump >= 2 min_slip_m, those of them within ``within_cells`` of ``fault``).

    ``metric``: how "within" is measured, ``"euclidean"`` (default) or ``"chessboard"``
    (max(|d_row|, |d_col|), the box in which :func:`jump_field` looks for the jump).
    """
    if metric not in ("euclidean", "chessboard"):
        raise InputError(f"metric = {metric!r}; allowed: 'euclidean', 'chessboard'")
    hi = (np.asarray(jump) >= 2.0 * min_slip_m) & np.asarray(rock, dtype=bool)
    f = np.asarray(fault, dtype=bool)
    if not f.any():
        return int(hi.sum()), 0
    if metric == "euclidean":
        near = ndimage.distance_transform_edt(~f) <= within_cells
    else:
        near = ndimage.distance_transform_cdt(~f, metric="chessboard") <= within_cells
    return int(hi.sum()), int((hi & near).sum())
