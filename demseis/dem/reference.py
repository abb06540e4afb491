"""Reference coordinates: where the rock at a point of a deformed section was in the
undeformed model (or where it was deposited, for syn-tectonic sediment).

Rock properties of a fine stratigraphy (beds of 1-10 m, finer than the 12.5-25 m elements)
can then be looked up at the reference coordinates of every output point. For thin beds to
stay continuous reflectors the map must be continuous inside material that moved together,
jump across surfaces where elements slid past each other, and have no element-scale jitter.

Two steps (Numba kernels in :mod:`demseis.dem._reference_kernels`):

1. :func:`element_maps`: per element e a local map ``ref = A_e cur + b_e``, fitted by
   weighted least squares to e and the neighbours (within ``fit_radius_m``, same group)
   whose motion is coherent with e's: rigid hypotheses anchored at e are scored by the
   neighbours they explain within ``tol_m + 2 strain_tol d``; the best one's inliers are
   refitted (affine when at least 4 points spread in 2D, else rigid, else e's translation)
   and re-selected within ``tol_m + strain_tol d`` until the set is stable. Elements across
   a slip surface have residuals of the order of the slip and do not enter the fit.
2. :func:`reference_coordinates`: for a point p the owner e is the element of least power
   distance ``|p - x_e|^2 - r_e^2`` (within ``reach`` radii); the result is a Wendland-weighted
   mean (support ``support`` radii) of the maps M_j(p) of nearby elements of e's group, only
   among those that agree with e's map at p to within ``agree_tol_m`` (smooth taper). Inside
   coherent material all maps agree and the blend is smooth; across a slip surface they
   disagree by the slip and the result follows the owner's side.

:func:`reference_map` does both for a snapshot of a run, with the reference positions of
:func:`demseis.labels.displacement_history` (each element's first appearance) and the owner's
layer and deposited flag.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from demseis.dem import _reference_kernels as _k
from demseis.errors import InputError
from demseis.labels import build_cell_list, displacement_history, neighbour_lists
from demseis.types import Grid

#: default fit radius, in multiples of the largest element radius
FIT_RADIUS_FACTOR = 2.5
#: default coherence tolerance of the fit and agreement tolerance of the blend, in multiples
#: of the smallest element radius
TOL_FACTOR = 0.25
#: points per affine fit at least (e included); fewer -> rigid
MIN_AFFINE = 4
#: eigmin / eigmax of the inliers' weighted covariance below which the fit is not affine
COND_MIN = 0.05
#: hypotheses tried per element (rigid motions anchored at e towards its nearest candidates)
N_HYPOTHESES = 8
#: least-squares refits per element at most
MAX_ITER = 4


@dataclass(frozen=True)
class MapInfo:
    """Diagnostics of :func:`element_maps`.

    Attributes
    ----------
    n_used : (n,) int64 points in each element's final fit (the element itself included).
    kind : (n,) int8 fit kind: 0 translation of the element alone, 1 rigid, 2 affine.
    """

    n_used: np.ndarray
    kind: np.ndarray


@dataclass(frozen=True)
class ReferenceMap:
    """Reference coordinates of points of one snapshot and their mechanical unit.

    Attributes
    ----------
    ref_xy : (m, 2) float64 reference coordinates (m); NaN outside the assembly.
    element : (m,) int64 index (in the snapshot) of the owner element; -1 outside.
    layer : (m,) int16 layer of the owner; -1 outside.
    deposited : (m,) bool, True where the owner is a syn-tectonic (growth) element: its
        reference is where it was deposited, in snapshot ``birth``.
    birth : (m,) int64 position in the snapshot list where the owner first appears (the frame
        of ``ref_xy``: 0 for the original pack); -1 outside.
    """

    ref_xy: np.ndarray
    element: np.ndarray
    layer: np.ndarray
    deposited: np.ndarray
    birth: np.ndarray


def _xy(a, name: str, n: int | None = None) -> np.ndarray:
    a = np.asarray(a, dtype=np.float64)
    if a.ndim != 2 or a.shape[1] != 2 or (n is not None and a.shape[0] != n):
        want = "(n, 2)" if n is None else f"({n}, 2)"
        raise InputError(f"{name} must have shape {want}; got {a.shape}")
    return np.ascontiguousarray(a)


def _elements(cur_xy, radius, group) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    cur = _xy(cur_xy, "cur_xy")
    n = cur.shape[0]
    if not np.all(np.isfinite(cur)):
        raise InputError("cur_xy contains non-finite values")
    r = np.ascontiguousarray(radius, dtype=np.float64)
    if r.shape != (n,):
        raise InputError(f"radius must have shape ({n},) like cur_xy; got {r.shape}")
    if n and not (np.all(np.isfinite(r)) and r.min() > 0):
        raise InputError("radius must be finite and > 0")
    if group is None:
        g = np.zeros(n, dtype=np.int64)
    else:
        g = np.asarray(group)
        if g.shape != (n,) or not np.issubdtype(g.dtype, np.integer):
            raise InputError(f"group must be an integer array of shape ({n},); got "
                             f"{g.dtype} {g.shape}")
        g = np.ascontiguousarray(g, dtype=np.int64)
    return cur, r, g


def _positive(value, name: str, default: float) -> float:
    v = default if value is None else value
    if isinstance(v, bool) or not isinstance(v, (int, float, np.integer, np.floating)) \
            or not (np.isfinite(v) and v > 0):
        raise InputError(f"{name} = {value!r}; allowed: a finite number > 0")
    return float(v)


def element_maps(ref_xy: np.ndarray, cur_xy: np.ndarray, radius: np.ndarray, *,
                 fit_radius_m: float | None = None, tol_m: float | None = None,
                 strain_tol: float = 0.02, group: np.ndarray | None = None,
                 return_info: bool = False) -> np.ndarray | tuple[np.ndarray, MapInfo]:
    """Per-element local map from current to reference coordinates, ``ref ~ A_e cur + b_e``.

    Parameters
    ----------
    ref_xy : (n, 2) reference centres (m).
    cur_xy : (n, 2) current centres of the same elements (m).
    radius : (n,) radii (m), > 0.
    fit_radius_m : neighbours (current distance) taking part in a fit; default 2.5 x the
        largest radius.
    tol_m : residual (m) below which a neighbour moves with the element; default 0.25 x the
        smallest radius. Relative motion below it is treated as deformation of one body.
    strain_tol : extra tolerance per metre of distance (strain and curvature the local affine
        map does not take up); doubled while scoring the rigid hypotheses.
    group : (n,) integers; only elements of the same group are fitted together (e.g. the
        birth snapshot: elements deposited later have another reference frame). Default: one.
    return_info : also return a :class:`MapInfo`.

    Returns
    -------
    maps : (n, 2, 3) float64 ``[A | b]`` per element (``maps[e] @ (x, y, 1)`` is the reference
        of current point (x, y) according to e); and the :class:`MapInfo` if asked.

    Raises
    ------
    demseis.errors.InputError
        On bad shapes, non-finite positions, radii <= 0, or bad tolerances.
    """
    cur, r, g = _elements(cur_xy, radius, group)
    n = cur.shape[0]
    ref = _xy(ref_xy, "ref_xy", n)
    if not np.all(np.isfinite(ref)):
        raise InputError("ref_xy contains non-finite values")
    maps = np.empty((n, 2, 3), dtype=np.float64)
    used = np.zeros(n, dtype=np.int64)
    kind = np.zeros(n, dtype=np.int8)
    if n:
        fit_r = _positive(fit_radius_m, "fit_radius_m", FIT_RADIUS_FACTOR * float(r.max()))
        tol = _positive(tol_m, "tol_m", TOL_FACTOR * float(r.min()))
        if isinstance(strain_tol, bool) or not (np.isfinite(strain_tol) and strain_tol >= 0):
            raise InputError(f"strain_tol = {strain_tol!r}; allowed: a finite number >= 0")
        # fixed-radius neighbours: |x_j - x_i| <= 1.0 * (fit_r/2 + fit_r/2)
        offsets, index = neighbour_lists(cur, np.full(n, 0.5 * fit_r), method="radius",
                                         radius_factor=1.0)
        _k.fit_element_maps(np.ascontiguousarray(ref[:, 0]), np.ascontiguousarray(ref[:, 1]),
                            np.ascontiguousarray(cur[:, 0]), np.ascontiguousarray(cur[:, 1]),
                            g, offsets, index, fit_r, tol, float(strain_tol), N_HYPOTHESES,
                            MIN_AFFINE, COND_MIN, MAX_ITER, maps, used, kind)
    return (maps, MapInfo(n_used=used, kind=kind)) if return_info else maps


def reference_coordinates(cur_xy: np.ndarray, radius: np.ndarray, maps: np.ndarray,
                          points_xy: np.ndarray, *, group: np.ndarray | None = None,
                          reach: float = 1.5, support: float = 2.0,
                          agree_tol_m: float | None = None, return_element: bool = False
                          ) -> np.ndarray | tuple[np.ndarray, np.ndarray]:
    """Reference coordinates of arbitrary points of the current (deformed) state.

    Parameters
    ----------
    cur_xy : (n, 2) current element centres (m); radius : (n,) radii (m).
    maps : (n, 2, 3) element maps from :func:`element_maps`.
    points_xy : (m, 2) query points (m, x right, y up).
    group : (n,) integers, as given to :func:`element_maps`; maps of another group than the
        owner's are never blended.
    reach : a point belongs to the assembly when it lies within ``reach`` radii of some
        element centre (>= 1); farther points get NaN.
    support : blending support of element j, in radii of j (>= reach).
    agree_tol_m : maps that disagree with the owner's at the point by more than this (m) take
        no part (smooth taper from half of it); default 0.25 x the smallest radius.
    return_element : also return the owner element of every point.

    Returns
    -------
    ref : (m, 2) float64 reference coordinates (m); NaN outside the assembly. With
    ``return_element``: (ref, owner (m,) int64 element index, -1 outside).
    """
    cur, r, g = _elements(cur_xy, radius, group)
    n = cur.shape[0]
    maps = np.asarray(maps, dtype=np.float64)
    if maps.shape != (n, 2, 3):
        raise InputError(f"maps must have shape ({n}, 2, 3); got {maps.shape}")
    pts = _xy(points_xy, "points_xy")
    reach = _positive(reach, "reach", 1.5)
    support = _positive(support, "support", 2.0)
    if reach < 1.0 or support < reach:
        raise InputError(f"reach = {reach}, support = {support}; allowed: 1 <= reach <= "
                         "support")
    m = pts.shape[0]
    out = np.full((m, 2), np.nan)
    owner = np.full(m, -1, dtype=np.int64)
    if n and m:
        tol = _positive(agree_tol_m, "agree_tol_m", TOL_FACTOR * float(r.min()))
        x = np.ascontiguousarray(cur[:, 0])
        y = np.ascontiguousarray(cur[:, 1])
        cell = support * float(r.max())
        x0, y0, ncx, ncy, start, items = build_cell_list(x, y, cell)
        _k.blend_maps(x, y, r, g, np.ascontiguousarray(maps), x0, y0, cell, ncx, ncy, start,
                      items, np.ascontiguousarray(pts[:, 0]), np.ascontiguousarray(pts[:, 1]),
                      reach, support, tol, out, owner)
    return (out, owner) if return_element else out


def reference_map(snapshots: Sequence, k: int, points_xy: np.ndarray, *,
                  fit_radius_m: float | None = None, tol_m: float | None = None,
                  strain_tol: float = 0.02, reach: float = 1.5, support: float = 2.0,
                  agree_tol_m: float | None = None,
                  displacement: tuple[np.ndarray, np.ndarray] | None = None) -> ReferenceMap:
    """Reference coordinates of points of snapshot ``k`` of a run, with their owner's unit.

    The reference of every element is where it first appears in ``snapshots[: k + 1]``
    (:func:`demseis.labels.displacement_history`): its position in snapshot 0 for the
    original pack, its deposition position for growth strata. Elements are grouped by that
    birth snapshot, so each point is mapped in the frame of its owner's cohort.

    Parameters
    ----------
    snapshots : sequence of :class:`demseis.types.Snapshot` in time order, one id space.
    k : index into ``snapshots`` (negative counts from the end).
    points_xy : (m, 2) query points (m).
    fit_radius_m, tol_m, strain_tol : see :func:`element_maps`.
    reach, support, agree_tol_m : see :func:`reference_coordinates`.
    displacement : snapshot ``k``'s entry of ``displacement_history(snapshots)``, where the
        caller has it already (it is computed from ``snapshots[: k + 1]`` otherwise).

    Returns
    -------
    ReferenceMap
    """
    snaps = list(snapshots)
    k = _snapshot_index(k, len(snaps))
    disp, birth = (displacement if displacement is not None
                   else displacement_history(snaps[: k + 1])[k])
    s = snaps[k]
    cur = np.asarray(s.xy, dtype=np.float64)
    maps = element_maps(cur - disp, cur, s.radius, fit_radius_m=fit_radius_m, tol_m=tol_m,
                        strain_tol=strain_tol, group=birth)
    ref, owner = reference_coordinates(cur, s.radius, maps, points_xy, group=birth,
                                       reach=reach, support=support, agree_tol_m=agree_tol_m,
                                       return_element=True)
    return _with_units(s, birth, ref, owner)


def _snapshot_index(k, n: int) -> int:
    """``k`` as an index into ``n`` snapshots (negative counts from the end)."""
    if isinstance(k, bool) or not isinstance(k, (int, np.integer)) or not -n <= k < n:
        raise InputError(f"k = {k!r}; allowed: an integer index into {n} snapshots")
    return int(k) % n


def _with_units(s, birth: np.ndarray, ref: np.ndarray, owner: np.ndarray) -> ReferenceMap:
    """The :class:`ReferenceMap` of points with reference ``ref`` and owners ``owner`` in
    snapshot ``s`` (elements' birth positions ``birth``)."""
    cur = np.asarray(s.xy, dtype=np.float64)
    inside = owner >= 0
    o = np.where(inside, owner, 0)
    n_el = cur.shape[0]
    layer = np.where(inside, np.asarray(s.layer)[o] if n_el else 0, -1).astype(np.int16)
    dep = inside & (np.asarray(s.deposited, dtype=bool)[o] if n_el else False)
    bth = np.where(inside, birth[o] if n_el else 0, -1).astype(np.int64)
    return ReferenceMap(ref_xy=ref, element=owner, layer=layer, deposited=dep, birth=bth)


def block_reference_map(snapshots: Sequence, k: int, points_xy: np.ndarray,
                        barrier: np.ndarray, barrier_grid: Grid, smooth_m: float, *,
                        band_m: float = 0.0, reach: float = 1.5,
                        displacement: tuple[np.ndarray, np.ndarray] | None = None
                        ) -> ReferenceMap:
    """Reference coordinates of points of snapshot ``k``, smooth between the barriers.

    Where :func:`reference_map` follows every element's own motion (granular rearrangement
    and slip between small blocks included), this map follows the run's motion at the scale
    ``smooth_m`` and cuts it only at ``barrier`` (the labelled faults): the displacement at a
    point is a moving least-squares fit, linear in x and y, of the displacements of the
    elements of its owner's cohort within ``smooth_m`` that it reaches without crossing a
    barrier cell (Numba ``blend_blocks``). Rock between the barriers folds, tilts and drags
    with the run, and every jump of the beds lies on a barrier. Owners, layers and cohorts
    are those of :func:`reference_map`.

    Parameters
    ----------
    snapshots, k, points_xy, reach, displacement : as for :func:`reference_map`.
    barrier : (nz, nx) raster on ``barrier_grid``, non-zero on the barriers (the fault label).
    barrier_grid : :class:`demseis.types.Grid` of ``barrier``.
    smooth_m : smoothing radius (m), > 0.
    band_m : elements whose centre lies within this distance (m) of a barrier cell along the
        section (the cells within ``round(band_m / cell)`` columns of it) take no part: where
        the slip is spread over a zone a few elements wide, the rock on either side is
        extrapolated up to the barrier, so the jump there is the whole slip across the zone.

    Returns
    -------
    ReferenceMap
    """
    snaps = list(snapshots)
    k = _snapshot_index(k, len(snaps))
    b = np.asarray(barrier)
    if b.shape != barrier_grid.shape:
        raise InputError(f"barrier must have the shape of its grid {barrier_grid.shape}; got "
                         f"{b.shape}")
    smooth = _positive(smooth_m, "smooth_m", 1.0)
    if isinstance(band_m, bool) or not isinstance(band_m, (int, float, np.integer, np.floating)) \
            or not (np.isfinite(band_m) and band_m >= 0):
        raise InputError(f"band_m = {band_m!r}; allowed: a finite number >= 0")
    bar = np.ascontiguousarray(b != 0, dtype=np.uint8)
    band = bar.copy()
    for d in range(1, int(round(float(band_m) / float(barrier_grid.cell_m))) + 1):
        band[:, d:] |= bar[:, :-d]
        band[:, :-d] |= bar[:, d:]
    reach = _positive(reach, "reach", 1.5)
    if reach < 1.0:
        raise InputError(f"reach = {reach}; allowed: >= 1")
    disp, birth = (displacement if displacement is not None
                   else displacement_history(snaps[: k + 1])[k])
    s = snaps[k]
    cur, r, g = _elements(s.xy, s.radius, birth)
    ref_el = cur - np.asarray(disp, dtype=np.float64)
    pts = _xy(points_xy, "points_xy")
    m = pts.shape[0]
    out = np.full((m, 2), np.nan)
    owner = np.full(m, -1, dtype=np.int64)
    if cur.shape[0] and m:
        x = np.ascontiguousarray(cur[:, 0])
        y = np.ascontiguousarray(cur[:, 1])
        cell = max(smooth, reach * float(r.max()))
        x0, y0, ncx, ncy, start, items = build_cell_list(x, y, cell)
        _k.blend_blocks(x, y, np.ascontiguousarray(ref_el[:, 0]),
                        np.ascontiguousarray(ref_el[:, 1]), r, g, x0, y0, cell, ncx, ncy,
                        start, items, np.ascontiguousarray(pts[:, 0]),
                        np.ascontiguousarray(pts[:, 1]), reach, smooth, bar, band,
                        float(barrier_grid.x0_m), float(barrier_grid.top_m),
                        float(barrier_grid.cell_m), out, owner)
    return _with_units(s, birth, out, owner)
