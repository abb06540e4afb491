"""Zero-phase Ricker wavelets and wavelet banks."""

from __future__ import annotations

import math

import numpy as np

from demseis.errors import InputError

RICKER_TAIL_A = 18.0
"""Truncation of the Ricker wavelet used by the forward model: the wavelet is zero for
``(pi f t)^2 > RICKER_TAIL_A``, i.e. |t| > sqrt(18)/(pi f) = 1.35/f, where
|w| = |1 - 2a| exp(-a) < 5.3e-7 of its peak."""


def ricker_value(freq_hz: float | np.ndarray, t_s: np.ndarray) -> np.ndarray:
    """The Ricker wavelet ``w(t) = (1 - 2 pi^2 f^2 t^2) exp(-pi^2 f^2 t^2)`` (peak 1 at t = 0).

    Parameters
    ----------
    freq_hz : peak frequency f (Hz); a scalar or an array broadcasting against ``t_s``.
    t_s : times (s).
    """
    a = (np.pi * np.asarray(freq_hz, dtype=np.float64) * np.asarray(t_s, dtype=np.float64)) ** 2
    return (1.0 - 2.0 * a) * np.exp(-a)


def ricker_half_width_s(freq_hz: float) -> float:
    """Half-width (s) beyond which the forward model treats a Ricker of ``freq_hz`` as zero.

    ``sqrt(RICKER_TAIL_A) / (pi f)`` = 1.35 / f; the neglected tail is below 5.3e-7 of the peak.
    """
    return math.sqrt(RICKER_TAIL_A) / (math.pi * float(freq_hz))


def _check_freqs(freq_hz) -> np.ndarray:
    f = np.atleast_1d(np.asarray(freq_hz, dtype=np.float64))
    if f.ndim != 1 or f.size == 0 or not np.all(np.isfinite(f)) or np.any(f <= 0):
        raise InputError(f"freq_hz must be one or more finite frequencies > 0 Hz, got {freq_hz!r}")
    return f


def ricker(freq_hz, dt_s: float, duration_s: float) -> np.ndarray:
    """A zero-phase Ricker wavelet (or a bank of them), odd length, peak 1 at the centre sample.

    ``w(t) = (1 - 2 pi^2 f^2 t^2) exp(-pi^2 f^2 t^2)`` sampled at ``t = (k - n//2) dt`` for
    k = 0..n-1, with ``n = floor(duration / dt)`` made odd by adding one when even. This is
    the time basis of ``bruges.filters.ricker(duration, dt, f)`` (``sym=True``), so both give
    the same samples for the usual sample intervals (bruges rounds ``dt`` to one significant
    digit internally, e.g. it treats 0.0025 s as 0.002 s; this function does not).

    Parameters
    ----------
    freq_hz : peak frequency f (Hz), a scalar, or a sequence of frequencies for a bank.
    dt_s : sample interval (s), > 0.
    duration_s : nominal wavelet length (s), at least ``dt_s``.

    Returns
    -------
    (n,) float64 for a scalar frequency, (nf, n) float64 for a sequence (one row per frequency).
    """
    scalar = np.ndim(freq_hz) == 0
    f = _check_freqs(freq_hz)
    if not (np.isfinite(dt_s) and dt_s > 0):
        raise InputError(f"dt_s must be a finite sample interval > 0 s, got {dt_s!r}")
    if not (np.isfinite(duration_s) and duration_s >= dt_s):
        raise InputError(f"duration_s must be >= dt_s ({dt_s!r} s), got {duration_s!r}")
    n = int(np.floor(duration_s / dt_s + 1e-9))
    if n % 2 == 0:
        n += 1
    t = (np.arange(n) - n // 2) * float(dt_s)
    w = ricker_value(f[:, None], t[None, :])
    return w[0] if scalar else w


def ricker_table(freq_hz: float, n_table: int = 8192) -> tuple[np.ndarray, float, float]:
    """The even Ricker sampled on ``[0, half]`` for the forward model's interpolating kernel.

    Returns ``(table (n_table,), inverse step (1/s), half width (s))``; the last entry is the
    value at the half width (< 5.3e-7). Linear interpolation in this table deviates from the
    analytic wavelet by at most ``step^2/8 * max|w''| = 6 pi^2 f^2 step^2 / 8``, about 2e-7
    of the peak at the default size, independently of f.
    """
    half = ricker_half_width_s(freq_hz)
    step = half / (n_table - 1)
    t = np.arange(n_table) * step
    return ricker_value(freq_hz, t), 1.0 / step, half
