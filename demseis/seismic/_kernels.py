"""Numba kernels of the seismic stage. Plain arrays in, plain arrays out; SI units.

Every kernel here has a slow, obvious NumPy/SciPy reference in ``tests/seismic``.
"""

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
    when (xc - x_e)^2 + (yc - y_e)^2 <= r_e^2. The candidate cell range of each disk is widened
    by one cell on every side so that rounding in the bounds can never drop a cell whose centre
    lies exactly on a disk's rim; the distance test alone decides.
    """
    n = x.shape[0]
    k = values.shape[1]
    for e in range(n):
        r = radius[e]
        r2 = r * r
        fj0 = np.ceil((x[e] - r - x0) / cell - 0.5) - 1.0
        fj1 = np.floor((x[e] + r - x0) / cell - 0.5) + 1.0
        fi0 = np.ceil((top - (y[e] + r)) / cell - 0.5) - 1.0
        fi1 = np.floor((top - (y[e] - r)) / cell - 0.5) + 1.0
        # clamp in float first: elements far outside the grid must not overflow int
        if fj1 < 0.0 or fi1 < 0.0 or fj0 > nx - 1.0 or fi0 > nz - 1.0:
            continue
        j0 = max(int(fj0), 0)
        j1 = min(int(fj1), nx - 1)
        i0 = max(int(fi0), 0)
        i1 = min(int(fi1), nz - 1)
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


@njit(cache=True)
def divide_by_count(out_sum, count):
    """In place: ``out_sum[i, j, :] /= count[i, j]``, NaN where ``count[i, j] == 0``.

    out_sum : (nz, nx, k) float64; count : (nz, nx) int32.
    """
    nz, nx, k = out_sum.shape
    for i in range(nz):
        for j in range(nx):
            c = count[i, j]
            if c == 0:
                for q in range(k):
                    out_sum[i, j, q] = np.nan
            elif c > 1:
                inv = 1.0 / c
                for q in range(k):
                    out_sum[i, j, q] *= inv


@njit(cache=True)
def correlate_rows_cols(a, weights, out):
    """Separable correlation with a symmetric 1-D kernel along both axes, edge-replicated.

    Parameters
    ----------
    a : (nz, nx) float64 input field.
    weights : (2 h + 1,) float64 symmetric kernel (e.g. normalised Gaussian weights).
    out : (nz, nx) float64 output, written.

    Equals ``scipy.ndimage.correlate1d`` along axis 0 then axis 1 with ``mode="nearest"``
    (the boundary value is repeated), which is what ``scipy.ndimage.gaussian_filter`` does.
    """
    nz, nx = a.shape
    h = weights.shape[0] // 2
    tmp = np.empty((nz, nx))
    for i in range(nz):
        for j in range(nx):
            tmp[i, j] = 0.0
        for q in range(-h, h + 1):
            ii = min(max(i + q, 0), nz - 1)
            w = weights[q + h]
            for j in range(nx):
                tmp[i, j] += w * a[ii, j]
    for i in range(nz):
        for j in range(nx):
            s = 0.0
            for q in range(-h, h + 1):
                jj = min(max(j + q, 0), nx - 1)
                s += weights[q + h] * tmp[i, jj]
            out[i, j] = s


@njit(cache=True, inline="always")
def _med3(a, b, c):
    """Median of three values, branch-free."""
    return max(min(a, b), min(max(a, b), c))


@njit(cache=True)
def _median3(a, out):
    """3 x 3 median with edge replication (Paeth / Smith's network).

    Each column triple (rows i-1, i, i+1) is sorted once per row into lo <= mid <= hi; the
    median of the 9 values is med3(max(lo), med3(mid), min(hi)) over the three columns, which
    is exact for 9 values.
    """
    nz, nx = a.shape
    lo = np.empty(nx + 2)
    md = np.empty(nx + 2)
    hi = np.empty(nx + 2)
    for i in range(nz):
        up = max(i - 1, 0)
        dn = min(i + 1, nz - 1)
        for j in range(nx):
            x = a[up, j]
            y = a[i, j]
            z = a[dn, j]
            l1 = min(x, y)
            h1 = max(x, y)
            lo[j + 1] = min(l1, z)
            hz = max(l1, z)
            md[j + 1] = min(h1, hz)
            hi[j + 1] = max(h1, hz)
        lo[0] = lo[1]
        md[0] = md[1]
        hi[0] = hi[1]
        lo[nx + 1] = lo[nx]
        md[nx + 1] = md[nx]
        hi[nx + 1] = hi[nx]
        for j in range(nx):
            mx_lo = max(max(lo[j], lo[j + 1]), lo[j + 2])
            mn_hi = min(min(hi[j], hi[j + 1]), hi[j + 2])
            m_md = _med3(md[j], md[j + 1], md[j + 2])
            out[i, j] = _med3(mx_lo, m_md, mn_hi)


@njit(cache=True)
def median_filter_square(a, size, out):
    """Median over a ``size`` x ``size`` window (odd size), edge-replicated.

    Parameters
    ----------
    a : (nz, nx) float64 input field.
    size : odd window width in cells (3, 5, ...).
    out : (nz, nx) float64 output, written.

    Equals ``scipy.ndimage.median_filter(a, size, mode="nearest")``. The window is gathered
    into a small buffer and partially sorted by insertion (windows are tiny: 9 or 25 values).
    """
    nz, nx = a.shape
    if size == 3:
        _median3(a, out)
        return
    h = size // 2
    m = size * size
    mid = m // 2
    buf = np.empty(m)
    for i in range(nz):
        for j in range(nx):
            c = 0
            for p in range(-h, h + 1):
                ii = min(max(i + p, 0), nz - 1)
                for q in range(-h, h + 1):
                    jj = min(max(j + q, 0), nx - 1)
                    v = a[ii, jj]
                    # insertion into the sorted prefix buf[:c]
                    t = c
                    while t > 0 and buf[t - 1] > v:
                        buf[t] = buf[t - 1]
                        t -= 1
                    buf[t] = v
                    c += 1
            out[i, j] = buf[mid]


@njit(cache=True)
def _convolve_column(ts, a, t_col, tab, ih, hw, even, out_row):
    """One column of :func:`convolve_spikes` (``even``) or :func:`convolve_spikes_table`:
    ``out_row[q] = sum_i a[i] w(t_col[q] - ts[i])`` over ``|t - ts| < hw``. The spikes in
    each output's window are found with two moving pointers (both series ascend), then
    summed in a branch-free loop; ``u`` is the table coordinate, ``|t - ts| / step`` for an
    even table on [0, hw], ``(t - ts + hw) / step`` for a table on [-hw, hw]."""
    m = ts.shape[0]
    ntab = tab.shape[0]
    lo = 0
    hi = 0
    for q in range(t_col.shape[0]):
        t = t_col[q]
        while lo < m and ts[lo] <= t - hw:
            lo += 1
        if hi < lo:
            hi = lo
        while hi < m and ts[hi] < t + hw:
            hi += 1
        s = 0.0
        if even:
            for i in range(lo, hi):
                u = abs(t - ts[i]) * ih
                p = min(int(u), ntab - 2)
                w0 = tab[p]
                s += a[i] * (w0 + (u - p) * (tab[p + 1] - w0))
        else:
            for i in range(lo, hi):
                u = (t - ts[i] + hw) * ih
                p = min(max(int(u), 0), ntab - 2)
                w0 = tab[p]
                s += a[i] * (w0 + (u - p) * (tab[p + 1] - w0))
        out_row[q] = s


@njit(cache=True)
def convolve_spikes(t_spike, amp, t_out, tables, inv_step, half_s, out):
    """Continuous-time convolution of per-column spike trains with tabulated even wavelets.

    For every wavelet f, column c and output time t = t_out[c, q]::

        out[f, c, q] = sum_i amp[c, i] * w_f(t - t_spike[c, i])      over |t - t_spike| < half_s[f]

    which is equation (6) of the paper, s(t) = (r * w)(t), for r(t) = sum_i a_i delta(t - t_i),
    evaluated exactly at arbitrary (non-uniform) output times: no resampling of reflectivity.

    Parameters
    ----------
    t_spike : (nx, m) float64 spike (interface) two-way times per column (s), ascending.
    amp : (nx, m) float64 spike amplitudes (reflection coefficients).
    t_out : (nx, k) float64 output times per column (s), ascending.
    tables : (nf, ntab) float64, ``tables[f, p] = w_f(p / inv_step[f])`` for p = 0..ntab-1, the
        even wavelet tabulated on [0, half_s[f]] (``ntab - 1`` steps); linear interpolation.
    inv_step : (nf,) float64 reciprocal of the table step (1/s).
    half_s : (nf,) float64 wavelet half-width (s); beyond it the wavelet is taken as zero.
    out : (nf, nx, k) float64 output, written.
    """
    for f in range(tables.shape[0]):
        for c in range(t_spike.shape[0]):
            _convolve_column(t_spike[c], amp[c], t_out[c], tables[f], inv_step[f], half_s[f],
                             True, out[f, c])


@njit(cache=True)
def convolve_spikes_table(t_spike, amp, t_out, table, inv_step, half_s, out):
    """:func:`convolve_spikes` for one wavelet of any symmetry, tabulated on ``[-half, half]``.

    ``out[c, q] = sum_i amp[c, i] * w(t_out[c, q] - t_spike[c, i])`` over
    ``|t - t_spike| < half_s``, with ``table[p] = w(-half_s + p / inv_step)`` for
    p = 0..ntab-1 (linear interpolation). ``out`` : (nx, k) float64, written.
    """
    for c in range(t_spike.shape[0]):
        _convolve_column(t_spike[c], amp[c], t_out[c], table, inv_step, half_s, False, out[c])


@njit(cache=True)
def containing_cell(t_bottom, t_s, out):
    """Index of the cell whose two-way-time span contains each time sample, per column.

    Parameters
    ----------
    t_bottom : (nx, nz) float64 two-way time (s) of the bottom edge of every cell, ascending
        down each column; the top edge of cell 0 is at t = 0.
    t_s : (nt,) float64 output times (s), ascending.
    out : (nx, nt) int64 output, written: j with t_bottom[c, j-1] <= t < t_bottom[c, j]
        (t_bottom[c, -1] read as 0), or -1 when t < 0 or t >= t_bottom[c, nz-1].
    """
    nx, nz = t_bottom.shape
    nt = t_s.shape[0]
    for c in range(nx):
        j = 0
        for q in range(nt):
            t = t_s[q]
            if t < 0.0:
                out[c, q] = -1
                continue
            while j < nz and t_bottom[c, j] <= t:
                j += 1
            out[c, q] = j if j < nz else -1


@njit(cache=True)
def _nearest_one(px, py, x, y, order, start, bx0, by0, bsize, nbx, nby):
    """Index of the element centre nearest to (px, py); see :func:`nearest_element_cells`."""
    bx = int(np.floor((px - bx0) / bsize))
    by = int(np.floor((py - by0) / bsize))
    r_max = max(max(bx, nbx - 1 - bx), max(by, nby - 1 - by)) + 1
    fx = px - (bx0 + bx * bsize)
    fy = py - (by0 + by * bsize)
    d_edge = min(min(fx, bsize - fx), min(fy, bsize - fy))
    if d_edge < 0.0:
        d_edge = 0.0
    best = np.inf
    bi = -1
    ring = 0
    while True:
        for dy in range(-ring, ring + 1):
            iy = by + dy
            if iy < 0 or iy >= nby:
                continue
            step = 1 if (ring == 0 or dy == -ring or dy == ring) else 2 * ring
            dx = -ring
            while dx <= ring:
                ix = bx + dx
                if 0 <= ix < nbx:
                    b = iy * nbx + ix
                    for k in range(start[b], start[b + 1]):
                        e = order[k]
                        ddx = x[e] - px
                        ddy = y[e] - py
                        d2 = ddx * ddx + ddy * ddy
                        if d2 < best or (d2 == best and e < bi):
                            best = d2
                            bi = e
                dx += step
        lim = ring * bsize + d_edge
        if (bi >= 0 and best <= lim * lim) or ring >= r_max:
            return bi
        ring += 1


@njit(cache=True)
def nearest_element_cells(x, y, order, start, bx0, by0, bsize, nbx, nby, cx, cy, out_index):
    """Index of the element centre nearest to each query point (exact), via a bucket grid.

    Parameters
    ----------
    x, y : (n,) float64 element centres (m).
    order : (n,) int64 element indices sorted by bucket key ``by * nbx + bx``.
    start : (nbx * nby + 1,) int64, elements of bucket b are ``order[start[b]:start[b + 1]]``.
    bx0, by0, bsize : lower-left corner and side (m) of the bucket grid (covers all centres).
    nbx, nby : buckets along x and y.
    cx, cy : (m,) float64 query points (m), e.g. cell centres; anywhere, even off the buckets.
    out_index : (m,) int64 output, written.

    Buckets are searched ring by ring around the query's bucket; after ring R every
    unexamined element is at least R * bsize + d_edge away (d_edge: distance from the query to
    the edge of its own bucket), so the search stops once the best distance is within that.
    Ties keep the lowest element index (as a brute-force argmin).
    """
    for q in range(cx.shape[0]):
        out_index[q] = _nearest_one(cx[q], cy[q], x, y, order, start, bx0, by0, bsize, nbx, nby)


@njit(cache=True)
def fill_empty_from_layer(mean, count, x, y, order, start, bx0, by0, bsize, nbx, nby,
                          x0, top, cell, layer, layer_mean):
    """In place: every empty cell (count 0) of ``mean`` takes the mean values of the layer of
    the element whose centre is nearest to the cell centre.

    mean : (nz, nx, k) float64; count : (nz, nx) int32; x, y, order, start, bx0, by0, bsize,
    nbx, nby : the bucket grid of :func:`nearest_element_cells`; x0, top, cell : the grid (m);
    layer : (n,) int64 layer of each element; layer_mean : (L, k) float64 per-layer means.
    """
    nz, nx, k = mean.shape
    for i in range(nz):
        py = top - (i + 0.5) * cell
        for j in range(nx):
            if count[i, j] == 0:
                e = _nearest_one(x0 + (j + 0.5) * cell, py, x, y, order, start, bx0, by0, bsize,
                                 nbx, nby)
                L = layer[e]
                for q in range(k):
                    mean[i, j, q] = layer_mean[L, q]


@njit(cache=True)
def fill_empty_constant(mean, count, value):
    """In place: every empty cell (count 0) of ``mean`` (nz, nx, k) takes ``value`` (k,)."""
    nz, nx, k = mean.shape
    for i in range(nz):
        for j in range(nx):
            if count[i, j] == 0:
                for q in range(k):
                    mean[i, j, q] = value[q]


@njit(cache=True)
def strata_lookup(x, y, unit, unit_top, n_pre, unit_first_bed, bed_bottom, undulation,
                  und_bound, bed_vp, bed_rho, lat_amp_vp, lat_amp_rho, lateral, dx, out_vp,
                  out_rho):
    """Vp and density of the bed containing each reference point (x, y) of a stratigraphy.

    Parameters
    ----------
    x, y : (n,) float64 reference coordinates (m), y up.
    unit : (n,) int64 unit of each point, or -1: the pre-kinematic unit containing y
        (units 0 .. n_pre-1 bottom to top, contiguous; below the lowest: 0, above: n_pre-1).
    unit_top : (U,) float64 top of each unit (m).
    n_pre : number of pre-kinematic units (>= 1).
    unit_first_bed : (U + 1,) int64; the beds of unit u are unit_first_bed[u] .. [u + 1] - 1,
        bottom to top.
    bed_bottom : (B,) float64 nominal bottom of each bed (m), ascending within a unit.
    undulation : (B, K) float64 displacement (m) of each bed's bottom boundary at x = k dx
        (0 for the first bed of a unit: unit boundaries are flat).
    und_bound : (B,) float64 max |undulation[j]|: farther from the nominal boundary, the side
        of y is known without interpolating.
    bed_vp, bed_rho : (B,) float64 Vp (m/s) and density (kg/m^3) of each bed.
    lat_amp_vp, lat_amp_rho : relative amplitude of the lateral variation of Vp and density.
    lateral : (B, K) float64 each bed's lateral field (unit variance) at x = k dx.
    dx : table spacing (m); x is clamped to [0, (K - 1) dx].
    out_vp, out_rho : (n,) float64 output, written.

    Tables are read by linear interpolation, ``t[k] (1 - w) + t[k + 1] w``. Bed j holds the
    points with bottom_j(x) <= y < bottom_{j+1}(x) (the first bed of a unit also everything
    below, the last everything above). The nominal bed is found by binary search, then moved
    down or up while y lies across an undulating boundary.
    """
    n = x.shape[0]
    kmax = lateral.shape[1] - 2
    for i in range(n):
        yi = y[i]
        s = min(max(x[i] / dx, 0.0), kmax + 1.0)
        k = min(int(s), kmax)
        w = s - k
        u = unit[i]
        if u < 0:
            lo = 0
            hi = n_pre - 1
            while lo < hi:  # first pre-kinematic unit with y < its top (clamped to the last)
                mid = (lo + hi) // 2
                if yi < unit_top[mid]:
                    hi = mid
                else:
                    lo = mid + 1
            u = lo
        first = unit_first_bed[u]
        last = unit_first_bed[u + 1] - 1
        lo = first
        hi = last
        while lo < hi:  # last bed whose nominal bottom is <= y (clamped to the first)
            mid = (lo + hi + 1) // 2
            if bed_bottom[mid] <= yi:
                lo = mid
            else:
                hi = mid - 1
        j = lo
        while j > first and yi - bed_bottom[j] <= und_bound[j]:
            if yi >= bed_bottom[j] + (undulation[j, k] * (1.0 - w) + undulation[j, k + 1] * w):
                break
            j -= 1
        while j < last and bed_bottom[j + 1] - yi <= und_bound[j + 1]:
            if yi < bed_bottom[j + 1] + (undulation[j + 1, k] * (1.0 - w)
                                         + undulation[j + 1, k + 1] * w):
                break
            j += 1
        f = lateral[j, k] * (1.0 - w) + lateral[j, k + 1] * w
        out_vp[i] = bed_vp[j] * (1.0 + lat_amp_vp * f)
        out_rho[i] = bed_rho[j] * (1.0 + lat_amp_rho * f)
