"""Numba kernels of the reference baseline fault detector (see :mod:`demseis.evaluation.baseline`)."""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True)
def dip_scan_semblance(section, slopes, half_traces, half_samples, eps):
    """Maximum over trial slopes of the semblance in a sliding window (Marfurt et al., 1998).

    For each pixel (iz, ix) and slope p (samples per trace), the window holds the traces
    ix-half_traces..ix+half_traces and, on trace ix+dx, the samples iz+dz+p*dx for
    dz = -half_samples..half_samples (linear interpolation between samples). With u the window
    values and m_z the number of traces inside the section at row dz::

        c(p) = (sum_dz (sum_dx u)^2 + eps) / (sum_dz m_z sum_dx u^2 + eps)

    which lies in [0, 1] (Cauchy-Schwarz); 1 means identical traces along slope p. ``eps``
    keeps quiet windows (no reflector) at c close to 1 instead of noise-dominated values.

    Parameters
    ----------
    section : ndarray, shape (nz, nx), float32 or float64
        Seismic section, rows are depth (or time) samples, columns are traces.
    slopes : ndarray, shape (n_slopes,), float64
        Trial slopes in samples per trace.
    half_traces, half_samples : int
        Window half-widths in traces and samples.
    eps : float
        Regularisation added to numerator and denominator (units of amplitude squared).

    Returns
    -------
    ndarray, shape (nz, nx), float32
        max_p c(p) at every pixel.
    """
    nz, nx = section.shape
    # The window sum over dz of row terms separates: row z' = iz + dz of the window only depends
    # on z' (and the slope), so row terms are computed once per (slope, z', ix) and summed with
    # a running window, O(n_slopes nz nx (2 half_traces + 1)) instead of that times the height.
    nrow = nz + 2 * half_samples
    best = np.zeros((nz, nx))
    num_row = np.empty(nrow)
    den_row = np.empty(nrow)
    for k in range(slopes.shape[0]):
        p = slopes[k]
        for ix in range(nx):
            for r in range(nrow):
                zr = r - half_samples  # row index z' of the window, may lie outside the section
                s = 0.0
                e = 0.0
                m = 0
                for dx in range(-half_traces, half_traces + 1):
                    jx = ix + dx
                    if jx < 0 or jx >= nx:
                        continue
                    z = zr + p * dx
                    if z < 0.0 or z > nz - 1:
                        continue
                    z0 = int(np.floor(z))
                    f = z - z0
                    z1 = z0 + 1 if z0 + 1 < nz else z0
                    v = (1.0 - f) * section[z0, jx] + f * section[z1, jx]
                    s += v
                    e += v * v
                    m += 1
                num_row[r] = s * s
                den_row[r] = m * e
            # window of pixel iz covers rows r = iz .. iz + 2 half_samples
            num = 0.0
            den = 0.0
            for r in range(2 * half_samples + 1):
                num += num_row[r]
                den += den_row[r]
            for iz in range(nz):
                if iz > 0:
                    num += num_row[iz + 2 * half_samples] - num_row[iz - 1]
                    den += den_row[iz + 2 * half_samples] - den_row[iz - 1]
                c = (num + eps) / (den + eps)
                if c > best[iz, ix]:
                    best[iz, ix] = c
    return best.astype(np.float32)
