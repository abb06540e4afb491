"""Source wavelets: the zero-phase Ricker (analytic), Ormsby and Butterworth band-pass
wavelets, constant-phase rotation and minimum phase (:class:`Wavelet`), and a wavelet estimated
from a section (:func:`estimate_wavelet`)."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from demseis.errors import InputError


def scipy_fft(*names: str) -> tuple:
    """The functions ``names`` of ``scipy.fft``, imported at the first call: the one place
    ``demseis.seismic`` imports it (about 0.1-0.2 s; ``import demseis.seismic`` loads no
    scipy submodule, and only PSF imaging and the wavelet spectra need it)."""
    import scipy.fft

    return tuple(getattr(scipy.fft, name) for name in names)

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


# --------------------------------------------------------------------------------------------
# band-pass families, constant-phase rotation, minimum phase


WAVELETS = ("ricker", "ormsby", "butterworth")
"""Wavelet families: the Ricker of peak ``freq_hz``, and two band-pass wavelets whose pass band
spans ``band_octaves`` octaves centred (geometrically) on ``freq_hz``."""

WAVELET_PHASES = ("zero", "minimum")
"""``zero``: the family's amplitude spectrum with zero phase; ``minimum``: the minimum-phase
wavelet of that amplitude spectrum (causal, its energy as early as it can be)."""

BUTTERWORTH_ORDER = 4
"""Order n of each of the Butterworth wavelet's low- and high-cut filters."""

ORMSBY_TAPER_OCTAVES = 0.5
"""Width of each of the Ormsby trapezoid's ramps: ``f1 = f2 / 2**0.5``, ``f4 = f3 * 2**0.5``."""

HALF_WIDTH_PERIODS = 3.0
"""A wavelet other than the zero-phase Ricker is kept over ``|t| <= 3 / f_low`` (three periods of
its low corner: ``freq_hz / 2`` for a Ricker, ``f1`` for Ormsby, the low -3 dB corner for
Butterworth; six for a minimum-phase wavelet, which is causal and longer) and tapered to zero
by a raised cosine over the outer quarter of that window."""

MIN_PHASE_FLOOR = {"ricker": 1e-12, "butterworth": 1e-12, "ormsby": 1e-4}
"""Minimum phase: the log-spectrum is held at least this far below its peak (the Ricker's
Gaussian tail; the Ormsby's stop bands, where a deeper floor makes the causal wavelet longer
than its window: its amplitude spectrum then departs from the trapezoid by up to 4 % of the
peak, against 0.2 % for the others), and its value at f = 0 is that at the first bin."""

_SAMPLES_PER_PERIOD = 256
"""The fine grid of a tabulated wavelet samples its highest frequency (:meth:`Wavelet.f_max_hz`)
this many times per period, so linear interpolation stays within about 1e-4 of the peak."""


@dataclass(frozen=True)
class Wavelet:
    """A source wavelet: a family, its band, and its phase.

    Attributes
    ----------
    family : one of :data:`WAVELETS`.
    freq_hz : Ricker peak frequency, or the geometric centre of a band-pass wavelet's pass band.
    band_octaves : width of the pass band (Ormsby: between f2 and f3; Butterworth: between its
        -3 dB corners) in octaves; unused by the Ricker.
    phase_deg : constant-phase rotation (degrees): ``w cos(phi) - H[w] sin(phi)`` with ``H`` the
        Hilbert transform (bruges' ``rotate_phase`` convention; 90 turns a peak into a
        zero crossing whose lobe leads).
    phase : one of :data:`WAVELET_PHASES`, applied before the rotation.

    Every variant has the amplitude spectrum of the zero-phase wavelet of peak 1 at t = 0.
    The zero-phase Ricker (the default) is evaluated analytically as before; the others are
    built from their amplitude spectra on a fine grid (:meth:`table`).
    """

    family: str = "ricker"
    freq_hz: float = 40.0
    band_octaves: float = 2.0
    phase_deg: float = 0.0
    phase: str = "zero"

    def __post_init__(self) -> None:
        if self.family not in WAVELETS:
            raise InputError(f"wavelet family must be one of {WAVELETS}, got {self.family!r}")
        if self.phase not in WAVELET_PHASES:
            raise InputError(f"wavelet phase must be one of {WAVELET_PHASES}, got {self.phase!r}")
        _check_freqs(self.freq_hz)
        if not (math.isfinite(self.band_octaves) and 0.1 <= self.band_octaves <= 8.0):
            raise InputError(f"band_octaves must be in [0.1, 8], got {self.band_octaves!r}")
        if not math.isfinite(self.phase_deg):
            raise InputError(f"phase_deg must be a finite angle, got {self.phase_deg!r}")

    @property
    def is_plain_ricker(self) -> bool:
        """The zero-phase, unrotated Ricker (the forward model's analytic, even path)."""
        return self.family == "ricker" and self.phase == "zero" and self.phase_deg % 360.0 == 0.0

    def band_hz(self) -> tuple[float, float]:
        """The pass band ``(freq / 2**(b/2), freq * 2**(b/2))`` of a band-pass wavelet (Hz)."""
        half = 2.0 ** (self.band_octaves / 2.0)
        return self.freq_hz / half, self.freq_hz * half

    def ormsby_corners(self) -> tuple[float, float, float, float]:
        """``(f1, f2, f3, f4)`` of the Ormsby trapezoid (Hz)."""
        f2, f3 = self.band_hz()
        ramp = 2.0 ** ORMSBY_TAPER_OCTAVES
        return f2 / ramp, f2, f3, f3 * ramp

    def low_hz(self) -> float:
        """The low corner that sets the wavelet's length (:data:`HALF_WIDTH_PERIODS`)."""
        if self.family == "ricker":
            return self.freq_hz / 2.0
        if self.family == "ormsby":
            return self.ormsby_corners()[0]
        return self.band_hz()[0]

    def f_max_hz(self) -> float:
        """A frequency above which the amplitude spectrum is negligible (< 1e-4 of its peak)."""
        if self.family == "ricker":
            return 4.0 * self.freq_hz
        if self.family == "ormsby":
            return self.ormsby_corners()[3]
        return self.band_hz()[1] * 10.0 ** (2.0 / BUTTERWORTH_ORDER)

    def amplitude(self, f_hz: np.ndarray) -> np.ndarray:
        """The amplitude spectrum at frequencies ``f_hz`` (Hz, >= 0), in the units of the
        family's formula (the Ricker's ``2 f^2 / (sqrt(pi) fp^3) exp(-f^2/fp^2)``, the Ormsby
        trapezoid of height 1, the Butterworth product of height ~1)."""
        f = np.abs(np.asarray(f_hz, dtype=np.float64))
        if self.family == "ricker":
            fp = self.freq_hz
            return 2.0 * f * f / (math.sqrt(math.pi) * fp ** 3) * np.exp(-(f / fp) ** 2)
        if self.family == "ormsby":
            f1, f2, f3, f4 = self.ormsby_corners()
            return np.interp(f, [f1, f2, f3, f4], [0.0, 1.0, 1.0, 0.0], left=0.0, right=0.0)
        lo, hi = self.band_hz()
        n2 = 2 * BUTTERWORTH_ORDER
        with np.errstate(divide="ignore", over="ignore"):
            high_cut = 1.0 / (1.0 + (f / hi) ** n2)
            low_cut = 1.0 / (1.0 + (lo / np.where(f > 0, f, np.inf)) ** n2)
        return high_cut * np.where(f > 0, low_cut, 0.0)

    def log_amplitude(self, f_hz: np.ndarray) -> np.ndarray:
        """``log(amplitude(f))`` computed without underflow where the family has a closed form
        (Ricker, Butterworth; ``-inf`` at f = 0), the Ormsby's ``log`` of its trapezoid."""
        f = np.abs(np.asarray(f_hz, dtype=np.float64))
        with np.errstate(divide="ignore"):
            lf = np.log(f)
            if self.family == "ricker":
                fp = self.freq_hz
                return math.log(2.0 / (math.sqrt(math.pi) * fp ** 3)) + 2.0 * lf - (f / fp) ** 2
            if self.family == "ormsby":
                return np.log(self.amplitude(f))
            lo, hi = self.band_hz()
            n2 = 2 * BUTTERWORTH_ORDER
            low = np.where(f > 0, -np.logaddexp(0.0, n2 * (math.log(lo) - np.where(f > 0, lf, 0.0))),
                           -np.inf)
            return -np.logaddexp(0.0, n2 * (np.where(f > 0, lf, -np.inf) - math.log(hi))) + low

    def half_width_s(self) -> float:
        """Half-width (s) beyond which the wavelet is zero."""
        if self.is_plain_ricker:
            return ricker_half_width_s(self.freq_hz)
        periods = HALF_WIDTH_PERIODS * (2.0 if self.phase == "minimum" else 1.0)
        return periods / self.low_hz()

    def table(self) -> tuple[np.ndarray, float, float]:
        """The wavelet tabulated on ``[-half, half]`` for the forward model's kernel.

        Returns ``(table (m,), inverse step (1/s), half width (s))``, ``table[p]`` the value at
        ``t = -half + p / inverse_step``. Built on a fine grid from the amplitude spectrum:
        zero phase, or minimum phase by the folded real cepstrum of the log-spectrum
        (:meth:`log_amplitude`, :data:`MIN_PHASE_FLOOR`), rotated by ``phase_deg`` (the positive
        frequencies times ``exp(i phi)``), scaled so that the zero-phase wavelet peaks at 1,
        truncated and tapered (:data:`HALF_WIDTH_PERIODS`).
        """
        irfft, rfft, rfftfreq = scipy_fft("irfft", "rfft", "rfftfreq")

        fs = _SAMPLES_PER_PERIOD * self.f_max_hz()
        half_n = int(math.ceil(self.half_width_s() * fs))
        n_fft = 1 << int(math.ceil(math.log2(4 * half_n + 8)))
        f = rfftfreq(n_fft, 1.0 / fs)
        amp = self.amplitude(f)
        scale = 1.0 / irfft(amp, n_fft)[0]         # the zero-phase wavelet's peak -> 1
        if self.phase == "minimum":
            logs = self.log_amplitude(f)
            logs[0] = logs[1]                     # a spectral zero at DC: held from f = df
            logs = np.maximum(logs, float(logs.max()) + math.log(MIN_PHASE_FLOOR[self.family]))
            cep = irfft(logs, n_fft)
            fold = np.zeros(n_fft)
            fold[0] = cep[0]
            fold[1:n_fft // 2] = 2.0 * cep[1:n_fft // 2]
            fold[n_fft // 2] = cep[n_fft // 2]
            spec = np.exp(rfft(fold))
        else:
            spec = amp.astype(np.complex128)
        if self.phase_deg % 360.0 != 0.0:
            spec = spec * rotation_factors(f.size, n_fft, self.phase_deg)
        w = np.roll(irfft(spec, n_fft) * scale, n_fft // 2)[n_fft // 2 - half_n:
                                                            n_fft // 2 + half_n + 1]
        t = np.abs(np.arange(-half_n, half_n + 1)) / half_n
        taper = np.where(t <= 0.75, 1.0, 0.5 * (1.0 + np.cos(np.pi * (t - 0.75) / 0.25)))
        return w * taper, fs, half_n / fs

    def samples(self, dt_s: float, duration_s: float) -> np.ndarray:
        """The wavelet at ``t = (k - n//2) dt`` for k = 0..n-1, n odd (the time basis of
        :func:`ricker`), zero beyond its half-width."""
        if not (np.isfinite(dt_s) and dt_s > 0):
            raise InputError(f"dt_s must be a finite sample interval > 0 s, got {dt_s!r}")
        if not (np.isfinite(duration_s) and duration_s >= dt_s):
            raise InputError(f"duration_s must be >= dt_s ({dt_s!r} s), got {duration_s!r}")
        n = int(np.floor(duration_s / dt_s + 1e-9))
        n += 1 - n % 2
        t = (np.arange(n) - n // 2) * float(dt_s)
        if self.is_plain_ricker:
            return ricker_value(self.freq_hz, t)
        tab, inv_step, half = self.table()
        return np.interp(t, -half + np.arange(tab.size) / inv_step, tab, left=0.0, right=0.0)


def as_wavelets(wavelets) -> list[Wavelet]:
    """A frequency (a Ricker peak), a :class:`Wavelet`, or a sequence of either, as a list of
    wavelets (an InputError names what is not one)."""
    items = list(wavelets) if isinstance(wavelets, (list, tuple, np.ndarray)) else [wavelets]
    if not items:
        raise InputError("give at least one wavelet or frequency")
    out = []
    for w in items:
        if isinstance(w, Wavelet):
            out.append(w)
        elif np.ndim(w) == 0 and not isinstance(w, (str, bool)):
            out.append(Wavelet("ricker", float(_check_freqs(w)[0])))
        else:
            raise InputError(f"a wavelet must be a frequency (Hz) or a Wavelet, got {w!r}")
    return out


def rotation_factors(n_bins: int, n: int, phase_deg: float) -> np.ndarray:
    """The factors by which a constant-phase rotation multiplies the ``n_bins`` terms of the
    real FFT of ``n`` samples: ``exp(i phi)``, and ``cos(phi)`` at zero frequency and (``n``
    even) at the Nyquist frequency, which have no quadrature."""
    rot = np.exp(1j * math.radians(float(phase_deg)))
    mult = np.full(n_bins, rot)
    mult[0] = rot.real
    if n % 2 == 0:
        mult[-1] = rot.real
    return mult


def rotate_phase(x: np.ndarray, phase_deg: float, axis: int = -1) -> np.ndarray:
    """Constant-phase rotation of traces along ``axis``: ``x cos(phi) - H[x] sin(phi)``, the
    Hilbert transform ``H`` taken by FFT over the trace (circular; pad a short trace).

    The convention of ``bruges.filters.rotate_phase`` (tested against it)."""
    irfft, rfft = scipy_fft("irfft", "rfft")

    a = np.asarray(x, dtype=np.float64)
    n = a.shape[axis]
    spec = rfft(a, axis=axis)
    mult = rotation_factors(spec.shape[axis], n, phase_deg)
    shape = [1] * a.ndim
    shape[axis] = -1
    return irfft(spec * mult.reshape(shape), n=n, axis=axis)


def kurtosis(x: np.ndarray) -> float:
    """Excess kurtosis ``m4 / m2**2 - 3`` of all values of ``x`` (central moments): 0 for
    Gaussian values, -1.5 for a sinusoid, > 0 for spiky ones; NaN when they are all equal."""
    d = np.asarray(x, dtype=np.float64).ravel()
    d = d - d.mean()
    m2 = float(np.mean(d * d))
    return float(np.mean(d ** 4) / m2 ** 2 - 3.0) if m2 > 0 else float("nan")


@dataclass(frozen=True)
class EstimatedWavelet:
    """A wavelet estimated from a section (:func:`estimate_wavelet`).

    Attributes
    ----------
    samples : (n,) the wavelet at ``t = (k - n//2) dt``, n odd, zero-phase peak scaled to 1.
    dt_s : its sample interval (the section's).
    phase_deg : the constant phase found, in (-90, 90] (a polarity flip, 180 deg, is not
        resolved: kurtosis does not see it).
    freqs_hz, amplitude : the section's mean amplitude spectrum (smoothed, peak 1).
    dominant_hz : the frequency of its peak.
    """

    samples: np.ndarray
    dt_s: float
    phase_deg: float
    freqs_hz: np.ndarray
    amplitude: np.ndarray
    dominant_hz: float


def estimate_wavelet(section: np.ndarray, dt_s: float, length_s: float = 0.128,
                     smooth_hz: float = 3.0) -> EstimatedWavelet:
    """Statistical wavelet estimate of a section: amplitude spectrum and one constant phase.

    The amplitude spectrum is the square root of the traces' mean power spectrum (each trace
    Hann-tapered, zero-padded to at least 4x), smoothed over ``smooth_hz``. The phase is the
    constant rotation that, undone, makes the section most non-Gaussian (largest kurtosis),
    the reflectivity being sparse: the kurtosis method of Levy and Oldenburg (1987) and
    van der Baan (2008), searched over -90..90 deg in 1-deg steps then refined to 0.1 deg.

    Parameters
    ----------
    section : (n_samples, n_traces) section, time (or depth) down axis 0; a (n,) trace.
    dt_s : its sample interval (s) (a depth section: give a cell's two-way time, or 1 to get
        frequencies in cycles per sample).
    length_s : length of the wavelet returned.
    smooth_hz : width of the moving average over the spectrum.

    Returns
    -------
    :class:`EstimatedWavelet`.
    """
    irfft, rfft, rfftfreq = scipy_fft("irfft", "rfft", "rfftfreq")

    x = np.asarray(section, dtype=np.float64)
    if x.ndim == 1:
        x = x[:, None]
    if x.ndim != 2 or x.shape[0] < 16 or not np.all(np.isfinite(x)):
        raise InputError(f"section must be a finite (n_samples >= 16, n_traces) array, got "
                         f"shape {np.shape(section)}")
    if not (np.isfinite(dt_s) and dt_s > 0):
        raise InputError(f"dt_s must be a finite sample interval > 0, got {dt_s!r}")
    x = x - x.mean(axis=0, keepdims=True)
    if not np.any(x):
        raise InputError("the section is constant: it has no wavelet to estimate")
    n = x.shape[0]
    n_fft = 1 << int(math.ceil(math.log2(4 * n)))
    power = np.mean(np.abs(rfft(x * np.hanning(n)[:, None], n_fft, axis=0)) ** 2, axis=1)
    f = rfftfreq(n_fft, dt_s)
    width = max(1, int(round(smooth_hz / (f[1] - f[0]))))
    amp = np.sqrt(np.convolve(power, np.ones(width) / width, mode="same"))
    amp /= amp.max()
    dominant = float(f[int(np.argmax(amp))])
    # the phase: rotating the data by -phi undoes a wavelet of phase phi
    pad = np.concatenate([x, np.zeros_like(x)], axis=0)

    def kurt(phi: float) -> float:
        return kurtosis(rotate_phase(pad, -phi, axis=0)[:n])

    coarse = np.arange(-89.0, 91.0, 1.0)
    best = float(coarse[int(np.argmax([kurt(p) for p in coarse]))])
    fine = best + np.arange(-1.0, 1.05, 0.1)
    best = float(fine[int(np.argmax([kurt(p) for p in fine]))])
    best = (best + 90.0) % 180.0 - 90.0
    if best == -90.0:
        best = 90.0
    half = int(round(length_s / (2.0 * dt_s)))
    w0 = np.roll(irfft(amp, n_fft), n_fft // 2)
    w0 /= w0[n_fft // 2]
    w = rotate_phase(w0, best)[n_fft // 2 - half: n_fft // 2 + half + 1]
    return EstimatedWavelet(w, float(dt_s), best, f, amp, dominant)
