"""What acquisition and processing do to a section after it is imaged: coherent linear noise,
trace gain jitter and footprint stripes, automatic gain control, clipping and the quantisation
of a display image. Each is one named per-sample parameter (:mod:`demseis.parameters`) and is
off at its default, drawing nothing from the random generator, so samples made without them
keep their bytes.

Order (:func:`process`): the imaged section with its random noise
(:func:`demseis.seismic.noise.add_noise`), then coherent linear noise, gains (trace jitter,
time jitter, footprint), AGC, clipping and quantisation.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, fields
from typing import Any

import numpy as np

from demseis.errors import InputError


@dataclass(frozen=True)
class Processing:
    """The processing of one sample (each field is the sample parameter of that name).

    Attributes
    ----------
    linear_noise_snr_db : SNR (dB, against the section before noise) of coherent linear
        noise: one band-limited random trace (the section's own mean spectrum) repeated along
        x with a constant time shift per trace; ``inf`` = none.
    linear_noise_slope : that shift (samples per trace; the sign is the dip direction).
    trace_gain_jitter : standard deviation of the natural log of each trace's gain.
    time_gain_jitter : standard deviation of the natural log of a gain that varies smoothly
        down the section, the same on every trace (bright and dim intervals: the amplitude
        contrasts that make a section's amplitudes heavy-tailed): a Gaussian random function
        of the row with correlation :data:`TIME_GAIN_SAMPLES`.
    footprint_amplitude : relative amplitude of acquisition-footprint stripes, a gain
        ``1 + a cos(2 pi j / P + phi)`` along the traces j (phi drawn).
    footprint_period_traces : their period P (traces).
    agc_window_samples : automatic gain control: each sample divided by the rms of a centred
        window of this many samples of its trace (truncated at the ends); 0 = off.
    clip_percentile : amplitudes clipped at this percentile of ``|x|``; 100 = off.
    quantise_bits : the section mapped to ``2**bits`` levels over ``[-max|x|, max|x|]`` and
        back (8: an 8-bit display image); 0 = off.
    """

    linear_noise_snr_db: float = math.inf
    linear_noise_slope: float = 2.0
    trace_gain_jitter: float = 0.0
    time_gain_jitter: float = 0.0
    footprint_amplitude: float = 0.0
    footprint_period_traces: float = 10.0
    agc_window_samples: int = 0
    clip_percentile: float = 100.0
    quantise_bits: int = 0

    def __post_init__(self) -> None:
        checks = (
            ("linear_noise_snr_db", not math.isnan(self.linear_noise_snr_db)
             and self.linear_noise_snr_db != -math.inf, "a number of dB or inf"),
            ("linear_noise_slope", math.isfinite(self.linear_noise_slope), "finite"),
            ("trace_gain_jitter", 0.0 <= self.trace_gain_jitter < math.inf, ">= 0"),
            ("time_gain_jitter", 0.0 <= self.time_gain_jitter < math.inf, ">= 0"),
            ("footprint_amplitude", 0.0 <= self.footprint_amplitude <= 1.0, "in [0, 1]"),
            ("footprint_period_traces", 1.0 < self.footprint_period_traces < math.inf, "> 1"),
            ("agc_window_samples", self.agc_window_samples >= 0, ">= 0"),
            ("clip_percentile", 0.0 < self.clip_percentile <= 100.0, "in (0, 100]"),
            ("quantise_bits", 0 <= self.quantise_bits <= 24, "in [0, 24]"),
        )
        for name, ok, what in checks:
            if not ok:
                raise InputError(f"{name} must be {what}, got {getattr(self, name)!r}")

    @classmethod
    def of(cls, values: Mapping[str, Any]) -> Processing:
        """The processing named by a sample's parameters (absent ones: off)."""
        return cls(**{f.name: int(values[f.name]) if f.type == "int" else float(values[f.name])
                      for f in fields(cls) if f.name in values})

    @property
    def is_identity(self) -> bool:
        """True when nothing is done (every step off)."""
        return self == Processing(linear_noise_slope=self.linear_noise_slope,
                                  footprint_period_traces=self.footprint_period_traces)


TIME_GAIN_SAMPLES = 12.0
"""Standard deviation (rows) of the Gaussian that smooths the time gain's random function."""


def smooth_noise(n: int, rng: np.random.Generator, sigma: float = TIME_GAIN_SAMPLES) -> np.ndarray:
    """A stationary Gaussian random function of ``n`` rows, unit variance: white noise
    (``n + 8 sigma`` draws) smoothed by a Gaussian of ``sigma`` rows and cut to ``n``."""
    pad = int(math.ceil(4 * sigma))
    k = np.arange(-pad, pad + 1)
    g = np.exp(-0.5 * (k / sigma) ** 2)
    g /= math.sqrt(float(np.sum(g * g)))
    return np.convolve(rng.standard_normal(n + 2 * pad), g, mode="valid")


def linear_noise(section: np.ndarray, snr_db: float, slope: float,
                 rng: np.random.Generator) -> np.ndarray:
    """Coherent linear noise for ``section`` (rows = time, columns = traces): a random trace
    with the section's mean amplitude spectrum, shifted by ``slope * j`` samples at trace j
    (a phase ramp, so fractional shifts are exact and circular), scaled so that
    ``20 log10(rms(section) / rms(noise)) = snr_db``."""
    x = np.asarray(section, dtype=np.float64)
    n, ntr = x.shape
    spec = np.sqrt(np.mean(np.abs(np.fft.rfft(x, axis=0)) ** 2, axis=1))
    base = np.fft.rfft(rng.standard_normal(n)) * spec
    f = np.fft.rfftfreq(n)
    shifts = slope * np.arange(ntr)
    noise = np.fft.irfft(base[:, None] * np.exp(-2j * np.pi * f[:, None] * shifts[None, :]),
                         n=n, axis=0)
    s_rms, n_rms = float(np.sqrt(np.mean(x * x))), float(np.sqrt(np.mean(noise * noise)))
    if s_rms == 0.0 or n_rms == 0.0:
        return np.zeros_like(x)
    return noise * (s_rms / (n_rms * 10.0 ** (snr_db / 20.0)))


def agc(section: np.ndarray, window: int) -> np.ndarray:
    """Automatic gain control: ``x[i, j] / rms(x[i - w//2 : i + w//2 + 1, j])`` (the window
    truncated at the ends of the trace); a window of zero rms divides by 1."""
    x = np.asarray(section, dtype=np.float64)
    if window < 1:
        raise InputError(f"the AGC window must be at least 1 sample, got {window!r}")
    c = np.concatenate([np.zeros((1, x.shape[1])), np.cumsum(x * x, axis=0)])
    i = np.arange(x.shape[0])
    lo = np.clip(i - window // 2, 0, x.shape[0])
    hi = np.clip(i + window // 2 + 1, 0, x.shape[0])
    ms = (c[hi] - c[lo]) / (hi - lo)[:, None]
    rms = np.sqrt(np.maximum(ms, 0.0))
    return x / np.where(rms > 0, rms, 1.0)


def quantise(section: np.ndarray, bits: int) -> np.ndarray:
    """The section on ``2**bits`` equal levels spanning ``[-m, m]``, ``m = max|x|``: level
    ``round((x + m) / (2 m) * (2**bits - 1))``, mapped back to amplitude."""
    x = np.asarray(section, dtype=np.float64)
    m = float(np.abs(x).max())
    if m == 0.0:
        return x.copy()
    top = float(2 ** int(bits) - 1)
    return np.round((x + m) / (2.0 * m) * top) * (2.0 * m / top) - m


def process(section: np.ndarray, proc: Processing, rng: np.random.Generator,
            clean: np.ndarray | None = None) -> np.ndarray:
    """Apply ``proc`` to one (rows, traces) section; the dtype is kept.

    ``clean`` is the section before its random noise (the reference of the linear noise's
    SNR; default ``section``). Draws from ``rng`` only for the steps that are on.
    """
    x = np.asarray(section)
    if x.ndim != 2:
        raise InputError(f"process takes one (rows, traces) section, got shape {x.shape}")
    if proc.is_identity:
        return x.copy()
    out = x.astype(np.float64)
    if proc.linear_noise_snr_db != math.inf:
        ref = out if clean is None else np.asarray(clean, dtype=np.float64)
        out = out + linear_noise(ref, proc.linear_noise_snr_db, proc.linear_noise_slope, rng)
    ntr = out.shape[1]
    if proc.trace_gain_jitter > 0:
        out = out * np.exp(proc.trace_gain_jitter * rng.standard_normal(ntr))[None, :]
    if proc.time_gain_jitter > 0:
        out = out * np.exp(proc.time_gain_jitter * smooth_noise(out.shape[0], rng))[:, None]
    if proc.footprint_amplitude > 0:
        phase = rng.uniform(0.0, 2.0 * math.pi)
        stripes = 1.0 + proc.footprint_amplitude * np.cos(
            2.0 * math.pi * np.arange(ntr) / proc.footprint_period_traces + phase)
        out = out * stripes[None, :]
    if proc.agc_window_samples > 0:
        out = agc(out, proc.agc_window_samples)
    if proc.clip_percentile < 100.0:
        c = float(np.percentile(np.abs(out), proc.clip_percentile))
        out = np.clip(out, -c, c)
    if proc.quantise_bits > 0:
        out = quantise(out, proc.quantise_bits)
    return out.astype(x.dtype if np.issubdtype(x.dtype, np.floating) else np.float64)
