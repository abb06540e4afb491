"""Survey sampling and the ``strata`` rendering: what a section looks like where it is sampled
like a survey.

Traces
------
A sweep's output columns are traces ``trace_spacing_m`` apart (``[output]``; 0 = the grid
cell), ``x_j = (j + 0.5) dx`` for every trace that fits the model's width, independent of the
model's raster grid and its elements. Rows are the grid's depth cells (``domain = "depth"``) or
a two-way-time axis of ``dt_s`` samples (``domain = "time"``), so faults draw at their apparent
dip: a time section is vertically exaggerated.

Labels are made on the grid (:mod:`demseis.labels`, the engines) and taken to the traces by
:func:`labels_at_traces`: each trace takes, row by row, the grid cell of its footprint
``[x_j - dx/2, x_j + dx/2)`` that holds a fault (then a fault core, then a damage zone; then
the cell nearest the trace), so a one-cell fault line stays one connected line at any
spacing, and every label array of a pixel comes from the same cell.

The ``strata`` rendering
------------------------
``rendering = "elements"`` images the engine's property grids (per-element properties,
rasterised: the paper's mode). ``rendering = "strata"`` images a fine stratigraphy instead:

1. the engine maps every point of a trace, at a vertical step of at most ``strata_dz_m``
   (an odd number of steps per grid cell, so the cell centres are points), back to its
   reference coordinates (:attr:`demseis.generator.engines.State.reference`: where the rock
   there was before it moved, or where it was deposited), evaluated every
   ``REFERENCE_STEP`` points and interpolated between (:func:`reference_points`);
2. the run's beds (:mod:`demseis.seismic.strata`, drawn once per run around the properties
   of its mechanical layers) give Vp and density there (:func:`fill_gaps` where there is no
   rock; drifts below ``HOLD_TOL`` held, :func:`hold_small_steps`);
3. the fault zones change the impedance by ``fault_zone_impedance`` times the damage label
   over 2 (the core 1, the damage zone 1/2), split evenly between Vp and density;
4. the fine columns are imaged like any property grid (one reflection per fine interface at
   its exact two-way time), the rows of the cell centres kept in depth.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping

import numpy as np
from scipy.ndimage import median_filter

from demseis.generator.config.layout import grid_of, on_grid, trace_spacing, trace_x
from demseis.generator.config.settings import Config
from demseis.generator.render import _survey_kernels as _k
from demseis.seismic import depth_to_time

#: relative change of Vp and density down a trace below which no reflection is made
HOLD_TOL = 1e-4
#: priority of a label pixel when a trace's footprint holds several grid cells
_FAULT_PRIORITY = 4


def footprint_columns(cfg: Config) -> list[np.ndarray]:
    """Per trace, the grid columns whose centres lie in its footprint (the nearest column when
    none does: traces closer than the cells)."""
    cell = float(cfg.grid.cell_m)
    nx = grid_of(cfg).nx
    dx = trace_spacing(cfg)
    centres = (np.arange(nx) + 0.5) * cell
    out = []
    for x in trace_x(cfg):
        cols = np.flatnonzero((centres >= x - 0.5 * dx) & (centres < x + 0.5 * dx))
        if cols.size == 0:
            cols = np.array([min(nx - 1, int(x // cell))])
        out.append(cols)
    return out


def nearest_columns(cfg: Config) -> np.ndarray:
    """(ntr,) the grid column under each trace."""
    cell = float(cfg.grid.cell_m)
    return np.minimum(grid_of(cfg).nx - 1, (trace_x(cfg) // cell).astype(np.int64))


def labels_at_traces(cfg: Config, maps: Mapping[str, np.ndarray]) -> dict[str, np.ndarray]:
    """The (nz, nx) grid label maps taken to the (nz, ntr) traces (module docstring).

    Every map must have the grid's shape; ``fault`` and ``damage`` set the priority.
    """
    if on_grid(cfg):
        return dict(maps)
    fault = np.asarray(maps["fault"])
    damage = np.asarray(maps["damage"])
    nz = fault.shape[0]
    cols = footprint_columns(cfg)
    xs = trace_x(cfg)
    cell = float(cfg.grid.cell_m)
    pick = np.empty((nz, len(cols)), dtype=np.int64)
    for j, c in enumerate(cols):
        # higher label priority first; among equals the cell nearest the trace
        near = np.abs((c + 0.5) * cell - xs[j])
        rank = np.argsort(np.argsort(near, kind="stable"), kind="stable")
        score = ((fault[:, c] > 0) * _FAULT_PRIORITY + damage[:, c].astype(np.int64)) \
            * (c.size + 1) - rank[None, :]
        pick[:, j] = c[np.argmax(score, axis=1)]
    rows = np.arange(nz)[:, None]
    return {name: np.asarray(m)[rows, pick] for name, m in maps.items()}


#: the reference map is evaluated every REFERENCE_STEP strata points down a trace and
#: interpolated in between (module docstring)
REFERENCE_STEP = 4
#: a jump of the reference y between two evaluated points larger than this (m) beyond their
#: depth difference is a slip surface: the points between take the nearer one's map
JUMP_M = 0.25


def reference_points(reference: Callable[[np.ndarray, np.ndarray], tuple[np.ndarray, ...]],
                     x_m: np.ndarray, depth_m: np.ndarray,
                     step: int = REFERENCE_STEP) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``reference(X, D)`` on the grid of traces ``x_m`` by strata depths ``depth_m`` (rows),
    evaluated every ``step`` rows (and the last) and interpolated linearly in between.

    Inside rock that moved together the map is smooth at the scale of a few metres, so the
    interpolation is exact to far below a bed; where the evaluated neighbours disagree (their
    reference y differ by more than ``JUMP_M`` beyond the depth between them: a slip surface,
    a growth unit's edge, no rock) each point takes the map of the nearer evaluated row, moved
    by its depth offset. Units are the nearer row's. Returns (x0, y0, unit) of shape
    (rows, traces).
    """
    nz = depth_m.size
    rows = np.unique(np.concatenate([np.arange(0, nz, step), [nz - 1]]))
    X, D = np.meshgrid(x_m, depth_m[rows])
    x0c, y0c, unitc = (np.asarray(a) for a in reference(X, D))
    if rows.size == nz:
        return x0c, y0c, unitc
    x0 = np.empty((nz, x_m.size))
    y0 = np.empty((nz, x_m.size))
    unit = np.empty((nz, x_m.size), dtype=np.int64)
    _k.interpolate_reference(rows, np.asarray(depth_m, dtype=np.float64),
                             np.ascontiguousarray(x0c, dtype=np.float64),
                             np.ascontiguousarray(y0c, dtype=np.float64),
                             np.ascontiguousarray(unitc, dtype=np.int64), JUMP_M, x0, y0, unit)
    return x0, y0, unit


def substeps(cfg: Config) -> int:
    """Odd number of strata steps per grid cell, each at most ``strata_dz_m``."""
    n = int(math.ceil(float(cfg.grid.cell_m) / float(cfg.output.strata_dz_m) - 1e-9))
    return n if n % 2 == 1 else n + 1


def fine_depths(cfg: Config, nz: int) -> np.ndarray:
    """(nz * substeps,) depths (m below the grid top) of the strata points of a trace."""
    n = substeps(cfg)
    dz = float(cfg.grid.cell_m) / n
    return (np.arange(nz * n) + 0.5) * dz


def median_window(width_m: float, cfg: Config) -> int:
    """A width (m) along the section in traces: an odd count, 1 (no filter) for 0."""
    w = float(width_m)
    if w <= 0:
        return 1
    n = max(1, int(round(w / trace_spacing(cfg))))
    return n if n % 2 else n + 1


def level_surface(vp: np.ndarray, rho: np.ndarray, rock: np.ndarray, window: int) -> None:
    """In place: the top of the rock levelled by a running median over ``window`` traces.

    The first rock row of each trace is replaced by the running median of the traces' first
    rock rows (``scipy.ndimage.median_filter``, edges repeated). Rock above that row (a bump of
    a few elements) becomes NaN, no rock, and the space between it and the trace's first rock
    (a pit between elements) takes the first rock's values, as a gap inside the rock does. A
    step wider than half the window (a fault scarp) is kept. A trace without rock, and every
    trace when ``window`` is 1, is left as it is.

    Parameters
    ----------
    vp, rho : (rows, traces) float64 properties of the strata points, NaN where no rock.
    rock : (rows, traces) bool, where an element holds the point.
    window : odd number of traces.
    """
    if window <= 1:
        return
    nr = rock.shape[0]
    has = rock.any(axis=0)
    first = np.where(has, np.argmax(rock, axis=0), nr)
    level = median_filter(first, size=int(window), mode="nearest")
    for c in np.flatnonzero(has):
        top, lv = int(first[c]), int(level[c])
        if lv > top:                        # a bump: no rock above the levelled surface
            vp[:lv, c] = np.nan
            rho[:lv, c] = np.nan
        elif lv < top:                      # a pit: the first rock's values up to the level
            vp[lv:top, c] = vp[top, c]
            rho[lv:top, c] = rho[top, c]


def velocity_window(cfg: Config) -> int:
    """``[output] velocity_median_m`` in traces (:func:`median_window`)."""
    return median_window(cfg.output.velocity_median_m, cfg)


def surface_window(cfg: Config) -> int:
    """``[output] surface_median_m`` in traces (:func:`median_window`)."""
    return median_window(cfg.output.surface_median_m, cfg)


def smooth_velocity(vp: np.ndarray, rho: np.ndarray, window: int) -> tuple[np.ndarray, np.ndarray]:
    """The velocity that takes the strata points to two-way time, as the running median of
    ``vp`` over ``window`` traces along each row (``scipy.ndimage.median_filter``, edges
    repeated), and the density that keeps every point's impedance ``vp * rho``.

    The reflectivity depends on the impedance only, so the section's reflections are those of
    the rock; their times follow the laterally smoothed velocity. Pits and bumps of a few
    elements at the surface, and narrow columns of slow sediment between elements, then shift
    no trace against its neighbours (a wavefront heals over features narrower than its Fresnel
    zone), while a change of velocity wider than half the window (a fault block, a basin's
    fill) still shifts the times below it. ``window`` 1 returns the arrays as they are.
    """
    if window <= 1:
        return vp, rho
    v = median_filter(vp, size=(1, int(window)), mode="nearest")
    return v, vp * rho / v


def fill_gaps(values: np.ndarray) -> np.ndarray:
    """``values`` (rows, cols) with NaN (no rock) filled.

    Above the first rock of a column (the space above the surface of a subsided hanging
    wall, say) every column takes one value, the median of the columns' first rock values, so
    that the two-way time through that space does not jump from trace to trace; gaps within
    or below the rock take the nearest value of the column (below first). An empty column
    takes the same single value.
    """
    v = np.array(values, dtype=np.float64)
    bad = ~np.isfinite(v)
    if not bad.any():
        return v
    has = (~bad).any(axis=0)
    first = np.argmax(~bad, axis=0)
    surface = v[first[has], np.flatnonzero(has)]
    _k.fill_column_gaps(v, float(np.median(surface)) if surface.size else 1.0)
    return v


def hold_small_steps(vp: np.ndarray, rho: np.ndarray, tol: float = HOLD_TOL) -> None:
    """In place, down each column of strata points: a change of Vp and density by at most
    ``tol`` of the last kept values is dropped (the kept values hold), so it makes no
    reflection. Within a bed the properties drift only with the lateral variation along a
    tilted bed (a few 1e-4 per step); dropping those drifts costs at most ``tol`` of any value
    and lets the convolution skip three of four zero spikes (demseis.seismic.forward)."""
    _k.hold_small_steps(vp, rho, float(tol))


def damage_factor(damage: np.ndarray, change: float) -> np.ndarray:
    """Impedance factor ``1 + change * damage / 2`` of each point (damage 0, 1 or 2)."""
    return 1.0 + float(change) * np.asarray(damage, dtype=np.float64) / 2.0


def to_time(maps: Mapping[str, np.ndarray], vp: np.ndarray, cell_m: float, t_s: np.ndarray,
            fills: Mapping[str, object]) -> dict[str, np.ndarray]:
    """Per-cell maps on the time axis ``t_s`` (nearest: each sample takes its cell's value)."""
    return {name: depth_to_time(m, vp, cell_m, t_s, method="nearest", fill=fills[name])
            for name, m in maps.items()}
