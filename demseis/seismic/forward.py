"""Impedance, reflectivity, depth/time conversion and wavelet convolution (1-D, vertical incidence).

Depth and time
--------------
Row ``i`` of a grid spans depths ``[i c, (i + 1) c]`` below the grid top (cell size ``c``).
With the interval velocity ``vp[i]`` of each cell, the two-way time (TWT) of the *bottom
edge* of cell ``i`` is ``T_i = 2 sum_{k <= i} c / vp[k]`` and the TWT of its centre is
``T_i - c / vp[i]``; t = 0 is the grid top.

The reflection coefficient ``R_i = (Z_{i+1} - Z_i) / (Z_{i+1} + Z_i)`` belongs to the interface
between cells ``i`` and ``i + 1``, i.e. to the time ``T_i``. The section is the continuous
convolution of the spike series ``r(t) = sum_i R_i delta(t - T_i)`` with the wavelet,
``s(t) = sum_i R_i w(t - T_i)`` (the paper's equation 6), evaluated

- ``domain="depth"`` (default): at the TWT of every cell centre, so sample (i, j) of the
  section sits on cell (i, j) of the grid and labels stay pixel-aligned;
- ``domain="time"``: at a regular time axis ``t_s`` shared by a whole sweep (see
  :func:`time_axis`); per-cell fields (labels) go to the same axis with :func:`depth_to_time`.

Because spikes sit at their exact interface times and the wavelet is evaluated analytically
(interpolated in a fine table, error < 3e-7 of its peak), there is no resampling of
reflectivity to a time grid and back: the depth-domain result is what a regular-time
convolution converges to as its sample interval goes to zero (tested against a bruges-based
resampling path). No interpolation of the seismic itself is involved.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from demseis.errors import InputError
from demseis.seismic import _kernels
from demseis.seismic.wavelet import Wavelet, as_wavelets, ricker_table

TABLE_SIZE = 8192
"""Entries of the tabulated wavelet used by the convolution kernel."""


def impedance(vp: np.ndarray, rho: np.ndarray) -> np.ndarray:
    """Acoustic impedance ``Z = rho * vp`` (kg m^-2 s^-1) from Vp (m/s) and density (kg/m^3)."""
    vp = np.asarray(vp, dtype=np.float64)
    rho = np.asarray(rho, dtype=np.float64)
    if vp.shape != rho.shape:
        raise InputError(f"vp and rho must have the same shape, got {vp.shape} and {rho.shape}")
    return vp * rho


def reflectivity(impedance: np.ndarray, axis: int = 0) -> np.ndarray:
    """Normal-incidence reflection coefficients ``(Z2 - Z1) / (Z2 + Z1)`` along ``axis``.

    Parameters
    ----------
    impedance : array of acoustic impedances (> 0); ``axis`` runs down in depth (or time).
    axis : the depth axis.

    Returns
    -------
    float64 array of the same shape: element ``i`` along ``axis`` is the coefficient of the
    interface between samples ``i`` (Z1, above) and ``i + 1`` (Z2, below); the last is 0.
    This is ``bruges.reflection.acoustic_reflectivity(impedance, axis=axis)`` (mode "same").
    """
    z = np.asarray(impedance, dtype=np.float64)
    if z.ndim == 0:
        raise InputError("impedance must be an array with at least one axis, got a scalar")
    if not -z.ndim <= axis < z.ndim:
        raise InputError(f"axis {axis} is out of range for an impedance of shape {z.shape}")
    if not np.all(z > 0):
        raise InputError("impedance must be positive and finite everywhere")
    z = np.moveaxis(z, axis, 0)
    out = np.zeros_like(z)
    out[:-1] = (z[1:] - z[:-1]) / (z[1:] + z[:-1])
    return np.moveaxis(out, 0, axis)


def convolve(trace: np.ndarray, wavelet: np.ndarray, axis: int = -1) -> np.ndarray:
    """Convolve regularly sampled traces with a wavelet (or a wavelet bank), same length out.

    Parameters
    ----------
    trace : n-D array; ``axis`` is the (regularly sampled) time axis.
    wavelet : (n,) wavelet or (nf, n) bank, n odd, not longer than the trace axis.
    axis : time axis of ``trace``.

    Returns
    -------
    float64 array: ``trace.shape`` for one wavelet, ``(nf,) + trace.shape`` for a bank. It is
    the centred ("same") part of the full discrete convolution, like ``np.convolve(...,
    mode="same")`` and ``bruges.filters.convolve``.
    """
    # lazy: scipy.signal takes ~1 s to import; the render does not call this helper
    from scipy.signal import fftconvolve

    x = np.asarray(trace, dtype=np.float64)
    w = np.asarray(wavelet, dtype=np.float64)
    if w.ndim not in (1, 2) or w.shape[-1] % 2 == 0:
        raise InputError(f"wavelet must be (n,) or (nf, n) with n odd, got shape {w.shape}")
    if x.ndim == 0 or not -x.ndim <= axis < x.ndim:
        raise InputError(f"axis {axis} is out of range for a trace of shape {x.shape}")
    if w.shape[-1] > x.shape[axis]:
        raise InputError(
            f"wavelet ({w.shape[-1]} samples) is longer than the trace axis ({x.shape[axis]})"
        )
    xm = np.moveaxis(x, axis, -1)
    bank = np.atleast_2d(w)
    out = np.stack([fftconvolve(xm, wk.reshape((1,) * (xm.ndim - 1) + (-1,)), mode="same",
                                axes=-1) for wk in bank])
    out = np.moveaxis(out, -1, axis + 1 if axis >= 0 else axis)
    return out[0] if w.ndim == 1 else out


def _check_grids(vp_g: np.ndarray, rho_g: np.ndarray,
                 cell_m: float) -> tuple[np.ndarray, np.ndarray]:
    vp = np.asarray(vp_g, dtype=np.float64)
    rho = np.asarray(rho_g, dtype=np.float64)
    if vp.ndim != 2 or vp.shape != rho.shape:
        raise InputError(
            f"vp_g and rho_g must be (nz, nx) grids of one shape, got {vp.shape} and {rho.shape}"
        )
    if not (np.all(np.isfinite(vp)) and np.all(vp > 0)):
        raise InputError("vp_g must be finite and > 0 m/s everywhere")
    if not (np.all(np.isfinite(rho)) and np.all(rho > 0)):
        raise InputError("rho_g must be finite and > 0 kg/m^3 everywhere")
    if not (np.isfinite(cell_m) and cell_m > 0):
        raise InputError(f"cell_m must be a cell size > 0 m, got {cell_m!r}")
    return vp, rho


def _rows_per_cell(n: int, nz: int) -> int:
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 1 or n % 2 == 0 \
            or nz % n:
        raise InputError(f"rows_per_cell must be an odd integer >= 1 that divides the {nz} rows, "
                         f"got {n!r}")
    return int(n)


def _live_spikes(t_spike: np.ndarray, amp: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The (nx, m) spike trains without their zero spikes, when that removes at least half of
    them (a fine grid of blocky beds: most adjacent rows are the same bed). Each column keeps
    its non-zero spikes in order, padded with zero spikes at +inf, so times still ascend; the
    convolution adds the same terms in the same order (a zero term adds exactly nothing)."""
    live = amp != 0.0
    keep = int(live.sum(axis=1).max(initial=0))
    if keep > amp.shape[1] // 2:
        return t_spike, amp
    order = np.argsort(~live, axis=1, kind="stable")[:, :keep]
    t = np.take_along_axis(t_spike, order, axis=1)
    a = np.take_along_axis(amp, order, axis=1)
    pad = ~np.take_along_axis(live, order, axis=1)
    t[pad] = np.inf
    a[pad] = 0.0
    return np.ascontiguousarray(t), np.ascontiguousarray(a)


def coarse_velocity(vp: np.ndarray, n: int) -> np.ndarray:
    """The interval velocity of cells made of ``n`` consecutive rows of ``vp`` (rows, cols):
    the harmonic mean of the rows', so a cell's two-way time is the sum of its rows'."""
    v = np.asarray(vp, dtype=np.float64)
    return 1.0 / (1.0 / v).reshape(v.shape[0] // n, n, v.shape[1]).mean(axis=1)


def interface_times(vp_g: np.ndarray, cell_m: float) -> tuple[np.ndarray, np.ndarray]:
    """Two-way times of cell bottoms and cell centres below the grid top.

    Parameters
    ----------
    vp_g : (nz, nx) interval velocity (m/s) per cell, row 0 at the top.
    cell_m : cell size (m).

    Returns
    -------
    t_bottom : (nz, nx) float64, ``2 sum_{k <= i} cell / vp[k]`` (s).
    t_centre : (nz, nx) float64, ``t_bottom - cell / vp`` (s).
    """
    vp = np.asarray(vp_g, dtype=np.float64)
    if vp.ndim != 2 or not np.all(vp > 0):
        raise InputError(f"vp_g must be an (nz, nx) grid of velocities > 0, got shape {vp.shape}")
    slow = cell_m / vp
    t_bottom = 2.0 * np.cumsum(slow, axis=0)
    return t_bottom, t_bottom - slow


def time_axis(nz: int, cell_m: float, vp_min_m_s: float, dt_s: float = 0.002) -> np.ndarray:
    """A regular two-way-time axis long enough for any ``nz``-cell column with Vp >= vp_min_m_s.

    ``t_s = k dt_s`` for ``k = 0 .. ceil(2 nz cell / (vp_min dt))``: the deepest cell bottom
    of any such column is at most ``2 nz cell / vp_min``. With ``vp_min_m_s =
    PropertyModel.vp_lower_bound_m_s`` (the smallest Vp any element or smoothed cell can take),
    the axis depends only on the grid, the property model and ``dt_s``, so every sample of a
    sweep shares one time-domain shape. Samples below a column's deepest interface are still
    computed (the wavelet tail), then zero.

    Parameters
    ----------
    nz : rows of the grid.
    cell_m : cell size (m).
    vp_min_m_s : the smallest Vp any cell can have (m/s).
    dt_s : sample interval (s); 2 ms resolves Rickers up to ~60-80 Hz (Nyquist 250 Hz).

    Returns
    -------
    (nt,) float64 times (s), starting at 0 (the grid top).
    """
    if not (isinstance(nz, (int, np.integer)) and nz > 0):
        raise InputError(f"nz must be a positive integer, got {nz!r}")
    for name, val in (("cell_m", cell_m), ("vp_min_m_s", vp_min_m_s), ("dt_s", dt_s)):
        if not (np.isfinite(val) and val > 0):
            raise InputError(f"{name} must be finite and > 0, got {val!r}")
    t_max = 2.0 * nz * cell_m / vp_min_m_s
    nt = int(math.ceil(t_max / dt_s - 1e-9)) + 1
    return np.arange(nt) * float(dt_s)


def depth_to_time(field: np.ndarray, vp_g: np.ndarray, cell_m: float, t_s: np.ndarray,
                  method: str = "nearest", fill=0) -> np.ndarray:
    """Map a per-cell depth field (labels, strain, impedance ...) to a TWT axis.

    Parameters
    ----------
    field : (nz, nx) per-cell values on the grid of ``vp_g``.
    vp_g : (nz, nx) interval velocity (m/s).
    cell_m : cell size (m).
    t_s : (nt,) ascending output times (s), e.g. from :func:`time_axis`.
    method : ``"nearest"`` gives each time sample the value of the cell whose TWT span contains
        it (exact for blocky fields; use it for integer labels, the dtype is kept);
        ``"linear"`` interpolates linearly between cell-centre times (continuous fields; float64).
    fill : value for times below the deepest cell of a column (and above the first centre
        for ``"linear"`` it is the first value, i.e. edge-held).

    Returns
    -------
    (nt, nx) array.
    """
    f = np.asarray(field)
    vp = np.asarray(vp_g, dtype=np.float64)
    t = np.asarray(t_s, dtype=np.float64)
    if f.shape != vp.shape or f.ndim != 2:
        raise InputError(f"field and vp_g must be (nz, nx) of one shape, got {f.shape}, {vp.shape}")
    if t.ndim != 1 or t.size == 0 or np.any(np.diff(t) <= 0):
        raise InputError("t_s must be a non-empty, strictly ascending 1-D time axis")
    t_bottom, t_centre = interface_times(vp, cell_m)
    nz, nx = f.shape
    if method == "nearest":
        idx = np.empty((nx, t.size), dtype=np.int64)
        _kernels.containing_cell(np.ascontiguousarray(t_bottom.T), t, idx)
        idx = idx.T
        valid = idx >= 0
        out = np.full((t.size, nx), fill, dtype=f.dtype)
        cols = np.broadcast_to(np.arange(nx), idx.shape)
        out[valid] = f[idx[valid], cols[valid]]
        return out
    if method == "linear":
        out = np.empty((t.size, nx))
        for j in range(nx):
            out[:, j] = np.interp(t, t_centre[:, j], f[:, j].astype(np.float64))
            out[t >= t_bottom[-1, j], j] = fill
        return out
    raise InputError(f"method must be 'nearest' or 'linear', got {method!r}")


def synthetic_sections(vp_g: np.ndarray, rho_g: np.ndarray, cell_m: float,
                       freqs_hz: float | Wavelet | Sequence[float | Wavelet],
                       domain: str = "depth", *,
                       t_s: np.ndarray | None = None,
                       col_step_m: float | None = None, rows_per_cell: int = 1) -> np.ndarray:
    """Noise-free sections of a property grid, one per wavelet (zero-phase Rickers by default).

    Impedance ``Z = rho vp``, reflectivity ``(Z2 - Z1)/(Z2 + Z1)`` between vertically
    adjacent cells, placed at the two-way time of the interface computed from the Vp column,
    convolved in time with a Ricker of each frequency (truncated at 1.35/f, where it is below
    5.3e-7 of its peak) and evaluated at the TWT of every cell centre (depth) or at ``t_s``
    (time). See the module docstring for the conventions.

    Parameters
    ----------
    vp_g, rho_g : (nz, nx) Vp (m/s) and density (kg/m^3), row 0 at the top.
    cell_m : cell size (m).
    freqs_hz : one frequency or a sequence (Hz): a bank of zero-phase Rickers rendered in one
        pass; an item may be a :class:`~demseis.seismic.wavelet.Wavelet` instead (another
        family, a phase rotation, minimum phase), convolved from its table on [-half, half]
        (:meth:`Wavelet.table`; linear interpolation within about 1e-4 of its peak).
    domain : ``"depth"`` (default, pixel-aligned with the grid) or ``"time"``.
    t_s : (nt,) ascending TWT axis (s) for ``domain="time"`` (required there; build it once
        per sweep with :func:`time_axis` so all samples share a shape). Ignored for depth.
    col_step_m : distance between columns; unused (columns are imaged independently), taken
        so that every imaging mode accepts a grid whose rows are finer than its columns.
    rows_per_cell : depth domain: the grid's rows split cells of an output grid in this odd
        number; the section is evaluated at the centres of those cells only (rows
        ``rows_per_cell // 2 :: rows_per_cell``). 1: every row.

    Returns
    -------
    (nf, nz // rows_per_cell, nx) float32 for depth, (nf, nt, nx) float32 for time.
    """
    vp, rho = _check_grids(vp_g, rho_g, cell_m)
    wavelets = as_wavelets(freqs_hz)
    nz, nx = vp.shape
    t_bottom, t_centre = interface_times(vp, cell_m)
    refl = reflectivity(vp * rho, axis=0)
    t_spike, amp = _live_spikes(np.ascontiguousarray(t_bottom[:-1].T),
                                np.ascontiguousarray(refl[:-1].T))
    if domain == "depth":
        n = _rows_per_cell(rows_per_cell, nz)
        t_out = np.ascontiguousarray(t_centre[n // 2::n].T)
    elif domain == "time":
        if t_s is None:
            raise InputError(
                "domain='time' needs t_s, the sweep's time axis: build it once with "
                "time_axis(grid.nz, grid.cell_m, model.vp_lower_bound_m_s, dt_s)"
            )
        t = np.asarray(t_s, dtype=np.float64)
        if t.ndim != 1 or t.size == 0 or np.any(np.diff(t) <= 0):
            raise InputError("t_s must be a non-empty, strictly ascending 1-D time axis (s)")
        t_out = np.ascontiguousarray(np.broadcast_to(t, (nx, t.size)))
    else:
        raise InputError(f"domain must be 'depth' or 'time', got {domain!r}")
    out = np.empty((len(wavelets), nx, t_out.shape[1]))
    plain = [k for k, w in enumerate(wavelets) if w.is_plain_ricker]
    if plain:          # the analytic Rickers: one pass over the even tables
        tables = np.empty((len(plain), TABLE_SIZE))
        inv_step = np.empty(len(plain))
        half = np.empty(len(plain))
        for i, k in enumerate(plain):
            tables[i], inv_step[i], half[i] = ricker_table(wavelets[k].freq_hz, TABLE_SIZE)
        bank = out if len(plain) == len(wavelets) else np.empty((len(plain),) + out.shape[1:])
        _kernels.convolve_spikes(t_spike, amp, t_out, tables, inv_step, half, bank)
        if bank is not out:
            out[plain] = bank
    for k, w in enumerate(wavelets):
        if not w.is_plain_ricker:
            table, inv, hw = w.table()
            _kernels.convolve_spikes_table(t_spike, amp, t_out, table, inv, hw, out[k])
    return np.ascontiguousarray(out.transpose(0, 2, 1), dtype=np.float32)
