"""How much a section looks like a survey's: the measures of the project's field reference and more.

Every function takes a (samples, traces) section (time rows, trace columns) and, for a
synthetic section, its fault label, so that the measures are taken in intact rock:

- :func:`adjacent_trace_correlation`: median Pearson correlation of neighbouring traces over
  32-sample windows overlapping by half (F3 at 4 ms: 0.92);
- :func:`zero_crossings`: median sign changes per 100 samples of a trace (F3: 34);
- :func:`horizon_roughness`: RMS (samples) of tracked reflector peaks from a smooth curve;
- :func:`offset_agreement`: whether the reflector offset across a labelled fault equals the
  lag its throw makes (:func:`expected_lags`);
- :func:`spectral_slope`: the slope of a reflectivity series' power spectrum in log-log.

``intact`` masks (:func:`intact_mask`) keep the pixels at least ``margin`` traces from any
fault label, as the field README asks for stores.

``demseis realism`` (:func:`demseis.evaluation.realism_report.realism_report`) puts a store
beside a field section and the field targets with these and:

- :func:`dominant_period` (centroid of the traces' mean amplitude spectrum) and
  :func:`peak_period`; :func:`excess_kurtosis` of the amplitudes;
- from the labels: :func:`local_dips` (apparent dip in pixel space, a local principal axis
  along each instance), :func:`faults_per_100_traces`, :func:`label_fraction` and
  :func:`throws_m` (``slip_m * sin(dip_deg)``).
"""

from __future__ import annotations

import numpy as np
from scipy import ndimage

from demseis.errors import InputError
from demseis.seismic.wavelet import kurtosis

WINDOW = 32
"""Samples per correlation window (half-overlapping)."""


def _section(section: np.ndarray) -> np.ndarray:
    s = np.asarray(section, dtype=np.float64)
    if s.ndim != 2 or min(s.shape) < 2:
        raise InputError(f"a section must be (samples, traces) with at least 2 of each, got "
                         f"shape {s.shape}")
    return s


def intact_mask(fault: np.ndarray, margin: int = 6) -> np.ndarray:
    """True at pixels at least ``margin`` traces (columns) from every fault pixel of their row."""
    f = np.asarray(fault) > 0
    near = f.copy()
    for d in range(1, margin):
        near[:, d:] |= f[:, :-d]
        near[:, :-d] |= f[:, d:]
    return ~near


def _windows(n: int, size: int = WINDOW) -> list[slice]:
    step = max(1, size // 2)
    return [slice(a, a + size) for a in range(0, max(1, n - size + 1), step)]


def trace_correlations(section: np.ndarray, intact: np.ndarray | None = None) -> np.ndarray:
    """The Pearson correlations of neighbouring traces over half-overlapping 32-sample
    windows, for the windows whose pixels (both traces) are all ``intact`` and not silent
    (what :func:`adjacent_trace_correlation` takes the median of)."""
    s = _section(section)
    ok = np.ones(s.shape, bool) if intact is None else np.asarray(intact, bool)
    vals = []
    for w in _windows(s.shape[0]):
        a, b = s[w, :-1], s[w, 1:]
        good = ok[w, :-1].all(axis=0) & ok[w, 1:].all(axis=0)
        a, b = a - a.mean(axis=0), b - b.mean(axis=0)
        den = np.sqrt((a * a).sum(axis=0) * (b * b).sum(axis=0))
        good &= den > 1e-12 * max(float(np.abs(s).max()), 1e-30) ** 2
        vals.append(((a * b).sum(axis=0)[good] / den[good]))
    return np.concatenate(vals) if vals else np.empty(0)


def adjacent_trace_correlation(section: np.ndarray, intact: np.ndarray | None = None) -> float:
    """Median Pearson correlation of neighbouring traces over half-overlapping 32-sample
    windows, over the windows whose pixels (both traces) are all ``intact`` and not silent.
    NaN if there is none."""
    v = trace_correlations(section, intact)
    return float(np.median(v)) if v.size else float("nan")


def zero_crossing_rates(section: np.ndarray, intact: np.ndarray | None = None) -> np.ndarray:
    """Sign changes per 100 samples of each trace with at least 32 live, ``intact`` samples
    (exact zeros are skipped): what :func:`zero_crossings` takes the median of."""
    s = _section(section)
    ok = np.ones(s.shape, bool) if intact is None else np.asarray(intact, bool)
    rates = []
    for j in range(s.shape[1]):
        t = s[ok[:, j], j]
        t = t[t != 0.0]
        if t.size >= WINDOW:
            rates.append(100.0 * np.count_nonzero(np.diff(np.sign(t)) != 0) / (t.size - 1))
    return np.asarray(rates, dtype=np.float64)


def zero_crossings(section: np.ndarray, intact: np.ndarray | None = None) -> float:
    """Median sign changes per 100 samples of a trace (over its live, ``intact`` samples;
    exact zeros are skipped). NaN if no trace has 32 such samples."""
    rates = zero_crossing_rates(section, intact)
    return float(np.median(rates)) if rates.size else float("nan")


def _peaks(trace: np.ndarray, floor: float) -> np.ndarray:
    """Sub-sample positions of the local maxima of ``trace`` above ``floor`` (parabolic)."""
    a, b, c = trace[:-2], trace[1:-1], trace[2:]
    k = np.flatnonzero((b > a) & (b >= c) & (b > floor)) + 1
    den = trace[k - 1] - 2 * trace[k] + trace[k + 1]
    off = np.where(den != 0, 0.5 * (trace[k - 1] - trace[k + 1]) / np.where(den != 0, den, 1), 0)
    return k + off


def horizon_roughness(section: np.ndarray, intact: np.ndarray | None = None, *,
                      min_traces: int = 15, smooth_traces: int = 9) -> float:
    """Median RMS (samples) of tracked reflector peaks from a smooth curve, in intact rock.

    Peaks above the section's 70th amplitude percentile are followed trace to trace (the
    nearest peak within 1.5 samples, while the pixels stay ``intact``); each track of at least
    ``min_traces`` traces is compared with its running mean over ``smooth_traces`` traces.
    NaN if no track is long enough.
    """
    s = _section(section)
    ok = np.ones(s.shape, bool) if intact is None else np.asarray(intact, bool)
    floor = float(np.percentile(s[s > 0], 70)) if (s > 0).any() else 0.0
    peaks = [_peaks(s[:, j], floor) for j in range(s.shape[1])]
    used = [np.zeros(p.size, bool) for p in peaks]
    rms = []
    half = smooth_traces // 2
    for j0 in range(s.shape[1]):
        for i0 in range(peaks[j0].size):
            if used[j0][i0]:
                continue
            track, j, i = [peaks[j0][i0]], j0, i0
            used[j][i] = True
            while j + 1 < s.shape[1]:
                p = peaks[j + 1]
                if p.size == 0:
                    break
                k = int(np.argmin(np.abs(p - track[-1])))
                if abs(p[k] - track[-1]) > 1.5 or used[j + 1][k] \
                        or not ok[int(round(p[k])), j + 1] or not ok[int(round(track[-1])), j]:
                    break
                j, i = j + 1, k
                used[j][i] = True
                track.append(p[k])
            if len(track) >= min_traces:
                t = np.asarray(track)
                kern = np.ones(smooth_traces) / smooth_traces
                smooth = np.convolve(t, kern, mode="valid")
                rms.append(float(np.sqrt(np.mean((t[half:len(t) - half] - smooth) ** 2))))
    return float(np.median(rms)) if rms else float("nan")


def best_lag(a: np.ndarray, b: np.ndarray, max_lag: int) -> int:
    """The shift ``L`` (samples, |L| <= max_lag) maximising the correlation of ``a[t]`` with
    ``b[t + L]`` over the samples both cover."""
    n = a.size
    best, arg = -np.inf, 0
    for lag in range(-max_lag, max_lag + 1):
        x = a[max(0, -lag):n - max(0, lag)]
        y = b[max(0, lag):n - max(0, -lag)]
        x, y = x - x.mean(), y - y.mean()
        den = np.sqrt((x * x).sum() * (y * y).sum())
        c = (x * y).sum() / den if den > 0 else -np.inf
        if c > best:
            best, arg = c, lag
    return arg


def expected_lags(fault: np.ndarray, throw_m: np.ndarray, sense: np.ndarray, vp_m_s: np.ndarray,
                  dt_s: float, side: int = 3) -> np.ndarray:
    """The lag (samples) between traces ``j - side`` and ``j + side`` that a fault pixel's throw
    makes in a time section: ``T_B(D_A(t) +- throw) - t``.

    ``D_A`` is the depth of time ``t`` in trace A = ``j - side`` and ``T_B`` the two-way time
    of a depth in trace B = ``j + side``, both from the interval velocity ``vp_m_s`` of the
    section's samples; the sign is + where trace B is the hanging wall of a normal fault (the
    fault trace moves towards B with depth) or the footwall of a reverse one (``sense`` 2).
    NaN where the pixel is not a fault or the direction cannot be read (an isolated pixel).
    """
    f = np.asarray(fault) > 0
    v = np.asarray(vp_m_s, dtype=np.float64)
    nt, nx = f.shape
    depth = np.cumsum(v, axis=0) * dt_s / 2.0                  # depth at the end of sample t
    depth = np.vstack([np.zeros((1, nx)), depth])[:-1]         # depth at sample t
    out = np.full(f.shape, np.nan)
    rows, cols = np.nonzero(f)
    for t, j in zip(rows, cols):
        a, b = j - side, j + side
        if a < 0 or b >= nx:
            continue
        up = np.flatnonzero(f[max(0, t - 4), max(0, j - 4):j + 5])
        down = np.flatnonzero(f[min(nt - 1, t + 4), max(0, j - 4):j + 5])
        if up.size == 0 or down.size == 0 or up.mean() == down.mean():
            continue
        towards_b = down.mean() > up.mean()                    # the trace moves right with depth
        sign = 1.0 if towards_b == (int(np.asarray(sense)[t, j]) != 2) else -1.0
        d = depth[t, a] + sign * float(np.asarray(throw_m)[t, j])
        out[t, j] = np.interp(d, depth[:, b], np.arange(nt)) - t
    return out


def offset_agreement(section: np.ndarray, fault: np.ndarray, lags: np.ndarray, *,
                     side: int = 3, half_window: int = 12, min_throw: float = 1.0,
                     tolerance: float = 1.0, step: int = 1) -> tuple[float, int]:
    """The fraction of labelled fault pixels whose reflector offset equals their throw.

    ``lags``: the lag (samples) each fault pixel's throw makes between traces ``j - side``
    and ``j + side`` (:func:`expected_lags`). At every ``step``-th fault pixel (row t, trace
    j) with ``|lag| >= min_throw``, the lag that best aligns the two traces over rows ``t +-
    w`` (``w`` = the larger of ``half_window`` and ``|lag| + 6``; searched up to ``|lag| +
    3``) is compared with it: within ``tolerance`` samples counts as agreement. A pixel is
    measured only where neither trace holds a fault label within the window (the traces lie
    on either side of this fault). Returns (fraction, pixels measured); NaN if none.
    """
    s = _section(section)
    f = np.asarray(fault) > 0
    want = np.asarray(lags, dtype=np.float64)
    rows, cols = np.nonzero(f & (np.abs(np.nan_to_num(want)) >= min_throw))
    hits = n = 0
    for t, j in list(zip(rows, cols))[::step]:
        w = max(half_window, int(np.ceil(abs(want[t, j]))) + 6)
        lo, hi = t - w, t + w + 1
        if j - side < 0 or j + side >= s.shape[1] or lo < 0 or hi > s.shape[0]:
            continue
        if f[lo:hi, j - side].any() or f[lo:hi, j + side].any():
            continue
        a, b = s[lo:hi, j - side], s[lo:hi, j + side]
        if not (np.any(a) and np.any(b)):
            continue
        lag = best_lag(a, b, int(np.ceil(abs(want[t, j]))) + 3)
        n += 1
        hits += abs(lag - want[t, j]) <= tolerance
    return (hits / n if n else float("nan")), n


def spectral_slope(series: np.ndarray, dt_s: float, band_hz: tuple[float, float] = (5.0, 120.0)) -> float:
    """Slope of log power against log frequency of ``series`` (rows: time, sample interval
    ``dt_s``; columns averaged) over ``band_hz``: > 0 for a spectrum rising with frequency."""
    x = np.asarray(series, dtype=np.float64)
    if x.ndim == 1:
        x = x[:, None]
    x = x - x.mean(axis=0)
    power = (np.abs(np.fft.rfft(x * np.hanning(x.shape[0])[:, None], axis=0)) ** 2).mean(axis=1)
    f = np.fft.rfftfreq(x.shape[0], dt_s)
    sel = (f >= band_hz[0]) & (f <= band_hz[1]) & (power > 0)
    if sel.sum() < 3:
        raise InputError(f"the series has fewer than 3 frequencies in {band_hz} Hz")
    return float(np.polyfit(np.log(f[sel]), np.log(power[sel]), 1)[0])


# ---- spectrum, amplitudes and labels: the measures of `demseis realism` -------------------------

def amplitude_spectrum(section: np.ndarray, nfft: int | None = None) -> tuple[np.ndarray, np.ndarray]:
    """The mean amplitude spectrum of a section's traces.

    Each trace (column) loses its mean, is tapered with a Hann window and zero-padded to
    ``nfft`` samples (default: the next power of two >= max(1024, 4 x samples)).

    Returns
    -------
    freq : (nfft // 2 + 1,) frequencies in cycles per sample.
    amp : the same shape, the traces' mean absolute Fourier amplitude.
    """
    s = _section(section)
    n = s.shape[0]
    if nfft is None:
        nfft = 1 << int(np.ceil(np.log2(max(1024, 4 * n))))
    x = (s - s.mean(axis=0)) * np.hanning(n)[:, None]
    amp = np.abs(np.fft.rfft(x, n=nfft, axis=0)).mean(axis=1)
    return np.fft.rfftfreq(nfft), amp


def peak_period(freq: np.ndarray, amp: np.ndarray, n_samples: int) -> float:
    """The period (samples) of the largest peak of ``amp`` at frequencies of at least 1.5
    cycles per ``n_samples`` (the trace length; below, the taper's leak of the mean), refined
    by a parabola through the peak and its neighbours. NaN for a flat spectrum."""
    f, a = np.asarray(freq, np.float64), np.asarray(amp, np.float64)
    ok = np.flatnonzero(f >= 1.5 / n_samples)
    if ok.size < 3 or not np.any(a[ok] > 0):
        return float("nan")
    k = int(ok[np.argmax(a[ok])])
    if 0 < k < f.size - 1:
        den = a[k - 1] - 2 * a[k] + a[k + 1]
        off = 0.5 * (a[k - 1] - a[k + 1]) / den if den != 0 else 0.0
    else:
        off = 0.0
    fk = f[k] + off * (f[1] - f[0])
    return float(1.0 / fk) if fk > 0 else float("nan")


def centroid_period(freq: np.ndarray, amp: np.ndarray, n_samples: int) -> float:
    """The period (samples) of the amplitude-weighted mean frequency of ``amp`` over the
    frequencies of at least 1.5 cycles per ``n_samples``: ``1 / (sum f a / sum a)``. Unlike
    the peak (:func:`peak_period`), it is stable on a flat (whitened) spectrum. NaN if
    ``amp`` is zero there."""
    f, a = np.asarray(freq, np.float64), np.asarray(amp, np.float64)
    ok = f >= 1.5 / n_samples
    total = float(a[ok].sum())
    if total <= 0:
        return float("nan")
    fc = float((f[ok] * a[ok]).sum()) / total
    return 1.0 / fc if fc > 0 else float("nan")


def dominant_period(section: np.ndarray) -> float:
    """Period (samples) of the centroid of the traces' mean amplitude spectrum
    (:func:`amplitude_spectrum`, :func:`centroid_period`)."""
    s = _section(section)
    return centroid_period(*amplitude_spectrum(s), s.shape[0])


def excess_kurtosis(section: np.ndarray) -> float:
    """Excess kurtosis ``m4 / m2**2 - 3`` of the section's live amplitudes (finite, not exactly
    zero): 0 for Gaussian amplitudes, -1.5 for a sinusoid, > 0 for spiky ones. NaN if fewer
    than 4 amplitudes."""
    a = np.asarray(section, dtype=np.float64).ravel()
    a = a[np.isfinite(a) & (a != 0.0)]
    return kurtosis(a) if a.size >= 4 else float("nan")


def fault_instances(fault: np.ndarray, fault_id: np.ndarray | None = None) -> np.ndarray:
    """An int label map of the fault instances: ``fault_id`` where given (0 = none), else the
    8-connected components of ``fault > 0``."""
    if fault_id is not None:
        fid = np.asarray(fault_id).astype(np.int64)
        return np.where(np.asarray(fault) > 0, fid, 0) if fault is not None else fid
    lab, _ = ndimage.label(np.asarray(fault) > 0, structure=np.ones((3, 3), int))
    return lab


def local_dips(instances: np.ndarray, radius_px: int = 8, max_ratio: float = 0.3) -> np.ndarray:
    """Apparent dip (degrees from horizontal, 0-90) of the label at each of its pixels, in
    pixel space (rows against columns).

    At each pixel of an instance, the pixels of the same instance within ``radius_px`` (a
    disk) have a covariance of their (row, column) offsets; its principal axis is the local
    direction of the polyline, and the dip is that axis' angle from the horizontal (the column
    axis): ``|0.5 * atan2(2 c_rx, c_xx - c_rr)|`` with ``r`` rows and ``x`` columns.
    Pixels whose neighbourhood is not elongated (minor / major eigenvalue > ``max_ratio``, a
    blob or a junction) or holds fewer than 3 pixels give no dip. Every pixel of a line
    counts once, so the distribution weights each instance by its length.

    Returns
    -------
    (n,) float64: the dips of the pixels that have one, instance by instance.
    """
    lab = np.asarray(instances)
    r = int(radius_px)
    dy, dx = np.mgrid[-r:r + 1, -r:r + 1].astype(np.float64)
    disk = (dy * dy + dx * dx <= r * r).astype(np.float64)
    kernels = [disk, disk * dy, disk * dx, disk * dy * dy, disk * dx * dx, disk * dy * dx]
    out = []
    for k in np.unique(lab[lab > 0]):
        rows, cols = np.nonzero(lab == k)
        r0, c0 = rows.min() - r, cols.min() - r
        m = np.zeros((rows.max() - r0 + r + 1, cols.max() - c0 + r + 1))
        m[rows - r0, cols - c0] = 1.0
        n, sy, sx, syy, sxx, sxy = (ndimage.correlate(m, kern, mode="constant")[rows - r0, cols - c0]
                                    for kern in kernels)
        keep = n >= 3
        n, sy, sx, syy, sxx, sxy = (v[keep] for v in (n, sy, sx, syy, sxx, sxy))
        cyy, cxx, cxy = syy / n - (sy / n) ** 2, sxx / n - (sx / n) ** 2, sxy / n - (sy / n) * (sx / n)
        half_tr, det = 0.5 * (cyy + cxx), cyy * cxx - cxy * cxy
        disc = np.sqrt(np.maximum(half_tr ** 2 - det, 0.0))
        big, small = half_tr + disc, half_tr - disc
        elongated = (big > 0) & (small <= max_ratio * big)
        phi = 0.5 * np.degrees(np.arctan2(2.0 * cxy, cxx - cyy))   # from the column axis
        out.append(np.abs(phi[elongated]))
    return np.concatenate(out) if out else np.empty(0)


def label_fraction(fault: np.ndarray) -> float:
    """Fault pixels / pixels."""
    f = np.asarray(fault)
    return float(np.count_nonzero(f > 0) / f.size)


def faults_per_100_traces(instances: np.ndarray) -> float:
    """Fault instances crossing the section per 100 of its traces (columns)."""
    lab = np.asarray(instances)
    return 100.0 * np.unique(lab[lab > 0]).size / lab.shape[1]


def throws_m(fault: np.ndarray, slip_m: np.ndarray, dip_deg: np.ndarray) -> np.ndarray:
    """Throw ``slip * sin(dip)`` (m) at each fault pixel with a finite slip and dip."""
    f = np.asarray(fault) > 0
    s = np.asarray(slip_m, np.float64)[f]
    d = np.asarray(dip_deg, np.float64)[f]
    ok = np.isfinite(s) & np.isfinite(d)
    return np.abs(s[ok] * np.sin(np.radians(d[ok])))
