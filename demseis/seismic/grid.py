"""The Cartesian grid on which element fields are rasterised.

Row 0 is the top of the model; rows go down in depth, columns go right in x. Seismic,
labels and every per-cell array share this grid, so they are pixel-aligned.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Grid:
    """A regular grid of ``nz`` rows by ``nx`` columns of square cells.

    Attributes
    ----------
    x0_m : x of the left edge of column 0.
    top_m : elevation (y) of the top edge of row 0; depth of row i centre is (i + 0.5) * cell_m.
    cell_m : cell size in metres (default 10 m).
    nz, nx : number of rows (depth) and columns (x).
    """

    x0_m: float
    top_m: float
    cell_m: float
    nz: int
    nx: int

    @classmethod
    def covering(cls, width_m: float, height_m: float, cell_m: float = 10.0) -> "Grid":
        """The grid over the box ``[0, width_m] x [0, height_m]`` (cells that fit whole)."""
        nx = max(1, int(np.floor(width_m / cell_m + 1e-9)))
        nz = max(1, int(np.floor(height_m / cell_m + 1e-9)))
        return cls(x0_m=0.0, top_m=float(height_m), cell_m=float(cell_m), nz=nz, nx=nx)

    @property
    def shape(self) -> tuple[int, int]:
        return (self.nz, self.nx)

    def x_centres(self) -> np.ndarray:
        """(nx,) x of the column centres."""
        return self.x0_m + (np.arange(self.nx) + 0.5) * self.cell_m

    def y_centres(self) -> np.ndarray:
        """(nz,) elevation y of the row centres (decreasing with row index)."""
        return self.top_m - (np.arange(self.nz) + 0.5) * self.cell_m
