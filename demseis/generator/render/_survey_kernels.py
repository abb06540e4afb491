"""Numba kernels of :mod:`demseis.generator.render.survey` (plain arrays in, plain arrays out)."""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True)
def interpolate_reference(rows, depth, x0c, y0c, unitc, jump_m, x0, y0, unit):
    """Fill (nz, nx) ``x0, y0, unit`` from the maps evaluated at ``rows`` (ascending, first 0,
    last nz - 1): linear between two evaluated rows whose reference y differ by their depth
    difference within ``jump_m`` and whose units agree, else the nearer row's map moved by the
    depth between them (see :func:`demseis.generator.render.survey.reference_points`)."""
    nz, nx = x0.shape
    k = 0
    for i in range(nz):
        while k < rows.size - 2 and rows[k + 1] <= i:
            k += 1
        lo = rows[k]
        hi = rows[k + 1]
        w = (i - lo) / (hi - lo)
        dz = depth[hi] - depth[lo]
        for j in range(nx):
            ya = y0c[k, j]
            yb = y0c[k + 1, j]
            if abs((ya - yb) - dz) <= jump_m and unitc[k, j] == unitc[k + 1, j]:
                x0[i, j] = (1.0 - w) * x0c[k, j] + w * x0c[k + 1, j]
                y0[i, j] = (1.0 - w) * ya + w * yb
                unit[i, j] = unitc[k, j]
            elif w <= 0.5:
                x0[i, j] = x0c[k, j]
                y0[i, j] = ya - w * dz
                unit[i, j] = unitc[k, j]
            else:
                x0[i, j] = x0c[k + 1, j]
                y0[i, j] = yb + (1.0 - w) * dz
                unit[i, j] = unitc[k + 1, j]


@njit(cache=True)
def fill_column_gaps(v, above_value):
    """In place: NaN above a column's first finite value -> ``above_value``; NaN below it ->
    the nearest finite value of the column (the one below on a tie); an all-NaN column ->
    ``above_value``."""
    nz, nx = v.shape
    for j in range(nx):
        first = -1
        for i in range(nz):
            if np.isfinite(v[i, j]):
                first = i
                break
        if first < 0:
            for i in range(nz):
                v[i, j] = above_value
            continue
        for i in range(first):
            v[i, j] = above_value
        i = first + 1
        while i < nz:
            if np.isfinite(v[i, j]):
                i += 1
                continue
            start = i                      # a gap start .. end - 1, rock at start - 1
            while i < nz and not np.isfinite(v[i, j]):
                i += 1
            end = i
            for r in range(start, end):
                if end < nz and end - r <= r - (start - 1):
                    v[r, j] = v[end, j]
                else:
                    v[r, j] = v[start - 1, j]


@njit(cache=True)
def hold_small_steps(vp, rho, tol):
    """In place, down each column: a value whose relative change from the last kept one is at
    most ``tol`` in both Vp and density is replaced by the kept one (so that change makes no
    reflection); the error of any value is at most ``tol`` of it."""
    nz, nx = vp.shape
    for j in range(nx):
        kv = vp[0, j]
        kr = rho[0, j]
        for i in range(1, nz):
            if abs(vp[i, j] - kv) <= tol * kv and abs(rho[i, j] - kr) <= tol * kr:
                vp[i, j] = kv
                rho[i, j] = kr
            else:
                kv = vp[i, j]
                kr = rho[i, j]
