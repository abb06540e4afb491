"""Numba kernels of :mod:`demseis.dem.reference`: per-element local maps from current to
reference coordinates, and their blending at arbitrary points.

Plain arrays in, plain arrays out; metres, x right, y up. Every loop is serial and visits
elements and candidates in a fixed order, so the same inputs give the same bytes.

A map is stored as a (2, 3) array ``M = [A | b]``: ``ref = A @ cur + b``.
"""

from __future__ import annotations

import numpy as np
from numba import njit

#: fit kinds written to ``out_kind``
KIND_TRANSLATION = 0
KIND_RIGID = 1
KIND_AFFINE = 2


@njit(cache=True, inline="always")
def wendland(q):
    """Wendland C2 weight (1 - q)^4 (4 q + 1) for q in [0, 1], 0 beyond."""
    if q >= 1.0:
        return 0.0
    t = 1.0 - q
    t2 = t * t
    return t2 * t2 * (4.0 * q + 1.0)


@njit(cache=True)
def _fit(cx, cy, rx, ry, w, use, m, min_affine, cond_min, out):
    """Weighted least-squares map ``r ~ A c + b`` over the points with ``use`` set.

    Affine when at least ``min_affine`` points, a well-spread cloud (eigmin / eigmax of the
    weighted covariance >= ``cond_min``) and singular values of A in [0.5, 2]; else rigid
    (2D Kabsch) when the cloud has any spread; else the translation of point 0. Writes
    ``out`` (2, 3) and returns the kind.
    """
    # one pass over coordinates relative to point 0 (short vectors: no cancellation)
    sw = 0.0
    mcx = 0.0
    mcy = 0.0
    mrx = 0.0
    mry = 0.0
    s00 = 0.0
    s01 = 0.0
    s11 = 0.0
    t00 = 0.0
    t01 = 0.0
    t10 = 0.0
    t11 = 0.0
    cnt = 0
    for a in range(m):
        if use[a]:
            wa = w[a]
            dcx = cx[a] - cx[0]
            dcy = cy[a] - cy[0]
            drx = rx[a] - rx[0]
            dry = ry[a] - ry[0]
            sw += wa
            mcx += wa * dcx
            mcy += wa * dcy
            mrx += wa * drx
            mry += wa * dry
            s00 += wa * dcx * dcx
            s01 += wa * dcx * dcy
            s11 += wa * dcy * dcy
            t00 += wa * drx * dcx
            t01 += wa * drx * dcy
            t10 += wa * dry * dcx
            t11 += wa * dry * dcy
            cnt += 1
    mcx /= sw
    mcy /= sw
    mrx /= sw
    mry /= sw
    # central moments
    s00 -= sw * mcx * mcx
    s01 -= sw * mcx * mcy
    s11 -= sw * mcy * mcy
    t00 -= sw * mrx * mcx
    t01 -= sw * mrx * mcy
    t10 -= sw * mry * mcx
    t11 -= sw * mry * mcy
    # back to absolute means
    mcx += cx[0]
    mcy += cy[0]
    mrx += rx[0]
    mry += ry[0]
    tr = s00 + s11
    disc = np.sqrt(max((s00 - s11) * (s00 - s11) * 0.25 + s01 * s01, 0.0))
    emax = 0.5 * tr + disc
    emin = 0.5 * tr - disc
    if cnt >= min_affine and emax > 0.0 and emin >= cond_min * emax:
        det = s00 * s11 - s01 * s01
        a00 = (t00 * s11 - t01 * s01) / det
        a01 = (-t00 * s01 + t01 * s00) / det
        a10 = (t10 * s11 - t11 * s01) / det
        a11 = (-t10 * s01 + t11 * s00) / det
        # singular values of A from |A|_F^2 and det A
        da = a00 * a11 - a01 * a10
        fro = a00 * a00 + a01 * a01 + a10 * a10 + a11 * a11
        h = np.sqrt(max(fro * fro * 0.25 - da * da, 0.0))
        smax = np.sqrt(max(0.5 * fro + h, 0.0))
        smin = np.sqrt(max(0.5 * fro - h, 0.0))
        if da > 0.0 and smin >= 0.5 and smax <= 2.0:
            out[0, 0] = a00
            out[0, 1] = a01
            out[1, 0] = a10
            out[1, 1] = a11
            out[0, 2] = mrx - a00 * mcx - a01 * mcy
            out[1, 2] = mry - a10 * mcx - a11 * mcy
            return KIND_AFFINE
    if cnt >= 2 and tr > 0.0:
        # rotation maximising sum w (R dc) . dr
        sdot = t00 + t11
        scross = t10 - t01
        th = np.arctan2(scross, sdot)
        c = np.cos(th)
        s = np.sin(th)
        out[0, 0] = c
        out[0, 1] = -s
        out[1, 0] = s
        out[1, 1] = c
        out[0, 2] = mrx - c * mcx + s * mcy
        out[1, 2] = mry - s * mcx - c * mcy
        return KIND_RIGID
    out[0, 0] = 1.0
    out[0, 1] = 0.0
    out[1, 0] = 0.0
    out[1, 1] = 1.0
    out[0, 2] = rx[0] - cx[0]
    out[1, 2] = ry[0] - cy[0]
    return KIND_TRANSLATION


@njit(cache=True)
def fit_element_maps(ref_x, ref_y, cur_x, cur_y, group, offsets, index, fit_radius, tol,
                     strain_tol, n_hypotheses, min_affine, cond_min, max_iter,
                     out_maps, out_used, out_kind):
    """Robust local map (current -> reference) of every element from its coherent neighbours.

    For element e the candidates are its neighbours j (``index[offsets[e]:offsets[e + 1]]``,
    current distance d_j < ``fit_radius``) of the same ``group``; point 0 is e itself.
    Weights are Wendland C2 of d_j / fit_radius (1 for e).

    1. Hypotheses: the translation of e, and the rigid motions anchored at e whose rotation
       turns (cur_j - cur_e) onto the direction of (ref_j - ref_e), for the ``n_hypotheses``
       nearest candidates j. A candidate is an inlier of a hypothesis when its residual
       |ref_k - H(cur_k)| <= tol + 2 strain_tol d_k; the hypothesis of largest inlier weight
       wins (ties: the first).
    2. Refinement: weighted least squares over e and the inliers (see :func:`_fit`), then
       inliers again with residual <= tol + strain_tol d_k, until the set stops changing or
       ``max_iter`` fits were made.

    Parameters
    ----------
    ref_x, ref_y, cur_x, cur_y : (n,) float64 reference and current centres (m).
    group : (n,) int64; only elements of one group are compared (e.g. birth snapshot).
    offsets, index : CSR neighbour lists in the current state (any order).
    fit_radius, tol, strain_tol : float, see above (m, m, dimensionless).
    n_hypotheses, min_affine, max_iter : int.
    cond_min : float, smallest eigmin / eigmax of the inliers' weighted covariance for affine.
    out_maps : (n, 2, 3) float64, written: [A | b] with ref = A cur + b.
    out_used : (n,) int64, written: points in the final fit (e included).
    out_kind : (n,) int8, written: 0 translation, 1 rigid, 2 affine.
    """
    n = ref_x.shape[0]
    cap = 1
    for e in range(n):
        cap = max(cap, offsets[e + 1] - offsets[e] + 1)
    cx = np.empty(cap)
    cy = np.empty(cap)
    rx = np.empty(cap)
    ry = np.empty(cap)
    dd = np.empty(cap)
    w = np.empty(cap)
    idx = np.empty(cap, dtype=np.int64)
    use = np.zeros(cap, dtype=np.bool_)
    new = np.zeros(cap, dtype=np.bool_)
    fit = np.empty((2, 3))
    for e in range(n):
        # candidates sorted by (distance, index), e first
        m = 1
        cx[0] = cur_x[e]
        cy[0] = cur_y[e]
        rx[0] = ref_x[e]
        ry[0] = ref_y[e]
        dd[0] = 0.0
        idx[0] = e
        for s in range(offsets[e], offsets[e + 1]):
            j = index[s]
            if j == e or group[j] != group[e]:
                continue
            dx = cur_x[j] - cur_x[e]
            dy = cur_y[j] - cur_y[e]
            d = np.sqrt(dx * dx + dy * dy)
            if d >= fit_radius:
                continue
            pos = m
            while pos > 1 and (dd[pos - 1] > d or (dd[pos - 1] == d and idx[pos - 1] > j)):
                cx[pos] = cx[pos - 1]
                cy[pos] = cy[pos - 1]
                rx[pos] = rx[pos - 1]
                ry[pos] = ry[pos - 1]
                dd[pos] = dd[pos - 1]
                idx[pos] = idx[pos - 1]
                pos -= 1
            cx[pos] = cur_x[j]
            cy[pos] = cur_y[j]
            rx[pos] = ref_x[j]
            ry[pos] = ref_y[j]
            dd[pos] = d
            idx[pos] = j
            m += 1
        for a in range(m):
            w[a] = wendland(dd[a] / fit_radius)
        w[0] = 1.0
        # 1. hypotheses anchored at e
        best = -1.0
        best_th = 0.0
        n_h = min(n_hypotheses, m - 1)
        for h in range(n_h + 1):
            th = 0.0
            if h > 0:
                ux = cx[h] - cx[0]
                uy = cy[h] - cy[0]
                vx = rx[h] - rx[0]
                vy = ry[h] - ry[0]
                th = np.arctan2(ux * vy - uy * vx, ux * vx + uy * vy)
            c = np.cos(th)
            s_ = np.sin(th)
            score = 0.0
            for a in range(m):
                ux = cx[a] - cx[0]
                uy = cy[a] - cy[0]
                ex = rx[0] + c * ux - s_ * uy - rx[a]
                ey = ry[0] + s_ * ux + c * uy - ry[a]
                if np.sqrt(ex * ex + ey * ey) <= tol + 2.0 * strain_tol * dd[a]:
                    score += w[a]
            if score > best:
                best = score
                best_th = th
        c = np.cos(best_th)
        s_ = np.sin(best_th)
        for a in range(m):
            ux = cx[a] - cx[0]
            uy = cy[a] - cy[0]
            ex = rx[0] + c * ux - s_ * uy - rx[a]
            ey = ry[0] + s_ * ux + c * uy - ry[a]
            use[a] = np.sqrt(ex * ex + ey * ey) <= tol + 2.0 * strain_tol * dd[a]
        use[0] = True
        # 2. refinement
        kind = KIND_TRANSLATION
        for _ in range(max_iter):
            kind = _fit(cx, cy, rx, ry, w, use, m, min_affine, cond_min, fit)
            same = True
            for a in range(m):
                ex = fit[0, 0] * cx[a] + fit[0, 1] * cy[a] + fit[0, 2] - rx[a]
                ey = fit[1, 0] * cx[a] + fit[1, 1] * cy[a] + fit[1, 2] - ry[a]
                new[a] = a == 0 or np.sqrt(ex * ex + ey * ey) <= tol + strain_tol * dd[a]
                if new[a] != use[a]:
                    same = False
            if same:
                break
            for a in range(m):
                use[a] = new[a]
        cnt = 0
        for a in range(m):
            if use[a]:
                cnt += 1
        for r in range(2):
            for q in range(3):
                out_maps[e, r, q] = fit[r, q]
        out_used[e] = cnt
        out_kind[e] = kind


@njit(cache=True, inline="always")
def cell_range(p_x, p_y, x0, y0, cell, ncx, ncy):
    """The cells of a cell list (origin ``x0, y0``, size ``cell``, ``ncx`` x ``ncy``) around
    the point's own: (gx0, gx1, gy0, gy1), inclusive and clipped to the list."""
    gx = int(np.floor((p_x - x0) / cell))
    gy = int(np.floor((p_y - y0) / cell))
    return max(gx - 1, 0), min(gx + 1, ncx - 1), max(gy - 1, 0), min(gy + 1, ncy - 1)


@njit(cache=True, inline="always")
def owner_of(cur_x, cur_y, radius, ncx, start, items, p_x, p_y, gx0, gx1, gy0, gy1, reach):
    """The element of least power distance ``|p - x_j|^2 - r_j^2`` among those of cells
    ``gx0..gx1`` x ``gy0..gy1`` of the cell list with ``|p - x_j| <= reach r_j`` (ties: the
    lowest index); -1 where there is none."""
    e = -1
    best = np.inf
    for by in range(gy0, gy1 + 1):
        for bx in range(gx0, gx1 + 1):
            c = by * ncx + bx
            for s in range(start[c], start[c + 1]):
                j = items[s]
                dx = p_x - cur_x[j]
                dy = p_y - cur_y[j]
                d2 = dx * dx + dy * dy
                rr = reach * radius[j]
                if d2 > rr * rr:
                    continue
                pw = d2 - radius[j] * radius[j]
                if pw < best or (pw == best and j < e):
                    best = pw
                    e = j
    return e


@njit(cache=True)
def blend_maps(cur_x, cur_y, radius, group, maps, x0, y0, cell, ncx, ncy, start, items,
               px, py, reach, support, agree_tol, out_ref, out_elem):
    """Reference coordinates of points by blending the element maps that agree at each point.

    For a point p the owner e is the element of least power distance |p - x_e|^2 - r_e^2
    among those with |p - x_e| <= ``reach`` r_e (ties: lowest index). The result is
    ``sum_j w_j M_j(p) / sum_j w_j`` over the elements j of e's group with |p - x_j| <
    ``support`` r_j, with w_j = Wendland(|p - x_j| / (support r_j)) g(delta_j / agree_tol),
    delta_j = |M_j(p) - M_e(p)| and g a taper: 1 up to 0.5, smoothstep down to 0 at 1
    (maps that disagree with e's at p take no part, so the result jumps across slip surfaces).

    Parameters
    ----------
    cur_x, cur_y, radius : (n,) float64 element centres and radii (m).
    group : (n,) int64 element groups; maps of other groups than e's are never blended.
    maps : (n, 2, 3) float64 element maps [A | b].
    x0, y0, cell, ncx, ncy, start, items : cell list of the centres (``build_cell_list`` of
        :mod:`demseis.labels`) with ``cell >= support * max(radius)``.
    px, py : (m,) float64 query points (m).
    reach, support, agree_tol : float (radii, radii, m).
    out_ref : (m, 2) float64, written: reference coordinates; NaN where no element reaches.
    out_elem : (m,) int64, written: owner e; -1 where no element reaches.
    """
    for q in range(px.shape[0]):
        p_x = px[q]
        p_y = py[q]
        gx0, gx1, gy0, gy1 = cell_range(p_x, p_y, x0, y0, cell, ncx, ncy)
        e = owner_of(cur_x, cur_y, radius, ncx, start, items, p_x, p_y, gx0, gx1, gy0, gy1,
                     reach)
        out_elem[q] = e
        if e < 0:
            out_ref[q, 0] = np.nan
            out_ref[q, 1] = np.nan
            continue
        fe_x = maps[e, 0, 0] * p_x + maps[e, 0, 1] * p_y + maps[e, 0, 2]
        fe_y = maps[e, 1, 0] * p_x + maps[e, 1, 1] * p_y + maps[e, 1, 2]
        sw = 0.0
        ax = 0.0
        ay = 0.0
        for by in range(gy0, gy1 + 1):
            for bx in range(gx0, gx1 + 1):
                c = by * ncx + bx
                for s in range(start[c], start[c + 1]):
                    j = items[s]
                    if group[j] != group[e]:
                        continue
                    dx = p_x - cur_x[j]
                    dy = p_y - cur_y[j]
                    sj = support * radius[j]
                    d2 = dx * dx + dy * dy
                    if d2 >= sj * sj:
                        continue
                    fx = maps[j, 0, 0] * p_x + maps[j, 0, 1] * p_y + maps[j, 0, 2]
                    fy = maps[j, 1, 0] * p_x + maps[j, 1, 1] * p_y + maps[j, 1, 2]
                    t = np.sqrt((fx - fe_x) ** 2 + (fy - fe_y) ** 2) / agree_tol
                    if t >= 1.0:
                        continue
                    g = 1.0
                    if t > 0.5:
                        u = 2.0 * (1.0 - t)
                        g = u * u * (3.0 - 2.0 * u)
                    wj = wendland(np.sqrt(d2) / sj) * g
                    sw += wj
                    ax += wj * fx
                    ay += wj * fy
        if sw > 0.0:
            out_ref[q, 0] = ax / sw
            out_ref[q, 1] = ay / sw
        else:
            out_ref[q, 0] = fe_x
            out_ref[q, 1] = fe_y


@njit(cache=True)
def crosses_barrier(ax, ay, bx, by, barrier, bx0, btop, bcell):
    """Whether the segment a -> b passes through a set cell of ``barrier`` (rows down from
    ``btop``, columns right from ``bx0``, square cells of ``bcell``), not counting a's cell.

    Every cell the segment passes through is visited (a grid traversal, Amanatides & Woo
    1987), so an 8-connected line of one-cell width is never stepped over diagonally (except
    by a segment through a cell corner exactly). The part of the segment outside the raster
    crosses nothing.
    """
    nz = barrier.shape[0]
    nx = barrier.shape[1]
    # grid coordinates: u along columns, v along rows (down)
    ua = (ax - bx0) / bcell
    va = (btop - ay) / bcell
    ub = (bx - bx0) / bcell
    vb = (btop - by) / bcell
    i = int(np.floor(va))
    j = int(np.floor(ua))
    i1 = int(np.floor(vb))
    j1 = int(np.floor(ub))
    du = ub - ua
    dv = vb - va
    sj = 1 if du > 0 else -1
    si = 1 if dv > 0 else -1
    if du != 0.0:
        nxt = (j + 1.0) if du > 0 else float(j)
        tmu = (nxt - ua) / du
        tdu = abs(1.0 / du)
    else:
        tmu = np.inf
        tdu = np.inf
    if dv != 0.0:
        nxt = (i + 1.0) if dv > 0 else float(i)
        tmv = (nxt - va) / dv
        tdv = abs(1.0 / dv)
    else:
        tmv = np.inf
        tdv = np.inf
    nsteps = abs(i1 - i) + abs(j1 - j)
    for _ in range(nsteps):
        if tmu < tmv:
            j += sj
            tmu += tdu
        else:
            i += si
            tmv += tdv
        if 0 <= i < nz and 0 <= j < nx and barrier[i, j]:
            return True
    return False


@njit(cache=True)
def blend_blocks(cur_x, cur_y, ref_x, ref_y, radius, group, x0, y0, cell, ncx, ncy, start,
                 items, px, py, reach, smooth, barrier, band, bx0, btop, bcell, out_ref,
                 out_elem):
    """Reference coordinates of points from the elements' displacements, smoothed within the
    blocks that a barrier raster (the labelled faults) bounds.

    For a point p the owner e is found as in :func:`blend_maps`. The displacement at p is a
    moving least-squares fit, linear in x and y, of the displacements ``cur_j - ref_j`` of the
    elements j of e's group with |p - x_j| < ``smooth``, weighted by Wendland(|p - x_j| /
    ``smooth``), among those whose centre is not in a ``band`` cell (the barriers and the
    rock beside them, whose slip is spread over a few elements) and that p reaches without
    crossing a barrier cell (:func:`crosses_barrier`); a mean where fewer than 3 such elements
    or their spread is degenerate, e's own displacement where none. The result is p minus it:
    the rock between barriers deforms smoothly at the scale ``smooth``, and only the barriers
    make jumps.

    Parameters
    ----------
    cur_x, cur_y, ref_x, ref_y, radius : (n,) float64 element centres in the current and the
        reference frame, radii (m).
    group : (n,) int64 element groups (birth cohorts); other groups than e's never take part.
    x0, y0, cell, ncx, ncy, start, items : cell list of the centres with ``cell >= smooth``
        and ``cell >= reach * max(radius)``.
    px, py : (m,) float64 query points (m).
    reach : a point's owner lies within ``reach`` radii of it.
    smooth : smoothing radius (m).
    barrier : (nz, nx) uint8 raster, non-zero on the barriers; bx0, btop, bcell its left edge,
        top edge (elevation) and cell size (m).
    band : (nz, nx) uint8 raster on the same grid, non-zero where elements take no part (the
        barrier cells at least).
    out_ref : (m, 2) float64, written: reference coordinates; NaN where no element reaches.
    out_elem : (m,) int64, written: owner e; -1 where no element reaches.
    """
    nz = barrier.shape[0]
    nx = barrier.shape[1]
    for q in range(px.shape[0]):
        p_x = px[q]
        p_y = py[q]
        gx0, gx1, gy0, gy1 = cell_range(p_x, p_y, x0, y0, cell, ncx, ncy)
        e = owner_of(cur_x, cur_y, radius, ncx, start, items, p_x, p_y, gx0, gx1, gy0, gy1,
                     reach)
        out_elem[q] = e
        if e < 0:
            out_ref[q, 0] = np.nan
            out_ref[q, 1] = np.nan
            continue
        # weighted sums for u(x) = u0 + G (x - p), over x relative to p
        sw = 0.0
        sx = 0.0
        sy = 0.0
        sxx = 0.0
        sxy = 0.0
        syy = 0.0
        su0 = 0.0
        sux = 0.0
        suy = 0.0
        sv0 = 0.0
        svx = 0.0
        svy = 0.0
        cnt = 0
        for by in range(gy0, gy1 + 1):
            for bx in range(gx0, gx1 + 1):
                c = by * ncx + bx
                for s in range(start[c], start[c + 1]):
                    j = items[s]
                    if group[j] != group[e]:
                        continue
                    dx = cur_x[j] - p_x
                    dy = cur_y[j] - p_y
                    d = np.sqrt(dx * dx + dy * dy)
                    if d >= smooth:
                        continue
                    ci = int(np.floor((btop - cur_y[j]) / bcell))
                    cj = int(np.floor((cur_x[j] - bx0) / bcell))
                    if 0 <= ci < nz and 0 <= cj < nx and band[ci, cj]:
                        continue
                    if crosses_barrier(p_x, p_y, cur_x[j], cur_y[j], barrier, bx0, btop,
                                       bcell):
                        continue
                    w = wendland(d / smooth)
                    if w <= 0.0:
                        continue
                    uj = cur_x[j] - ref_x[j]
                    vj = cur_y[j] - ref_y[j]
                    sw += w
                    sx += w * dx
                    sy += w * dy
                    sxx += w * dx * dx
                    sxy += w * dx * dy
                    syy += w * dy * dy
                    su0 += w * uj
                    sux += w * uj * dx
                    suy += w * uj * dy
                    sv0 += w * vj
                    svx += w * vj * dx
                    svy += w * vj * dy
                    cnt += 1
        if cnt == 0:
            out_ref[q, 0] = p_x - (cur_x[e] - ref_x[e])
            out_ref[q, 1] = p_y - (cur_y[e] - ref_y[e])
            continue
        u = su0 / sw
        v = sv0 / sw
        if cnt >= 3:
            # central second moments: a well-spread cloud gets the linear fit
            mx = sx / sw
            my = sy / sw
            cxx = sxx / sw - mx * mx
            cxy = sxy / sw - mx * my
            cyy = syy / sw - my * my
            tr = cxx + cyy
            det = cxx * cyy - cxy * cxy
            disc = np.sqrt(max(0.25 * tr * tr - det, 0.0))
            emin = 0.5 * tr - disc
            emax = 0.5 * tr + disc
            if emax > 0.0 and emin >= 0.05 * emax:
                # solve [[sw sx sy] [sx sxx sxy] [sy sxy syy]] [a0 ax ay] = rhs for u and v
                m00 = sw
                m01 = sx
                m02 = sy
                m11 = sxx
                m12 = sxy
                m22 = syy
                c00 = m11 * m22 - m12 * m12
                c01 = m02 * m12 - m01 * m22
                c02 = m01 * m12 - m02 * m11
                dt = m00 * c00 + m01 * c01 + m02 * c02
                if dt != 0.0:
                    u = (c00 * su0 + c01 * sux + c02 * suy) / dt
                    v = (c00 * sv0 + c01 * svx + c02 * svy) / dt
        out_ref[q, 0] = p_x - u
        out_ref[q, 1] = p_y - v
