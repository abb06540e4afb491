"""The crest of localised shear: where a section's slip surfaces run (step 1 of
:mod:`demseis.labels.traces`).

The element displacement, rasterised and smoothed per deposition cohort, gives a shear field
(:func:`shear_field`); its ridges, found along the Hessian's normal (:func:`ridge_normals`) by
non-maximum suppression, thinned and pruned, are the crest cells (:func:`crest_cells`). The
crest is then moved onto the centre of the displacement jump across it
(:func:`centre_on_jump`) and straightened along its length (:func:`project_on_local_line`).
"""

from __future__ import annotations

import numpy as np
from scipy import ndimage

from demseis.labels import _kernels
from demseis.labels.centreline import prune_spurs
from demseis.labels.config import LabelConfig
from demseis.labels.direction import box_support, local_direction
from demseis.labels.masks import EIGHT, remove_small_components, skeletonize


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
        box_sl = box_support(m_full, 2 * radius + 2)
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
    box_sl = box_support(c, window)  # the filters on the mask's box: same bits (see box_support)
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
    return skeletonize(ndimage.binary_dilation(out, structure=EIGHT))


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
