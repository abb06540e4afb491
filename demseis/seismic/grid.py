"""The Cartesian grid on which element fields are rasterised.

Row 0 is the top of the model; rows go down in depth, columns go right in x. Seismic,
labels and every per-cell array share this grid, so they are pixel-aligned.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from demseis.errors import InputError


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

    def __post_init__(self) -> None:
        if not (np.isfinite(self.cell_m) and self.cell_m > 0):
            raise InputError(f"Grid cell_m must be a finite size > 0 m, got {self.cell_m!r}")
        if not (np.isfinite(self.x0_m) and np.isfinite(self.top_m)):
            raise InputError(f"Grid x0_m and top_m must be finite, got {self.x0_m!r}, "
                             f"{self.top_m!r}")
        for name in ("nz", "nx"):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or v < 1:
                raise InputError(f"Grid {name} must be an integer >= 1, got {v!r}")

    @classmethod
    def covering(cls, width_m: float, height_m: float, cell_m: float = 10.0) -> "Grid":
        """The grid over the box ``[0, width_m] x [0, height_m]`` (cells that fit whole)."""
        if not (np.isfinite(cell_m) and cell_m > 0):
            raise InputError(f"Grid cell_m must be a finite size > 0 m, got {cell_m!r}")
        if not (np.isfinite(width_m) and np.isfinite(height_m) and width_m > 0 and height_m > 0):
            raise InputError(f"Grid.covering needs width_m, height_m > 0, got {width_m!r}, "
                             f"{height_m!r}")
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
