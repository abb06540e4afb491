"""Slip surfaces as traced objects: crest of localised shear, linked into faults, kept where they slip.

A fault label should mark where the section shows an offset. The continuum strain of the
element displacements (:mod:`demseis.labels.strain`) is high in a band around every slip
surface, but also where the rock only bends (a monocline above a blind tip) and in the broad
wedge of a large-throw fault. Thresholding and thinning that band (the ``"strain_band"``
method of :mod:`demseis.labels.maps`) turns such blobs into networks with loops and horizontal
"rungs". Here instead (the ``"slip_trace"`` method):

1. **Crest.** The rasterised strain is smoothed (``ridge_sigma_cells``) and its Hessian gives the
   local band normal (eigenvector of the most negative curvature). Non-maximum suppression
   keeps the cells that are not below their neighbours one cell away on both sides along that
   normal (a ridge, Canny-style) where the strain is at least ``ridge_threshold``; the crest is
   thinned to one cell (Guo-Hall), components shorter than ``min_trace_cells`` dropped, short
   spurs pruned and every branch moving-averaged along its length (``centreline_window_cells``),
   as for the strain-band centre line.
2. **Slip.** At every crest cell the trace's local direction is fitted over a 9 x 9 window, and
   the element displacement (rasterised like the strain) is sampled ``k`` cells away on both
   sides along the normal, k = 2..``slip_offset_cells``; the largest |u(+k) - u(-k)| is the
   displacement jump (slip, m), averaged along the trace over 5 x 5 cells. A crest cell is fault
   only where that slip is at least ``min_slip_m`` and its dip at least ``min_dip_deg``.
2b. **Strands.** A DEM shear zone slips on several grain boundaries side by side; steps 1-2
   are repeated on the displacement smoothed by only ``strand_sigma_cells``: crests of that
   field more than STRAND_SEPARATION_CELLS from a trace, spanning STRAND_SPAN_CELLS or more,
   whose jump over 1-2 cells is at least ``min_slip_m`` and persists 3-4 cells out, are traces
   too (strands); the dip test is repeated on the union, and a strand within
   STRAND_ZONE_CELLS of a trace takes its fault id.
3. **Faults.** The kept cells are linked into traces: the skeleton is cut at its junctions, and
   at each junction the two branches that continue each other (directions within
   ``link_angle_deg`` of a straight line) are joined; the others (splays, antithetics, the
   second of two crossing faults) start their own fault. Instance ids are 1.. by size.
4. **Attributes.** Dip (degrees from horizontal, from the fitted direction), sense of slip (1
   normal: the upper block moved down the fault relative to the lower; 2 reverse), slip.
5. **Fault core.** Around each trace, the shear band's width at half maximum of the shear
   smoothed by CORE_SIGMA_CELLS, up to ``core_halfwidth_cells`` either side, where the band is
   at least 5 cells wide (:func:`band_core`): ``damage`` class 2 in the targets. A sharp slip
   surface's core is its trace; the ``fault`` mask stays the trace.

All of it is on the grid of the seismic (row 0 at the top, square cells).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import ndimage
from scipy.spatial import cKDTree

from demseis.errors import InputError
from demseis.labels import _kernels
from demseis.labels.centreline import crossing_number, prune_spurs
from demseis.labels.config import LabelConfig
from demseis.labels.maps import remove_small_components, skeletonize

_EIGHT = np.ones((3, 3), dtype=bool)

#: sense-of-slip codes of the ``sense`` target
SENSE_NONE, SENSE_NORMAL, SENSE_REVERSE = 0, 1, 2

#: window (cells) over which a trace's local direction is fitted (also the rung definition)
DIRECTION_WINDOW = 9

#: largest gap (cells) across which two facing trace ends are joined into one fault
LINK_GAP_CELLS = 10.0

#: strands (the finer crest search) closer than this (cells) to a trace are that trace's crest
STRAND_SEPARATION_CELLS = 2.0

#: strands (and their crest pieces) spanning fewer cells (bounding-box diagonal) are dropped
STRAND_SPAN_CELLS = 11.0

#: a strand lying mostly within this distance (cells) of a trace belongs to that fault's zone
STRAND_ZONE_CELLS = 15.0

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


@dataclass(frozen=True)
class Traces:
    """Fault traces of one section (all (nz, nx), one-cell-wide lines).

    Attributes
    ----------
    trace : bool, labelled trace cells (slip >= min_slip_m).
    instance : int32, fault id 1..n on trace cells, 0 elsewhere.
    slip_m : float32, displacement jump across the trace (m), 0 off the trace.
    dip_deg : float32, dip of the trace (degrees from horizontal, 0..90), 0 off the trace.
    sense : uint8, 1 normal / 2 reverse on trace cells, 0 elsewhere.
    crest : bool, every crest cell before the slip test (for diagnostics).
    crest_slip_m : float32, slip measured on every crest cell (NaN where not measurable).
    core : bool or None, the shear band's core around the traces (the trace cells and the
        band's width at half maximum of the fine shear around them: :func:`band_core`);
        None when ``core_halfwidth_cells`` is 0.
    """

    trace: np.ndarray
    instance: np.ndarray
    slip_m: np.ndarray
    dip_deg: np.ndarray
    sense: np.ndarray
    crest: np.ndarray
    crest_slip_m: np.ndarray
    core: np.ndarray | None = None

    @property
    def n_faults(self) -> int:
        """Number of fault instances."""
        return int(self.instance.max()) if self.instance.size else 0


def displacement_history(snapshots) -> list[np.ndarray]:
    """Displacement (m, x right, y up) of every element since its first appearance.

    Parameters
    ----------
    snapshots : sequence of :class:`demseis.dem.types.Snapshot` in time order, one id space.

    Returns
    -------
    list of (displacement (n_k, 2) float64, birth (n_k,) int64) aligned with each snapshot's
    elements; an element's reference position is where it first appears (``birth``: the
    position in ``snapshots`` of that snapshot; 0 for the original pack).
    """
    first_ids = np.empty(0, dtype=np.int64)
    first_xy = np.empty((0, 2), dtype=np.float64)
    first_k = np.empty(0, dtype=np.int64)
    out = []
    for k, s in enumerate(snapshots):
        ids = np.asarray(s.ids, dtype=np.int64)
        xy = np.asarray(s.xy, dtype=np.float64)
        pos = np.searchsorted(first_ids, ids)
        known = pos < first_ids.shape[0]
        known[known] = first_ids[pos[known]] == ids[known]
        ref = xy.copy()
        ref[known] = first_xy[pos[known]]
        birth = np.full(ids.shape[0], k, dtype=np.int64)
        birth[known] = first_k[pos[known]]
        out.append((xy - ref, birth))
        if (~known).any():
            all_ids = np.concatenate([first_ids, ids[~known]])
            all_xy = np.concatenate([first_xy, xy[~known]])
            all_k = np.concatenate([first_k, birth[~known]])
            order = np.argsort(all_ids, kind="stable")
            first_ids, first_xy, first_k = all_ids[order], all_xy[order], all_k[order]
    return out


def ridge_normals(g: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Unit normal (row, col) of the ridges of ``g``: eigenvector of the Hessian's least eigenvalue."""
    g_r, g_c = np.gradient(g)
    h_rr, h_rc = np.gradient(g_r)
    h_cr, h_cc = np.gradient(g_c)
    h_x = 0.5 * (h_rc + h_cr)
    # eigenvector of the largest eigenvalue at angle phi (from the row axis); least at phi + 90
    phi = 0.5 * np.arctan2(2.0 * h_x, h_rr - h_cc) + 0.5 * np.pi
    return np.cos(phi), np.sin(phi)


def shear_field(disp_x_m: np.ndarray, disp_y_m: np.ndarray, rock: np.ndarray, cell_m: float,
                sigma_cells: float, cohort: np.ndarray | None = None) -> np.ndarray:
    """Engineering shear strain of the smoothed grid displacement, per deposition cohort.

    gamma = sqrt((du_x/dx - du_y/dy)^2 + (du_x/dy + du_y/dx)^2) (1 for simple shear of 1, a
    Gaussian profile of area = slip across a displacement step; rigid motion gives 0). The
    displacement is smoothed by a Gaussian of ``sigma_cells`` normalised over the cells of
    one cohort (elements of one first appearance): displacements are measured from each
    element's first appearance, so they jump at a deposition surface without any strain
    there, and that jump must not be differentiated.

    Parameters
    ----------
    disp_x_m, disp_y_m : (nz, nx) rasterised element displacement (m, x right, y up).
    rock : (nz, nx) bool. cell_m : cell size (m). sigma_cells : smoothing (cells).
    cohort : (nz, nx) int cohort of each rock cell (default: one cohort).

    Returns
    -------
    (nz, nx) float64, 0 outside the rock.
    """
    rock = np.asarray(rock, dtype=bool)
    coh = np.zeros(rock.shape, dtype=np.int64) if cohort is None else np.asarray(cohort)
    out = np.zeros(rock.shape)
    # each cohort on its bounding box grown by the filter's radius + 2 (a sediment cohort is a
    # thin band): the smoothed values there, and the gradients at the cohort's cells, are
    # the same bits as on the whole grid (tests/labels/test_traces_box.py)
    radius = int(4.0 * float(sigma_cells)) + 1 if sigma_cells > 0 else 0  # >= scipy's
    for c in np.unique(coh[rock]):
        m_full = rock & (coh == c)
        box_sl = _support(m_full, 2 * radius + 2)
        m = m_full[box_sl]
        w = m.astype(np.float64)
        den = ndimage.gaussian_filter(w, sigma_cells, mode="nearest") if sigma_cells > 0 else w
        grads = []
        shared = None  # nearest-cell indices of the cells outside the cohort (both components)
        for u in (disp_x_m[box_sl], disp_y_m[box_sl]):
            uu = np.where(m, u, 0.0)
            num = ndimage.gaussian_filter(uu, sigma_cells, mode="nearest") if sigma_cells > 0 \
                else uu
            with np.errstate(invalid="ignore", divide="ignore"):
                sm = np.where(den > 1e-3, num / np.maximum(den, 1e-12), np.nan)
            # fill outside the cohort from the nearest cohort cell so differences stay inside
            bad = ~np.isfinite(sm)
            if bad.all():
                sm = np.zeros_like(sm)
            elif bad.any():
                if shared is None or not np.array_equal(shared[0], bad):
                    shared = (bad, ndimage.distance_transform_edt(
                        bad, return_distances=False, return_indices=True))
                idx = shared[1]
                sm = sm[idx[0], idx[1]]
            d_row, d_col = np.gradient(sm)
            grads.append((d_col / cell_m, -d_row / cell_m))  # d/dx, d/dy (y up)
        (uxx, uxy), (uyx, uyy) = grads
        g = np.sqrt((uxx - uyy) ** 2 + (uxy + uyx) ** 2)
        out[box_sl][m] = g[m]
    return out


def crest_cells(field: np.ndarray, rock: np.ndarray, config: LabelConfig) -> np.ndarray:
    """One-cell-wide crest lines of a (smooth) shear field (step 1 of the module docstring)."""
    g = np.asarray(field, dtype=np.float64)
    n_r, n_c = ridge_normals(g)
    out = np.zeros(g.shape, dtype=np.uint8)
    _kernels.ridge_nms(np.ascontiguousarray(g), np.ascontiguousarray(n_r),
                       np.ascontiguousarray(n_c), np.ascontiguousarray(rock),
                       float(config.ridge_threshold), out)
    gap = int(config.link_gap_cells)
    w = int(config.centreline_window_cells)
    pad = gap + 2
    crest = np.pad(out.astype(bool), pad)
    if gap > 0:  # bridge gaps of up to ~gap cells: thin the crest grown by gap / 2
        crest = ndimage.binary_dilation(crest, structure=_disk(gap / 2.0))
    skel = skeletonize(crest)
    if w > 1 and skel.any():
        skel = prune_spurs(skel, w)
    skel = skel[pad:-pad, pad:-pad] & rock
    return remove_small_components(skel, config.min_trace_cells)


def _disk(radius: float) -> np.ndarray:
    k = int(np.ceil(radius))
    yy, xx = np.mgrid[-k:k + 1, -k:k + 1]
    return xx * xx + yy * yy <= radius * radius + 1e-9


def project_on_local_line(cells: np.ndarray, shift: np.ndarray, window: int) -> np.ndarray:
    """Redraw a line mask with every cell moved onto the line fitted through its neighbours.

    Each cell's position (its centre plus ``shift``, NaN = 0) is projected on the principal
    axis of the positions of the line cells in the ``window`` x ``window`` box around it (a
    moving-least-squares line), which removes element-scale stepping without cutting the line
    into branches at its junctions; the projected points are rounded to cells, 1-cell gaps
    closed and the result thinned to one cell.
    """
    c = np.asarray(cells, dtype=bool)
    if not c.any() or window <= 1:
        return c.copy()
    box_sl = _support(c, window)  # the filters on the mask's box: same bits (see _support)
    w = c[box_sl].astype(np.float64)
    rr, cc = np.mgrid[box_sl].astype(np.float64)
    pr = rr + np.nan_to_num(shift[box_sl][..., 0], nan=0.0)
    pc = cc + np.nan_to_num(shift[box_sl][..., 1], nan=0.0)

    def box(a: np.ndarray) -> np.ndarray:
        return ndimage.uniform_filter(a * w, size=window, mode="constant")

    n = np.maximum(box(np.ones_like(w)), 1e-12)
    mr, mc = box(pr) / n, box(pc) / n
    crr = box(pr * pr) / n - mr * mr
    ccc = box(pc * pc) / n - mc * mc
    crc = box(pr * pc) / n - mr * mc
    phi = 0.5 * np.arctan2(2.0 * crc, crr - ccc)
    t_r, t_c = np.cos(phi), np.sin(phi)
    rows, cols = np.nonzero(c)
    br, bc = rows - box_sl[0].start, cols - box_sl[1].start
    a = (rows - mr[br, bc]) * t_r[br, bc] + (cols - mc[br, bc]) * t_c[br, bc]
    qr = np.rint(mr[br, bc] + a * t_r[br, bc]).astype(np.int64)
    qc = np.rint(mc[br, bc] + a * t_c[br, bc]).astype(np.int64)
    ok = (qr >= 0) & (qr < c.shape[0]) & (qc >= 0) & (qc < c.shape[1])
    out = np.zeros_like(c)
    out[qr[ok], qc[ok]] = True
    # rounding leaves gaps of a cell or two: the skeleton of the line grown by one cell
    # bridges them (a closing would not: it erodes a one-cell line back to its gaps)
    return skeletonize(ndimage.binary_dilation(out, structure=_EIGHT))


def centre_on_jump(skel: np.ndarray, disp_x_m: np.ndarray, disp_y_m: np.ndarray,
                   rock: np.ndarray, reach_cells: int) -> np.ndarray:
    """Sub-cell offset (rows, cols) from each line cell to the centre of the displacement jump.

    Along the line's normal the displacement is sampled at t = -reach..reach cells (half-cell
    steps) and projected on the jump u(+reach) - u(-reach); the offset is the centroid of its
    increase along t (where the displacement changes: the slip surface, or the middle of a
    shear band). NaN where the jump is not measurable.
    """
    rows, cols = np.nonzero(skel)
    t_r, t_c = local_direction(skel)
    n_r, n_c = t_c[rows, cols], -t_r[rows, cols]
    ts = np.arange(-2 * reach_cells, 2 * reach_cells + 1) / 2.0
    u_row = np.ascontiguousarray(-np.asarray(disp_y_m, dtype=np.float64))
    u_col = np.ascontiguousarray(np.asarray(disp_x_m, dtype=np.float64))
    prof = np.empty((rows.size, ts.size, 2))
    _kernels.sample_profiles(u_row, u_col, np.ascontiguousarray(rock), rows.astype(np.int64),
                             cols.astype(np.int64), n_r.copy(), n_c.copy(), ts, prof)
    jump = prof[:, -1] - prof[:, 0]
    mag = np.hypot(jump[:, 0], jump[:, 1])
    with np.errstate(invalid="ignore", divide="ignore"):
        f = (prof[..., 0] * jump[:, None, 0] + prof[..., 1] * jump[:, None, 1]) / mag[:, None]
        df = np.clip(np.diff(f, axis=1), 0.0, None)
        tm = 0.5 * (ts[1:] + ts[:-1])
        off = (df * tm).sum(1) / df.sum(1)
    out = np.full((*skel.shape, 2), np.nan)
    ok = np.isfinite(off) & (mag > 0)
    out[rows[ok], cols[ok], 0] = off[ok] * n_r[ok]
    out[rows[ok], cols[ok], 1] = off[ok] * n_c[ok]
    return out


def local_direction(skel: np.ndarray, window: int = DIRECTION_WINDOW) -> tuple[np.ndarray, np.ndarray]:
    """Unit tangent (row, col) of a line mask, fitted over a ``window`` x ``window`` box.

    Principal axis of the coordinates of the mask cells in the box centred on each cell (the
    box sums are box filters of the cell moments). Values off the mask are meaningless (the
    filters run on the mask's bounding box only, see :func:`_support`; (1, 0) outside it).
    """
    s_full = np.asarray(skel, dtype=np.float64)
    t_r = np.ones(s_full.shape)
    t_c = np.zeros(s_full.shape)
    box_sl = _support(s_full != 0, window)
    if box_sl is None:
        return t_r, t_c
    s = s_full[box_sl]
    rr, cc = np.mgrid[box_sl].astype(np.float64)  # absolute coordinates, as on the whole grid

    def box(a: np.ndarray) -> np.ndarray:
        return ndimage.uniform_filter(a, size=window, mode="constant") * window * window

    n = np.maximum(box(s), 1e-12)
    mr, mc = box(s * rr) / n, box(s * cc) / n
    crr = box(s * rr * rr) / n - mr * mr
    ccc = box(s * cc * cc) / n - mc * mc
    crc = box(s * rr * cc) / n - mr * mc
    phi = 0.5 * np.arctan2(2.0 * crc, crr - ccc)  # angle of the major axis from the row axis
    t_r[box_sl] = np.cos(phi)
    t_c[box_sl] = np.sin(phi)
    return t_r, t_c


def _support(mask: np.ndarray, size: int) -> tuple[slice, slice] | None:
    """Bounding box of ``mask`` grown by ``size // 2 + 1`` cells (clipped to the grid); None
    if the mask is empty.

    A box filter (``ndimage.uniform_filter``, mode "constant" 0) of an array that is 0 off
    the mask gives, inside this box, the same bits as on the whole grid: scipy runs a sum
    along each line, and the box starts where the running sum is still exactly 0 (its window
    holds only zeros) and ends after the last non-zero input, so every value inside sees the
    same additions in the same order. (Only the values at mask cells are used: outside the
    mask but inside the box they are the same too.)
    """
    rows = np.flatnonzero(mask.any(axis=1))
    if rows.size == 0:
        return None
    cols = np.flatnonzero(mask.any(axis=0))
    m = size // 2 + 1
    return (slice(max(int(rows[0]) - m, 0), min(int(rows[-1]) + m + 1, mask.shape[0])),
            slice(max(int(cols[0]) - m, 0), min(int(cols[-1]) + m + 1, mask.shape[1])))


def dip_of(t_row: np.ndarray, t_col: np.ndarray) -> np.ndarray:
    """Dip (degrees from horizontal, 0..90) of a tangent (row, col) on square cells."""
    return np.degrees(np.arctan2(np.abs(t_row), np.abs(t_col)))


def rung_fraction(skel: np.ndarray, window: int = DIRECTION_WINDOW, max_deg: float = 12.0) -> float:
    """Share of skeleton cells whose direction fitted over ``window`` x ``window`` is within
    ``max_deg`` of horizontal (the "rungs" of issue 13). NaN for an empty skeleton."""
    s = np.asarray(skel, dtype=bool)
    if not s.any():
        return float("nan")
    t_r, t_c = local_direction(s, window)
    return float((dip_of(t_r, t_c)[s] <= max_deg).mean())


def loop_count(skel: np.ndarray) -> int:
    """Number of closed loops of a line mask: background regions it encloses (4-connected)."""
    s = np.asarray(skel, dtype=bool)
    holes = ndimage.binary_fill_holes(s) & ~s
    return int(ndimage.label(holes)[1])


def trace_instances(skel: np.ndarray, link_angle_deg: float = 35.0,
                    gap_cells: float = 8.0) -> np.ndarray:
    """Fault ids of a one-cell-wide trace network (0 off the trace, 1.. by size).

    Branches are the 8-connected pieces left when the junction cells (crossing number >= 3)
    and their neighbours are removed. At each junction, pairs of branches that continue each
    other (their directions away from the junction within ``link_angle_deg`` of opposite) are
    joined, the straightest pair first; every other branch is a fault of its own. Two branch
    ends at most ``gap_cells`` apart that face each other (each end's direction within
    ``link_angle_deg`` of the line joining them) are one fault across the gap. Junction
    cells take the id of the nearest branch cell.
    """
    s = np.asarray(skel, dtype=bool)
    out = np.zeros(s.shape, dtype=np.int32)
    if not s.any():
        return out
    # a crossing drawn as a 2 x 2 block has crossing number 2 everywhere: 4+ neighbours too
    nbrs = ndimage.convolve(s.astype(np.int32), np.ones((3, 3), np.int32), mode="constant") - 1
    junction = ((crossing_number(s) >= 3) | (nbrs >= 4)) & s
    zone = ndimage.binary_dilation(junction, structure=_EIGHT) & s
    body = s & ~zone
    blab, nb = ndimage.label(body, structure=_EIGHT)
    if nb == 0:
        lab, _ = ndimage.label(s, structure=_EIGHT)
        return _by_size(lab)
    parent = np.arange(nb + 1)

    def find(a: int) -> int:
        while parent[a] != a:
            parent[a] = parent[parent[a]]
            a = parent[a]
        return a

    cos_max = -np.cos(np.radians(link_angle_deg))
    zlab, nz_ = ndimage.label(zone, structure=_EIGHT)
    br_r, br_c = np.nonzero(blab)
    br_l = blab[br_r, br_c]
    reach = 8.0
    tree = cKDTree(np.column_stack([br_r, br_c]).astype(np.float64))

    def within(pr: float, pc: float) -> np.ndarray:
        """Branch cells within ``reach`` of (pr, pc), in the order of np.nonzero."""
        cand = np.array(sorted(tree.query_ball_point((pr, pc), reach + 1e-6)), dtype=np.int64)
        if cand.size == 0:
            return cand
        return cand[(br_r[cand] - pr) ** 2 + (br_c[cand] - pc) ** 2 <= reach * reach]

    for z, sl in enumerate(ndimage.find_objects(zlab), start=1):
        if sl is None:
            continue
        zr, zc = np.nonzero(zlab[sl] == z)
        cr, cc = zr.mean() + sl[0].start, zc.mean() + sl[1].start
        r0, r1 = max(sl[0].start - 1, 0), min(sl[0].stop + 1, s.shape[0])
        c0, c1 = max(sl[1].start - 1, 0), min(sl[1].stop + 1, s.shape[1])
        near = (zlab[r0:r1, c0:c1] == z)
        ring = ndimage.binary_dilation(np.pad(near, 1), structure=_EIGHT)[1:-1, 1:-1]
        adj = np.unique(blab[r0:r1, c0:c1][ring & (blab[r0:r1, c0:c1] > 0)])
        if adj.size < 2:
            continue
        dirs = {}
        around = within(cr, cc)
        for b in adj:
            sel = around[br_l[around] == b]
            if not sel.size:
                continue
            d = np.array([br_r[sel].mean() - cr, br_c[sel].mean() - cc])
            nrm = np.hypot(*d)
            if nrm > 0:
                dirs[int(b)] = d / nrm
        keys = sorted(dirs)
        pairs = sorted((float(dirs[a] @ dirs[b]), a, b)
                       for i, a in enumerate(keys) for b in keys[i + 1:])
        used: set[int] = set()
        for cos_ab, a, b in pairs:
            if cos_ab > cos_max:
                break
            if a in used or b in used:
                continue
            used.update((a, b))
            parent[find(a)] = find(b)
    # pieces of one fault separated by a short gap: end points facing each other
    ends = np.argwhere((crossing_number(body) == 1) & body)
    if ends.shape[0] >= 2:
        e_lab = blab[ends[:, 0], ends[:, 1]]
        e_dir = np.zeros((ends.shape[0], 2))
        for q, (r_, c_) in enumerate(ends):  # direction from the piece into the gap
            sel = within(float(r_), float(c_))
            sel = sel[br_l[sel] == e_lab[q]]
            d = np.array([r_ - br_r[sel].mean(), c_ - br_c[sel].mean()])
            nrm = np.hypot(*d)
            e_dir[q] = d / nrm if nrm > 0 else 0.0
        cos_gap = np.cos(np.radians(link_angle_deg))
        # candidate pairs (a < b, lexicographic: the order fixes the union-find roots)
        close = sorted(cKDTree(ends.astype(np.float64)).query_pairs(gap_cells + 1e-6))
        for a, b in close:
            if e_lab[a] == e_lab[b]:
                continue
            v = (ends[b] - ends[a]).astype(np.float64)
            dist = np.hypot(*v)
            if dist == 0 or dist > gap_cells:
                continue
            v /= dist
            if e_dir[a] @ v >= cos_gap and -(e_dir[b] @ v) >= cos_gap:
                parent[find(int(e_lab[a]))] = find(int(e_lab[b]))
    roots = np.array([find(i) for i in range(nb + 1)])
    lab = roots[blab]
    lab[~body] = 0
    # junction cells: id of the nearest branch cell
    idx = ndimage.distance_transform_edt(lab == 0, return_distances=False, return_indices=True)
    fill = lab[idx[0], idx[1]]
    lab = np.where(zone, fill, lab)
    lab[~s] = 0
    return _by_size(lab)


def _by_size(lab: np.ndarray) -> np.ndarray:
    """Renumber positive labels 1.. by decreasing size (ties: lower old label first)."""
    ids, counts = np.unique(lab[lab > 0], return_counts=True)
    order = ids[np.lexsort((ids, -counts))]
    lut = np.zeros(int(lab.max()) + 1, dtype=np.int32)
    lut[order] = np.arange(1, order.size + 1, dtype=np.int32)
    return lut[lab]


def slip_traces(strain: np.ndarray, disp_x_m: np.ndarray, disp_y_m: np.ndarray,
                rock: np.ndarray, cell_m: float, config: LabelConfig | None = None,
                cohort: np.ndarray | None = None) -> Traces:
    """Fault traces of one section from its rasterised strain and displacement.

    Parameters
    ----------
    strain : (nz, nx) gamma_max on the grid (0 outside the rock).
    disp_x_m, disp_y_m : (nz, nx) element displacement since first appearance (m, x right,
        y up), rasterised like the strain.
    rock : (nz, nx) bool, cells inside the rock.
    cell_m : grid cell size (m); ``min_slip_m`` defaults to one cell.
    config : :class:`LabelConfig` (defaults if None).
    cohort : (nz, nx) int, first-appearance snapshot of each cell's element (None: one cohort).

    Returns
    -------
    :class:`Traces`.
    """
    cfg = (config or LabelConfig()).validate()
    strain = np.asarray(strain, dtype=np.float64)
    rock = np.asarray(rock, dtype=bool)
    shape = strain.shape
    for name, a in (("disp_x_m", disp_x_m), ("disp_y_m", disp_y_m), ("rock", rock)):
        if np.shape(a) != shape:
            raise InputError(f"{name} has shape {np.shape(a)}; expected {shape} like strain")
    min_slip = cfg.min_slip_for(cell_m)
    # voids inside the assembly (an opened gap along a fault) are rock for the tracing
    solid = rock
    rock = ndimage.binary_fill_holes(rock)
    if cohort is not None:
        cohort = np.asarray(cohort)
        idx = ndimage.distance_transform_edt(cohort < 0, return_distances=False,
                                             return_indices=True)
        cohort = np.where(rock, cohort[idx[0], idx[1]], -1)
    field = shear_field(disp_x_m, disp_y_m, rock, cell_m, cfg.ridge_sigma_cells, cohort)
    crest = crest_cells(field, rock, cfg)
    if crest.any():
        shift = centre_on_jump(crest, disp_x_m, disp_y_m, rock, cfg.slip_offset_cells)
        crest = project_on_local_line(crest, shift, int(cfg.centreline_window_cells)) & rock
        crest = remove_small_components(crest, cfg.min_trace_cells)
    crest_slip = np.full(shape, np.nan, dtype=np.float32)
    trace, slip = _slipping(crest, disp_x_m, disp_y_m, rock, cohort, 2, cfg.slip_offset_cells,
                            min_slip, cfg)
    crest_slip[crest] = slip[crest]
    strand = np.zeros(shape, dtype=bool)
    fine = None
    if cfg.strand_sigma_cells > 0 and trace.any():
        # the other slip surfaces of a wide shear zone: crests of the finer field more than
        # STRAND_SEPARATION_CELLS from a trace (the trace's own crest is there too)
        fine = shear_field(disp_x_m, disp_y_m, rock, cell_m, cfg.strand_sigma_cells, cohort)
        fcrest = crest_cells(fine, rock, cfg)
        fcrest &= ndimage.distance_transform_edt(~trace) > STRAND_SEPARATION_CELLS
        fcrest = _long_pieces(fcrest, STRAND_SPAN_CELLS)
        f_dir = local_direction(fcrest)
        strand, fslip = _slipping(fcrest, disp_x_m, disp_y_m, rock, cohort, 1, 2, min_slip, cfg,
                                  f_dir)
        # the two sides of a surface are blocks: the jump persists 3-4 cells out (around a
        # grain that moved against all its neighbours it does not)
        far, _ = _slipping(fcrest, disp_x_m, disp_y_m, rock, cohort, 3, 4, min_slip, cfg, f_dir)
        strand &= far
        strand = _long_pieces(strand, STRAND_SPAN_CELLS)
        crest_slip[fcrest] = fslip[fcrest]
        crest = crest | fcrest
        slip = np.where(strand, fslip, slip)
        trace = trace | strand
        for _ in range(3 if cfg.min_dip_deg > 0 else 0):
            # the direction of a strand next to a trace is the pair's: test the dip again, of
            # what is labelled (trace_targets leaves out the voids)
            shown = trace & solid
            t_r, t_c = local_direction(shown)
            flat = shown & (dip_of(t_r, t_c) < cfg.min_dip_deg)
            if not flat.any():
                break
            trace &= ~flat
        trace = remove_small_components(trace, cfg.min_trace_cells)
        strand &= trace
    if not trace.any():
        return Traces(trace=np.zeros(shape, bool), instance=np.zeros(shape, np.int32),
                      slip_m=np.zeros(shape, np.float32), dip_deg=np.zeros(shape, np.float32),
                      sense=np.zeros(shape, np.uint8), crest=crest, crest_slip_m=crest_slip)
    inst = trace_instances(trace & ~strand, cfg.link_angle_deg, LINK_GAP_CELLS)
    if strand.any():
        inst = _strand_instances(inst, strand, cfg.link_angle_deg)
    t_r, t_c = local_direction(trace)
    dip = dip_of(t_r, t_c)
    # sense: jump (upper side minus lower side) against the down-dip direction
    jump = _jump(trace & ~strand, t_r, t_c, disp_x_m, disp_y_m, rock, cfg.slip_offset_cells,
                 cohort)
    if strand.any():
        js = _jump(strand, t_r, t_c, disp_x_m, disp_y_m, rock, 2, cohort, k_min=1)
        jump = np.where(strand[..., None], js, jump)
    down_r, down_c = np.abs(t_r), np.where(t_r >= 0, t_c, -t_c)
    along = jump[..., 1] * down_r + jump[..., 2] * down_c
    sense = np.where(along >= 0, SENSE_NORMAL, SENSE_REVERSE).astype(np.uint8)
    z = ~trace
    slip_out = np.where(trace, slip, 0.0).astype(np.float32)
    dip_out = np.where(z, 0.0, dip).astype(np.float32)
    sense[z] = SENSE_NONE
    core = None
    if cfg.core_halfwidth_cells > 0:
        if fine is None or cfg.strand_sigma_cells != CORE_SIGMA_CELLS:
            fine = shear_field(disp_x_m, disp_y_m, rock, cell_m, CORE_SIGMA_CELLS, cohort)
        core = band_core(trace, t_r, t_c, fine, solid, cohort, int(cfg.core_halfwidth_cells))
    return Traces(trace=trace, instance=inst, slip_m=slip_out, dip_deg=dip_out, sense=sense,
                  crest=crest, crest_slip_m=crest_slip, core=core)


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
        mean = _along_trace_mean(trace, on_trace, trace, DIRECTION_WINDOW)
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
    return fill_small_holes(core, rock, hole_cells)


def fill_small_holes(mask: np.ndarray, rock: np.ndarray, max_cells: int) -> np.ndarray:
    """``mask`` with its holes (4-connected regions of non-mask cells enclosed by it) of at
    most ``max_cells`` cells filled, on ``rock`` cells only."""
    mask = np.asarray(mask, dtype=bool)
    if max_cells <= 0 or not mask.any():
        return mask.copy()
    lab, n = ndimage.label(ndimage.binary_fill_holes(mask) & ~mask)
    if not n:
        return mask.copy()
    small = np.bincount(lab.ravel(), minlength=n + 1) <= max_cells
    small[0] = False
    return mask | (small[lab] & np.asarray(rock, dtype=bool))


def _slipping(crest: np.ndarray, disp_x_m: np.ndarray, disp_y_m: np.ndarray, rock: np.ndarray,
              cohort: np.ndarray | None, k_min: int, k_max: int, min_slip: float,
              cfg: LabelConfig, direction: tuple[np.ndarray, np.ndarray] | None = None
              ) -> tuple[np.ndarray, np.ndarray]:
    """Crest cells that slip (step 2 of the module docstring) and the slip of every crest cell.

    Returns (trace cells: slip >= ``min_slip``, dip >= ``min_dip_deg``, pieces of at least
    ``min_trace_cells``; slip (m) along the crest, the jump for k = k_min..k_max averaged
    along it over 5 x 5 cells, NaN off the crest or where not measurable).
    """
    if not crest.any():
        return np.zeros(crest.shape, dtype=bool), np.full(crest.shape, np.nan)
    t_r, t_c = local_direction(crest) if direction is None else direction
    jump = _jump(crest, t_r, t_c, disp_x_m, disp_y_m, rock, k_max, cohort, k_min=k_min)
    slip = _along_trace_mean(crest, np.nan_to_num(jump[..., 0], nan=0.0),
                             np.isfinite(jump[..., 0]))
    slip = np.where(crest, slip, np.nan)
    trace = crest & (slip >= min_slip)
    if cfg.min_dip_deg > 0:
        trace &= dip_of(t_r, t_c) >= cfg.min_dip_deg
    return remove_small_components(trace, cfg.min_trace_cells), slip


def _long_pieces(cells: np.ndarray, min_cells: int) -> np.ndarray:
    """The 8-connected pieces of ``cells`` whose bounding box has a diagonal of at least
    ``min_cells`` cells (a strand is a surface, not the rim of one particle that moved
    against all its neighbours)."""
    lab, _ = ndimage.label(cells, structure=_EIGHT)
    keep = np.zeros(int(lab.max()) + 1, dtype=bool)
    for q, sl in enumerate(ndimage.find_objects(lab), start=1):
        keep[q] = np.hypot(sl[0].stop - sl[0].start, sl[1].stop - sl[1].start) >= min_cells
    keep[0] = False
    return keep[lab]


def _strand_instances(inst: np.ndarray, strand: np.ndarray, link_angle_deg: float) -> np.ndarray:
    """Fault ids with the strands: a strand whose cells lie mostly within STRAND_ZONE_CELLS of
    a trace is a surface of that fault's shear zone and takes its id (the commonest id of the
    nearest trace cells); the others are faults of their own (ids by
    :func:`trace_instances` among themselves). Renumbered 1.. by size."""
    out = inst.copy()
    own = trace_instances(strand, link_angle_deg, LINK_GAP_CELLS)
    if inst.any():
        dist, idx = ndimage.distance_transform_edt(inst == 0, return_indices=True)
        nearest = inst[idx[0], idx[1]]
    else:
        dist, nearest = np.full(inst.shape, np.inf), np.zeros_like(inst)
    lab, n = ndimage.label(strand, structure=_EIGHT)
    offset = int(inst.max())
    for q, sl in enumerate(ndimage.find_objects(lab), start=1):
        cells = lab[sl] == q
        d = dist[sl][cells]
        if np.median(d) <= STRAND_ZONE_CELLS:
            ids, counts = np.unique(nearest[sl][cells], return_counts=True)
            out[sl][cells] = ids[np.argmax(counts)]
        else:
            out[sl][cells] = own[sl][cells] + offset
    return _by_size(out)


def _jump(cells: np.ndarray, t_r: np.ndarray, t_c: np.ndarray, disp_x_m: np.ndarray,
          disp_y_m: np.ndarray, rock: np.ndarray, k_max: int,
          cohort: np.ndarray | None = None, k_min: int = 2) -> np.ndarray:
    """(nz, nx, 3) |jump|, jump row / col components at ``cells`` (NaN elsewhere), for the
    offsets k = k_min..k_max cells along the normal.

    The normal points to the upper side (row decreasing; column increasing for a vertical
    trace), so the jump is u(upper side) - u(lower side).
    """
    rows, cols = np.nonzero(cells)
    n_r, n_c = t_c[rows, cols].copy(), -t_r[rows, cols].copy()
    flip = (n_r > 0) | ((n_r == 0) & (n_c < 0))
    n_r[flip] *= -1.0
    n_c[flip] *= -1.0
    u_row = np.ascontiguousarray(-np.asarray(disp_y_m, dtype=np.float64))
    u_col = np.ascontiguousarray(np.asarray(disp_x_m, dtype=np.float64))
    res = np.empty((rows.size, 3))
    coh = np.zeros(cells.shape, np.int64) if cohort is None else cohort.astype(np.int64)
    _kernels.jump_across(u_row, u_col, np.ascontiguousarray(rock), np.ascontiguousarray(coh),
                         rows.astype(np.int64),
                         cols.astype(np.int64), n_r, n_c, int(k_min), max(int(k_max), int(k_min)), res)
    out = np.full((*cells.shape, 3), np.nan)
    out[rows, cols] = res
    return out


def _along_trace_mean(cells: np.ndarray, values: np.ndarray, ok: np.ndarray,
                      size: int = 5) -> np.ndarray:
    """Mean of ``values`` over the ``ok`` cells of ``cells`` in a size x size box (NaN if none;
    the value at a cell of ``cells`` is exact, elsewhere it may be NaN: see :func:`_support`)."""
    m = cells & ok
    out = np.full(cells.shape, np.nan)
    box_sl = _support(m, size)
    if box_sl is None:
        return out
    w = m[box_sl].astype(np.float64)
    num = ndimage.uniform_filter(values[box_sl] * w, size=size, mode="constant")
    den = ndimage.uniform_filter(w, size=size, mode="constant")
    with np.errstate(invalid="ignore", divide="ignore"):
        out[box_sl] = np.where(den > 1e-9, num / np.maximum(den, 1e-12), np.nan)
    return out
