"""Numba kernels of the seismic stage. Plain arrays in, plain arrays out; SI units."""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True)
def rasterise_sum(x, y, radius, values, x0, top, cell, nz, nx, out_sum, out_count):
    """Accumulate element values into the cells whose centre lies inside each disk.

    Parameters
    ----------
    x, y, radius : (n,) float64 element centres and radii (m); y is elevation (up).
    values : (n, k) float64 per-element values.
    x0, top, cell : grid left edge, top elevation and cell size (m).
    nz, nx : grid rows and columns.
    out_sum : (nz, nx, k) float64, incremented in place with the sum of contributing values.
    out_count : (nz, nx) int32, incremented with the number of contributing elements.

    A cell (i, j) has centre (x0 + (j + 0.5) cell, top - (i + 0.5) cell); element e contributes
    when (xc - x_e)^2 + (yc - y_e)^2 <= r_e^2.
    """
    n = x.shape[0]
    k = values.shape[1]
    for e in range(n):
        r = radius[e]
        r2 = r * r
        j0 = int(np.ceil((x[e] - r - x0) / cell - 0.5))
        j1 = int(np.floor((x[e] + r - x0) / cell - 0.5))
        i0 = int(np.ceil((top - (y[e] + r)) / cell - 0.5))
        i1 = int(np.floor((top - (y[e] - r)) / cell - 0.5))
        if j0 < 0:
            j0 = 0
        if i0 < 0:
            i0 = 0
        if j1 > nx - 1:
            j1 = nx - 1
        if i1 > nz - 1:
            i1 = nz - 1
        for i in range(i0, i1 + 1):
            yc = top - (i + 0.5) * cell
            dy = yc - y[e]
            for j in range(j0, j1 + 1):
                xc = x0 + (j + 0.5) * cell
                dx = xc - x[e]
                if dx * dx + dy * dy <= r2:
                    out_count[i, j] += 1
                    for c in range(k):
                        out_sum[i, j, c] += values[e, c]
