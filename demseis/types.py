"""Plain data types shared by every stage: the raster :class:`Grid` and the particle :class:`Snapshot`.

Coordinates: x to the right, y up, metres. The DEM box is ``0 <= x <= width_m`` and
``0 <= y <= height_m`` before faulting (y = 0 is the top of the basement). On a :class:`Grid`, row 0
is the top of the model; rows go down in depth, columns go right in x. Seismic, labels and every
per-cell array share one grid, so they are pixel-aligned.

Snapshots are saved to and loaded from ``.npz`` files with :func:`save_snapshots` and
:func:`load_snapshots` (keys ``n`` and, per snapshot k, ``s{k}_ids``, ``s{k}_xy``,
``s{k}_radius``, ``s{k}_layer``, ``s{k}_throw_m``, ``s{k}_step``, ``s{k}_deposited``).
This module imports only NumPy and :mod:`demseis.errors`; every stage may import it.
"""

from __future__ import annotations

import os
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


@dataclass(frozen=True)
class Snapshot:
    """State of the assembly at one increment.

    Attributes
    ----------
    index : snapshot number (0 = the undeformed reference).
    step : integrator step at which it was taken.
    throw_m : basement throw applied so far (m).
    ids : (n,) int64 element ids, stable across snapshots of one run.
    xy : (n, 2) float64 element centres (m).
    radius : (n,) float64 radii (m).
    layer : (n,) int16 layer index (0 = deepest pre-kinematic layer; growth layers follow).
    deposited : (n,) bool, True for elements added by syn-tectonic sedimentation.
    """

    index: int
    step: int
    throw_m: float
    ids: np.ndarray
    xy: np.ndarray
    radius: np.ndarray
    layer: np.ndarray
    deposited: np.ndarray

    @property
    def n(self) -> int:
        return int(self.ids.shape[0])


def save_snapshots(path: str | os.PathLike, snaps: list[Snapshot]) -> None:
    """Write snapshots to an ``.npz`` file (see the module docstring for the keys)."""
    arrays: dict[str, np.ndarray] = {"n": np.asarray(len(snaps))}
    for k, s in enumerate(snaps):
        arrays.update({f"s{k}_ids": s.ids, f"s{k}_xy": s.xy, f"s{k}_radius": s.radius,
                       f"s{k}_layer": s.layer, f"s{k}_deposited": s.deposited,
                       f"s{k}_throw_m": np.asarray(s.throw_m), f"s{k}_step": np.asarray(s.step),
                       f"s{k}_index": np.asarray(s.index)})
    np.savez(path, **arrays)


def load_snapshots(path: str | os.PathLike) -> list[Snapshot]:
    """Snapshots saved by :func:`save_snapshots` (``step``, ``index`` and ``deposited`` are
    optional keys: 0, k and all-False when absent)."""
    try:
        d = np.load(path)
        n = int(d["n"])
    except (OSError, ValueError, KeyError) as exc:
        raise InputError(f"{os.fspath(path)!r} is not a demseis snapshot .npz ({exc})") from exc
    out = []
    for k in range(n):
        ids = np.asarray(d[f"s{k}_ids"], dtype=np.int64)
        dep = d[f"s{k}_deposited"] if f"s{k}_deposited" in d else np.zeros(ids.shape[0], bool)
        out.append(Snapshot(
            index=int(d[f"s{k}_index"]) if f"s{k}_index" in d else k,
            step=int(d[f"s{k}_step"]) if f"s{k}_step" in d else 0,
            throw_m=float(d[f"s{k}_throw_m"]), ids=ids,
            xy=np.asarray(d[f"s{k}_xy"], dtype=np.float64),
            radius=np.asarray(d[f"s{k}_radius"], dtype=np.float64),
            layer=np.asarray(d[f"s{k}_layer"], dtype=np.int16), deposited=np.asarray(dep, bool)))
    return out
