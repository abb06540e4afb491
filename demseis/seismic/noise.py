"""Additive random noise at a stated signal-to-noise ratio.

SNR (dB) = 20 log10(rms(signal) / rms(noise)), the rms taken over one whole section.
"""

from __future__ import annotations

import math

import numpy as np

from demseis.errors import InputError

NOISE_KINDS = ("white", "band", "coloured")


def rms(a: np.ndarray, axis=None) -> np.ndarray:
    """Root mean square (float64)."""
    a = np.asarray(a, dtype=np.float64)
    return np.sqrt(np.mean(a * a, axis=axis))


def snr_db(signal: np.ndarray, noisy: np.ndarray) -> float:
    """Measured SNR (dB) of ``noisy`` against the clean ``signal``.

    20 log10(rms(s) / rms(noisy - s)).
    """
    s = np.asarray(signal, dtype=np.float64)
    n = np.asarray(noisy, dtype=np.float64) - s
    return 20.0 * math.log10(rms(s) / rms(n))


def add_noise(section: np.ndarray, snr_db: float, kind: str,
              rng: np.random.Generator, slope: float = 1.0) -> np.ndarray:
    """Add white, band-limited or coloured Gaussian noise at exactly the requested SNR.

    Parameters
    ----------
    section : (nz, nx) section, (..., nz, nx) stack of independent sections (e.g. one per
        frequency), or (n,) single trace. Axis -2 (-1 for a trace) is depth/time.
    snr_db : requested SNR in dB; ``inf`` returns an unchanged copy.
    kind : ``"white"``: independent N(0, 1) samples; ``"band"``: white noise filtered along
        depth/time by the section's own mean amplitude spectrum (zero phase, circular, so the
        noise is stationary and has the band of the signal, whatever wavelet made it);
        ``"coloured"``: white noise filtered along depth/time to a power spectral density
        proportional to ``f**-slope`` (1: pink, 2: brown; the zero-frequency term removed).
    rng : random generator (the only source of randomness).
    slope : the coloured noise's spectral slope (>= 0); unused by the other kinds.

    Returns
    -------
    Array of the input's shape and float dtype (float32 stays float32). Each section's noise is
    scaled so that 20 log10(rms(section) / rms(noise)) equals ``snr_db`` for that draw. A
    section that is identically zero gets no noise (its SNR is undefined).
    """
    x = np.asarray(section)
    if x.ndim == 0 or x.size == 0:
        raise InputError(f"section must be a non-empty array, got shape {x.shape}")
    if kind not in NOISE_KINDS:
        raise InputError(f"noise kind must be one of {NOISE_KINDS}, got {kind!r}")
    try:
        snr = float(snr_db)
    except (TypeError, ValueError):
        raise InputError(f"snr_db must be a number (dB) or inf, got {snr_db!r}") from None
    if math.isnan(snr) or snr == -math.inf:
        raise InputError(f"snr_db must be a finite number of dB or +inf, got {snr_db!r}")
    if not (math.isfinite(slope) and slope >= 0):
        raise InputError(f"noise slope must be a finite number >= 0, got {slope!r}")
    out_dtype = x.dtype if np.issubdtype(x.dtype, np.floating) else np.float64
    if snr == math.inf:
        return x.astype(out_dtype, copy=True)
    xs = x.astype(np.float64)[..., None] if x.ndim == 1 else x.astype(np.float64)
    noise = rng.standard_normal(xs.shape)
    if kind != "white":    # white noise filtered along depth/time by an amplitude shape
        n = xs.shape[-2]
        if kind == "band":
            spec = np.fft.rfft(xs, axis=-2)
            shape = np.sqrt(np.mean(np.abs(spec) ** 2, axis=-1, keepdims=True))
        else:
            f = np.fft.rfftfreq(n)
            shape = np.zeros((f.size, 1))
            shape[1:, 0] = f[1:] ** (-slope / 2.0)
        noise = np.fft.irfft(np.fft.rfft(noise, axis=-2) * shape, n=n, axis=-2)
    s_rms = rms(xs, axis=(-2, -1))
    n_rms = rms(noise, axis=(-2, -1))
    with np.errstate(invalid="ignore", divide="ignore"):
        scale = np.where(n_rms > 0, s_rms / (n_rms * 10.0 ** (snr / 20.0)), 0.0)
    noisy = xs + noise * scale[..., None, None]
    if x.ndim == 1:
        noisy = noisy[..., 0]
    return noisy.astype(out_dtype)
