"""Numba kernels of the labels stage. Plain arrays in, plain arrays out; SI units (metres).

Neighbour search uses a uniform cell list (counting sort of element indices by cell). The strain
kernel fits, per element, a least-squares deformation gradient to its neighbours' relative
positions. The thinning kernel is Guo-Hall (1989) two-subiteration parallel thinning.
"""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True)
def build_cell_list(x, y, cell):
    """Bin points into square cells of side ``cell`` (counting sort).

    Parameters
    ----------
    x, y : (n,) float64 point coordinates (m).
    cell : float, cell side (m), > 0.

    Returns
    -------
    x0, y0 : float, lower-left corner of cell (0, 0).
    ncx, ncy : int, number of cells in x and y.
    start : (ncx * ncy + 1,) int64; points of cell c are ``items[start[c]:start[c + 1]]``.
    items : (n,) int64 point indices sorted by cell (cell index c = cy * ncx + cx).
    """
    n = x.shape[0]
    x0 = x.min() if n > 0 else 0.0
    y0 = y.min() if n > 0 else 0.0
    x1 = x.max() if n > 0 else 0.0
    y1 = y.max() if n > 0 else 0.0
    ncx = int((x1 - x0) / cell) + 1
    ncy = int((y1 - y0) / cell) + 1
    counts = np.zeros(ncx * ncy + 1, dtype=np.int64)
    home = np.empty(n, dtype=np.int64)
    for i in range(n):
        cx = int((x[i] - x0) / cell)
        cy = int((y[i] - y0) / cell)
        if cx >= ncx:
            cx = ncx - 1
        if cy >= ncy:
            cy = ncy - 1
        c = cy * ncx + cx
        home[i] = c
        counts[c + 1] += 1
    start = np.cumsum(counts)
    fill = start[:-1].copy()
    items = np.empty(n, dtype=np.int64)
    for i in range(n):
        c = home[i]
        items[fill[c]] = i
        fill[c] += 1
    return x0, y0, ncx, ncy, start, items


@njit(cache=True)
def radius_neighbours(x, y, radius, factor):
    """Neighbours by distance: j is a neighbour of i when ``|p_j - p_i| <= factor * (r_i + r_j)``.

    Parameters
    ----------
    x, y : (n,) float64 reference centres (m).
    radius : (n,) float64 radii (m), > 0.
    factor : float, > 0; 1.0 selects touching disks, larger values reach further.

    Returns
    -------
    offsets : (n + 1,) int64; neighbours of i are ``index[offsets[i]:offsets[i + 1]]``.
    index : (m,) int64 neighbour indices, ascending within each element, never i itself.
    """
    n = x.shape[0]
    offsets = np.zeros(n + 1, dtype=np.int64)
    if n == 0:
        return offsets, np.empty(0, dtype=np.int64)
    cell = 2.0 * factor * radius.max()
    x0, y0, ncx, ncy, start, items = build_cell_list(x, y, cell)
    # pass 1: count
    for i in range(n):
        cx = min(int((x[i] - x0) / cell), ncx - 1)
        cy = min(int((y[i] - y0) / cell), ncy - 1)
        cnt = 0
        for gy in range(max(cy - 1, 0), min(cy + 2, ncy)):
            for gx in range(max(cx - 1, 0), min(cx + 2, ncx)):
                c = gy * ncx + gx
                for s in range(start[c], start[c + 1]):
                    j = items[s]
                    if j == i:
                        continue
                    dx = x[j] - x[i]
                    dy = y[j] - y[i]
                    lim = factor * (radius[i] + radius[j])
                    if dx * dx + dy * dy <= lim * lim:
                        cnt += 1
        offsets[i + 1] = offsets[i] + cnt
    index = np.empty(offsets[n], dtype=np.int64)
    # pass 2: fill
    for i in range(n):
        cx = min(int((x[i] - x0) / cell), ncx - 1)
        cy = min(int((y[i] - y0) / cell), ncy - 1)
        p = offsets[i]
        for gy in range(max(cy - 1, 0), min(cy + 2, ncy)):
            for gx in range(max(cx - 1, 0), min(cx + 2, ncx)):
                c = gy * ncx + gx
                for s in range(start[c], start[c + 1]):
                    j = items[s]
                    if j == i:
                        continue
                    dx = x[j] - x[i]
                    dy = y[j] - y[i]
                    lim = factor * (radius[i] + radius[j])
                    if dx * dx + dy * dy <= lim * lim:
                        index[p] = j
                        p += 1
        index[offsets[i]:offsets[i + 1]].sort()
    return offsets, index


@njit(cache=True)
def knn_neighbours(x, y, k):
    """The ``k`` nearest other points of every point (Euclidean), by expanding cell-list rings.

    Parameters
    ----------
    x, y : (n,) float64 reference centres (m).
    k : int, 1 <= k <= n - 1.

    Returns
    -------
    offsets : (n + 1,) int64, ``offsets[i] = i * k``.
    index : (n * k,) int64 neighbour indices of each point, nearest first (ties: lower index).
    """
    n = x.shape[0]
    offsets = np.arange(n + 1).astype(np.int64) * k
    index = np.empty(n * k, dtype=np.int64)
    if n == 0:
        return offsets, index
    w = max(x.max() - x.min(), 1e-12)
    h = max(y.max() - y.min(), 1e-12)
    # about 2 points per cell
    cell = np.sqrt(w * h * 2.0 / n)
    if cell <= 0.0:
        cell = 1.0
    x0, y0, ncx, ncy, start, items = build_cell_list(x, y, cell)
    bd = np.empty(k, dtype=np.float64)
    bi = np.empty(k, dtype=np.int64)
    maxring = max(ncx, ncy)
    for i in range(n):
        cx = min(int((x[i] - x0) / cell), ncx - 1)
        cy = min(int((y[i] - y0) / cell), ncy - 1)
        m = 0
        ring = 0
        while ring <= maxring:
            for gy in range(cy - ring, cy + ring + 1):
                if gy < 0 or gy >= ncy:
                    continue
                on_edge_y = gy == cy - ring or gy == cy + ring
                step = 1 if on_edge_y else 2 * ring
                gx = cx - ring
                while gx <= cx + ring:
                    if 0 <= gx < ncx:
                        c = gy * ncx + gx
                        for s in range(start[c], start[c + 1]):
                            j = items[s]
                            if j == i:
                                continue
                            dx = x[j] - x[i]
                            dy = y[j] - y[i]
                            d2 = dx * dx + dy * dy
                            if m < k:
                                pos = m
                                m += 1
                            elif d2 < bd[k - 1] or (d2 == bd[k - 1] and j < bi[k - 1]):
                                pos = k - 1
                            else:
                                continue
                            # insertion into the sorted buffer
                            while pos > 0 and (
                                bd[pos - 1] > d2 or (bd[pos - 1] == d2 and bi[pos - 1] > j)
                            ):
                                bd[pos] = bd[pos - 1]
                                bi[pos] = bi[pos - 1]
                                pos -= 1
                            bd[pos] = d2
                            bi[pos] = j
                    if step == 0:
                        break
                    gx += step
            # every point outside the rings scanned so far is at least ring * cell away
            if m == k and bd[k - 1] <= (ring * cell) * (ring * cell):
                break
            ring += 1
        for q in range(k):
            index[i * k + q] = bi[q]
    return offsets, index


@njit(cache=True)
def finite_strain(ref_x, ref_y, cur_x, cur_y, offsets, index, min_neighbours, cond_min,
                  out_f, out_gamma, out_vol, out_nn, out_valid):
    """Least-squares deformation gradient and finite strain of every element.

    For element i with neighbours j, dX_j = X_j - X_i (reference) and dx_j = x_j - x_i
    (current). F minimises sum_j |dx_j - F dX_j|^2, i.e. F = (sum dx dX^T)(sum dX dX^T)^-1.
    C = F^T F has eigenvalues lambda1 >= lambda2 (quadratic elongations) and
    gamma_max = (lambda1 - lambda2) / (2 sqrt(lambda1 lambda2)); volumetric = det(F) - 1
    (relative area change).

    Parameters
    ----------
    ref_x, ref_y, cur_x, cur_y : (n,) float64 reference and current centres (m).
    offsets, index : neighbour lists (CSR) from :func:`radius_neighbours` / :func:`knn_neighbours`.
    min_neighbours : int, fewer neighbours than this -> invalid.
    cond_min : float, invalid when the reference neighbour cloud is nearly collinear:
        eigmin(A) / eigmax(A) < cond_min with A = sum dX dX^T.
    out_f : (n, 2, 2) float64, written: F (NaN where invalid).
    out_gamma, out_vol : (n,) float64, written: gamma_max and det(F) - 1 (NaN where invalid).
    out_nn : (n,) int64, written: neighbour count.
    out_valid : (n,) bool, written: enough, non-collinear neighbours and det(F) > 0.
    """
    n = ref_x.shape[0]
    for i in range(n):
        a00 = 0.0
        a01 = 0.0
        a11 = 0.0
        b00 = 0.0
        b01 = 0.0
        b10 = 0.0
        b11 = 0.0
        nn = offsets[i + 1] - offsets[i]
        out_nn[i] = nn
        for s in range(offsets[i], offsets[i + 1]):
            j = index[s]
            dX = ref_x[j] - ref_x[i]
            dY = ref_y[j] - ref_y[i]
            dx = cur_x[j] - cur_x[i]
            dy = cur_y[j] - cur_y[i]
            a00 += dX * dX
            a01 += dX * dY
            a11 += dY * dY
            b00 += dx * dX
            b01 += dx * dY
            b10 += dy * dX
            b11 += dy * dY
        ok = nn >= min_neighbours and nn >= 2
        deta = a00 * a11 - a01 * a01
        tr = a00 + a11
        if ok:
            disc = np.sqrt(max((a00 - a11) * (a00 - a11) * 0.25 + a01 * a01, 0.0))
            emax = 0.5 * tr + disc
            emin = 0.5 * tr - disc
            if emax <= 0.0 or emin < cond_min * emax or deta <= 0.0:
                ok = False
        if ok:
            # F = B A^-1 with A^-1 = [[a11, -a01], [-a01, a00]] / det
            f00 = (b00 * a11 - b01 * a01) / deta
            f01 = (-b00 * a01 + b01 * a00) / deta
            f10 = (b10 * a11 - b11 * a01) / deta
            f11 = (-b10 * a01 + b11 * a00) / deta
            detf = f00 * f11 - f01 * f10
            if detf <= 0.0:
                ok = False
        if not ok:
            out_valid[i] = False
            out_gamma[i] = np.nan
            out_vol[i] = np.nan
            out_f[i, 0, 0] = np.nan
            out_f[i, 0, 1] = np.nan
            out_f[i, 1, 0] = np.nan
            out_f[i, 1, 1] = np.nan
            continue
        # C = F^T F
        c00 = f00 * f00 + f10 * f10
        c01 = f00 * f01 + f10 * f11
        c11 = f01 * f01 + f11 * f11
        half_diff = np.sqrt((c00 - c11) * (c00 - c11) * 0.25 + c01 * c01)
        # lambda1 - lambda2 = 2 half_diff; lambda1 lambda2 = det(C) = det(F)^2
        out_gamma[i] = half_diff / detf
        out_vol[i] = detf - 1.0
        out_f[i, 0, 0] = f00
        out_f[i, 0, 1] = f01
        out_f[i, 1, 0] = f10
        out_f[i, 1, 1] = f11
        out_valid[i] = True


@njit(cache=True)
def power_nearest(x, y, radius, inflate, x0, top, cell, nz, nx, out_index):
    """Per grid cell, the element of least power distance d^2 - r^2 among those within reach.

    An element reaches a cell when the cell centre lies within ``inflate * r`` of its centre;
    the power distance picks the Laguerre (power-diagram) cell of polydisperse disks, so a cell
    in a gap between disks goes to the disk it is "most inside".

    Parameters
    ----------
    x, y, radius : (n,) float64 element centres (m, y up) and radii (m).
    inflate : float >= 1, reach as a multiple of the radius.
    x0, top, cell : grid left edge, top elevation and cell size (m).
    nz, nx : grid rows and columns.
    out_index : (nz, nx) int64, written: element index, -1 where no element reaches.
    """
    best = np.full((nz, nx), np.inf)
    out_index[:, :] = -1
    for e in range(x.shape[0]):
        rr = inflate * radius[e]
        r2 = radius[e] * radius[e]
        j0 = max(int(np.ceil((x[e] - rr - x0) / cell - 0.5)), 0)
        j1 = min(int(np.floor((x[e] + rr - x0) / cell - 0.5)), nx - 1)
        i0 = max(int(np.ceil((top - (y[e] + rr)) / cell - 0.5)), 0)
        i1 = min(int(np.floor((top - (y[e] - rr)) / cell - 0.5)), nz - 1)
        for i in range(i0, i1 + 1):
            dy = top - (i + 0.5) * cell - y[e]
            for j in range(j0, j1 + 1):
                dx = x0 + (j + 0.5) * cell - x[e]
                d2 = dx * dx + dy * dy
                if d2 <= rr * rr:
                    p = d2 - r2
                    if p < best[i, j]:
                        best[i, j] = p
                        out_index[i, j] = e


@njit(cache=True)
def guo_hall_thin(mask, lut1, lut2):
    """Guo-Hall (1989) two-subiteration parallel thinning (algorithm A1 of Lam, Lee & Suen 1992).

    Unlike Zhang-Suen it keeps two-cell-thick diagonal lines and 2x2 blocks.

    Parameters
    ----------
    mask : (nz, nx) uint8, 1 = foreground; not modified; outside the image is background.
    lut1, lut2 : (256,) bool deletion tables of the two subiterations, indexed by the
        neighbour code sum(bit_k << k) with k = 0..7 for E, NE, N, NW, W, SW, S, SE
        (see :func:`demseis.labels.masks.guo_hall_luts`).

    Returns
    -------
    (nz, nx) uint8 skeleton.
    """
    nz, nx = mask.shape
    img = np.zeros((nz + 2, nx + 2), dtype=np.uint8)
    for i in range(nz):
        for j in range(nx):
            img[i + 1, j + 1] = 1 if mask[i, j] != 0 else 0
    rem_i = np.empty(nz * nx, dtype=np.int64)
    rem_j = np.empty(nz * nx, dtype=np.int64)
    changed = True
    while changed:
        changed = False
        for sub in range(2):
            m = 0
            for i in range(1, nz + 1):
                for j in range(1, nx + 1):
                    if img[i, j] == 0:
                        continue
                    code = (img[i, j + 1] | (img[i - 1, j + 1] << 1) | (img[i - 1, j] << 2)
                            | (img[i - 1, j - 1] << 3) | (img[i, j - 1] << 4)
                            | (img[i + 1, j - 1] << 5) | (img[i + 1, j] << 6)
                            | (img[i + 1, j + 1] << 7))
                    if (lut1[code] if sub == 0 else lut2[code]):
                        rem_i[m] = i
                        rem_j[m] = j
                        m += 1
            for q in range(m):
                img[rem_i[q], rem_j[q]] = 0
            if m > 0:
                changed = True
    return img[1:-1, 1:-1].copy()


@njit(cache=True)
def _bilinear_rock(f, rock, r, c):
    """Bilinear value of ``f`` at fractional (row, col) over the rock cells only.

    Weights of cells outside the grid or outside the rock are dropped and the rest
    renormalised; returns (value, ok) with ok False where no rock cell has weight.
    """
    nz, nx = f.shape
    i0 = int(np.floor(r))
    j0 = int(np.floor(c))
    fr = r - i0
    fc = c - j0
    acc = 0.0
    wsum = 0.0
    for di in range(2):
        wi = fr if di == 1 else 1.0 - fr
        i = i0 + di
        if i < 0 or i >= nz:
            continue
        for dj in range(2):
            wj = fc if dj == 1 else 1.0 - fc
            j = j0 + dj
            if j < 0 or j >= nx or not rock[i, j]:
                continue
            w = wi * wj
            if w <= 0.0:
                continue
            acc += w * f[i, j]
            wsum += w
    if wsum < 1e-9:
        return 0.0, False
    return acc / wsum, True


@njit(cache=True)
def ridge_nms(g, n_row, n_col, rock, threshold, out):
    """Non-maximum suppression of a ridge field across its local normal.

    A cell is a crest cell when it is in the rock, ``g >= threshold`` and ``g`` is not below
    its bilinear values one cell away on both sides along the unit normal (n_row, n_col).

    Parameters
    ----------
    g : (nz, nx) float64 smoothed strain.
    n_row, n_col : (nz, nx) float64 unit normal of the ridge (row and column components).
    rock : (nz, nx) bool, cells inside the rock.
    threshold : float, smallest crest value.
    out : (nz, nx) uint8, written: 1 = crest.
    """
    nz, nx = g.shape
    for i in range(nz):
        for j in range(nx):
            out[i, j] = 0
            v = g[i, j]
            if not rock[i, j] or v < threshold:
                continue
            a, oka = _bilinear_rock(g, rock, i + n_row[i, j], j + n_col[i, j])
            b, okb = _bilinear_rock(g, rock, i - n_row[i, j], j - n_col[i, j])
            if (not oka or v >= a) and (not okb or v >= b):
                out[i, j] = 1


@njit(cache=True)
def jump_across(u_row, u_col, rock, cohort, rows, cols, n_row, n_col, k_min, k_max, out):
    """Largest displacement jump across each trace point along its normal.

    For k = k_min..k_max cells the displacement (bilinear over rock cells) is sampled at
    p + k n and p - k n; the jump is u(p + k n) - u(p - k n). The k with the largest |jump|
    whose two samples both lie in the rock is kept.

    Parameters
    ----------
    u_row, u_col : (nz, nx) float64 displacement components (m) along rows (down) and columns.
    rock : (nz, nx) bool.
    cohort : (nz, nx) int64 first-appearance snapshot of each cell's element; an offset
        counts only where the cells nearest the two samples belong to the same cohort
        (displacements of different cohorts have different references).
    rows, cols : (m,) int64 trace cells.
    n_row, n_col : (m,) float64 unit normals of the trace at those cells.
    k_min, k_max : int, offsets (cells) tried, 1 <= k_min <= k_max.
    out : (m, 3) float64, written: |jump| (m), jump row and column components (m); NaN where
        no offset has both samples in the rock.
    """
    for q in range(rows.shape[0]):
        best = -1.0
        br = np.nan
        bc = np.nan
        for k in range(k_min, k_max + 1):
            ra = rows[q] + k * n_row[q]
            ca = cols[q] + k * n_col[q]
            rb = rows[q] - k * n_row[q]
            cb = cols[q] - k * n_col[q]
            ua_r, ok1 = _bilinear_rock(u_row, rock, ra, ca)
            ua_c, ok2 = _bilinear_rock(u_col, rock, ra, ca)
            ub_r, ok3 = _bilinear_rock(u_row, rock, rb, cb)
            ub_c, ok4 = _bilinear_rock(u_col, rock, rb, cb)
            if not (ok1 and ok2 and ok3 and ok4):
                continue
            nz, nx = cohort.shape
            ia = min(max(int(np.rint(ra)), 0), nz - 1)
            ja = min(max(int(np.rint(ca)), 0), nx - 1)
            ib = min(max(int(np.rint(rb)), 0), nz - 1)
            jb = min(max(int(np.rint(cb)), 0), nx - 1)
            if cohort[ia, ja] != cohort[ib, jb]:
                continue
            dr = ua_r - ub_r
            dc = ua_c - ub_c
            m = np.sqrt(dr * dr + dc * dc)
            if m > best:
                best = m
                br = dr
                bc = dc
        out[q, 0] = best if best >= 0.0 else np.nan
        out[q, 1] = br
        out[q, 2] = bc


@njit(cache=True)
def sample_profiles(u_row, u_col, rock, rows, cols, n_row, n_col, ts, out):
    """Displacement profiles along the normals of line cells.

    Parameters
    ----------
    u_row, u_col : (nz, nx) float64 displacement components (rows down, columns).
    rock : (nz, nx) bool.
    rows, cols : (m,) int64 line cells; n_row, n_col : (m,) float64 unit normals.
    ts : (k,) float64 offsets along the normal (cells).
    out : (m, k, 2) float64, written: (u_row, u_col) at p + t n (bilinear over rock cells);
        NaN where no rock cell is in reach.
    """
    for q in range(rows.shape[0]):
        for a in range(ts.shape[0]):
            r = rows[q] + ts[a] * n_row[q]
            c = cols[q] + ts[a] * n_col[q]
            vr, ok1 = _bilinear_rock(u_row, rock, r, c)
            vc, ok2 = _bilinear_rock(u_col, rock, r, c)
            if ok1 and ok2:
                out[q, a, 0] = vr
                out[q, a, 1] = vc
            else:
                out[q, a, 0] = np.nan
                out[q, a, 1] = np.nan


@njit(cache=True)
def thin_path(rows, cols):
    """Which pixels of an ordered digital path to keep so that it is one pixel wide.

    Parameters
    ----------
    rows, cols : (n,) int64 pixel coordinates in order along the path; consecutive pixels
        are equal or 8-neighbours.

    Returns
    -------
    (n,) bool. The kept pixels form a stack: each pixel of the path is pushed unless it
    repeats the top, after popping the top while the pixel below the top is an 8-neighbour
    of it (the corner of an L step, or a detour back). So the kept pixels start and end where
    the path does, consecutive kept pixels are 8-neighbours, and no two pixels two apart
    along the kept path touch (no corners, no pixel with two touching path neighbours).
    """
    n = rows.shape[0]
    keep = np.zeros(n, dtype=np.bool_)
    stack = np.empty(n, dtype=np.int64)
    top = -1
    for i in range(n):
        if top >= 0 and rows[i] == rows[stack[top]] and cols[i] == cols[stack[top]]:
            continue
        while top >= 1 and abs(rows[i] - rows[stack[top - 1]]) <= 1 \
                and abs(cols[i] - cols[stack[top - 1]]) <= 1:
            top -= 1
        if top >= 0 and rows[i] == rows[stack[top]] and cols[i] == cols[stack[top]]:
            continue                                  # back at a kept pixel (a detour)
        top += 1
        stack[top] = i
    for k in range(top + 1):
        keep[stack[k]] = True
    return keep
