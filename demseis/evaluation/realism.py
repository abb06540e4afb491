"""How much a section looks like a survey's: the measures of ../shared/field/README.md and more.

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
"""

from __future__ import annotations

import numpy as np

from demseis.errors import InputError

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


def adjacent_trace_correlation(section: np.ndarray, intact: np.ndarray | None = None) -> float:
    """Median Pearson correlation of neighbouring traces over half-overlapping 32-sample
    windows, over the windows whose pixels (both traces) are all ``intact`` and not silent.
    NaN if there is none."""
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
    v = np.concatenate(vals) if vals else np.empty(0)
    return float(np.median(v)) if v.size else float("nan")


def zero_crossings(section: np.ndarray, intact: np.ndarray | None = None) -> float:
    """Median sign changes per 100 samples of a trace (over its live, ``intact`` samples;
    exact zeros are skipped). NaN if no trace has 32 such samples."""
    s = _section(section)
    ok = np.ones(s.shape, bool) if intact is None else np.asarray(intact, bool)
    rates = []
    for j in range(s.shape[1]):
        t = s[ok[:, j], j]
        t = t[t != 0.0]
        if t.size >= WINDOW:
            rates.append(100.0 * np.count_nonzero(np.diff(np.sign(t)) != 0) / (t.size - 1))
    return float(np.median(rates)) if rates else float("nan")


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
