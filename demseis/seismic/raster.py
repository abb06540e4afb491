"""Rasterisation of per-element values onto a :class:`~demseis.types.Grid`."""

from __future__ import annotations

import numpy as np

from demseis.errors import InputError
from demseis.seismic._kernels import divide_by_count, rasterise_sum
from demseis.types import Grid


def rasterise(
    xy: np.ndarray,
    radius: np.ndarray,
    values: np.ndarray,
    grid: Grid,
) -> tuple[np.ndarray, np.ndarray]:
    """Mean of the element values whose disk contains each cell centre.

    Parameters
    ----------
    xy : (n, 2) element centres (m), y up.
    radius : (n,) radii (m).
    values : (n,) or (n, k) per-element values.
    grid : the target grid.

    Returns
    -------
    mean : (nz, nx) or (nz, nx, k) float64; NaN where no element covers the cell centre.
    count : (nz, nx) int32 number of contributing elements.
    """
    xy = np.asarray(xy, dtype=np.float64)
    radius = np.asarray(radius, dtype=np.float64)
    vals = np.asarray(values, dtype=np.float64)
    squeeze = vals.ndim == 1
    if squeeze:
        vals = vals[:, None]
    n = xy.shape[0]
    if xy.ndim != 2 or xy.shape[1] != 2 or radius.shape != (n,) or vals.shape[0] != n:
        raise InputError(
            f"rasterise: expected xy (n, 2), radius (n,), values (n[, k]); got "
            f"{xy.shape}, {radius.shape}, {np.shape(values)}"
        )
    if not (np.all(np.isfinite(xy)) and np.all(np.isfinite(radius)) and np.all(radius >= 0)):
        raise InputError("rasterise: xy and radius must be finite and radius >= 0 m")
    k = vals.shape[1]
    total = np.zeros((grid.nz, grid.nx, k), dtype=np.float64)
    count = np.zeros((grid.nz, grid.nx), dtype=np.int32)
    rasterise_sum(
        np.ascontiguousarray(xy[:, 0]), np.ascontiguousarray(xy[:, 1]), radius,
        np.ascontiguousarray(vals), float(grid.x0_m), float(grid.top_m), float(grid.cell_m),
        grid.nz, grid.nx, total, count,
    )
    divide_by_count(total, count)
    return (total[:, :, 0] if squeeze else total), count
