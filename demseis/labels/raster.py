"""Per-element values on the seismic grid, the gaps between the disks filled, and the rock.

Every cell belongs to its power-diagram element (least d^2 - r^2 within ``ROCK_REACH`` r:
Numba kernel ``power_nearest``); cells no element reaches (above the free surface) are not
rock. Values are the mean over the disks containing the cell centre
(:func:`demseis.seismic.rasterise`), in the gaps between disks the value of the cell's element.
"""

from __future__ import annotations

import numpy as np
from scipy import ndimage

from demseis.labels import _kernels
from demseis.seismic import rasterise


#: A cell belongs to the rock when it lies within this multiple of an element's radius.
ROCK_REACH = 1.5


def rasterise_strain(xy: np.ndarray, radius: np.ndarray, values: np.ndarray,
                     grid) -> tuple[np.ndarray, np.ndarray]:
    """Per-element values on ``grid``, gaps filled, and the owning element of every cell.

    Parameters
    ----------
    xy : (n, 2) centres (m, y up); radius : (n,) radii (m); values : (n,) float, NaN = unknown.
    grid : target grid.

    Returns
    -------
    field : (nz, nx) float64. Mean of the known values of the disks containing the cell centre
        (:func:`demseis.seismic.raster.rasterise`); where there is none, the value of the
        cell's power-diagram element if known, else of the nearest filled cell; 0 where no
        element reaches the cell (outside the rock).
    owner : (nz, nx) int64 power-diagram element of each cell (-1 outside the rock).
    """
    xy = np.asarray(xy, dtype=np.float64)
    radius = np.asarray(radius, dtype=np.float64)
    values = np.asarray(values, dtype=np.float64)
    known = np.isfinite(values)
    owner = np.empty(grid.shape, dtype=np.int64)
    _kernels.power_nearest(np.ascontiguousarray(xy[:, 0]), np.ascontiguousarray(xy[:, 1]),
                           radius, ROCK_REACH, float(grid.x0_m), float(grid.top_m),
                           float(grid.cell_m), grid.nz, grid.nx, owner)
    rock = owner >= 0
    if known.any():
        field, _ = rasterise(xy[known], radius[known], values[known], grid)
    else:
        field = np.full(grid.shape, np.nan)
    gap = ~np.isfinite(field) & rock
    from_owner = values[owner[gap]]
    field[gap] = from_owner
    field[~rock] = np.nan
    missing = ~np.isfinite(field) & rock
    if missing.any():
        have = np.isfinite(field)
        if have.any():
            idx = ndimage.distance_transform_edt(~have, return_distances=False,
                                                 return_indices=True)
            field[missing] = field[idx[0][missing], idx[1][missing]]
        else:
            field[missing] = 0.0
    field[~rock] = 0.0
    return field, owner
