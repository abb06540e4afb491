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

``demseis realism`` (:func:`realism_report`) puts a store beside a field section and the
field targets (:data:`FIELD_TARGETS`) with these and:

- :func:`dominant_period` (centroid of the traces' mean amplitude spectrum) and
  :func:`peak_period`; :func:`excess_kurtosis` of the amplitudes;
- from the labels: :func:`local_dips` (apparent dip in pixel space, a local principal axis
  along each instance), :func:`faults_per_100_traces`, :func:`label_fraction` and
  :func:`throws_m` (``slip_m * sin(dip_deg)``).
"""

from __future__ import annotations

import json

import numpy as np
from scipy import ndimage

from demseis.datasets import open_store, read_sample, store_layout
from demseis.datasets.read import done_samples
from demseis.errors import InputError
from demseis.evaluation.segyfile import read_segy_section

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
    if a.size < 4:
        return float("nan")
    d = a - a.mean()
    m2 = float(np.mean(d * d))
    return float(np.mean(d ** 4) / m2 ** 2 - 3.0) if m2 > 0 else float("nan")


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


# ---- a store beside a field section: `demseis realism` ------------------------------------------

FIELD_TARGETS: dict[str, dict] = {
    "dominant_period_samples": {
        "low": None, "high": None, "median": 7.0, "text": "~7 (4 ms)",
        "source": "hand-picked field sections (seven 2D time sections, 4 ms): a dominant period of "
                  "about 7 samples at 4 ms, 25 zero crossings per 76 samples"},
    "zero_crossings_per_100": {
        "low": None, "high": None, "median": 34.0, "text": "~34 (F3)",
        "source": "F3 inline at 4 ms, measured as here"},
    "adjacent_trace_correlation": {
        "low": None, "high": None, "median": 0.92, "text": "0.92 (F3)",
        "source": "F3 inline at 4 ms, measured as here"},
    "apparent_dip_deg": {
        "low": 81.0, "high": 88.0, "median": 85.0, "text": "81-88, median 85",
        "source": "faults picked by hand on seven 2D time sections of a field survey (4 ms, "
                  "~490 traces): 10th-90th percentile and median, in pixel space"},
    "faults_per_100_traces": {
        "low": 100 * 9 / 490, "high": 100 * 20 / 490, "median": None,
        "text": "1.8-4.1 (9-20 per ~490 traces)",
        "source": "the same hand-picked sections: 9 to 20 faults per section of ~490 traces"},
    "label_fraction_pct": {
        "low": 1.3, "high": 2.5, "median": None, "text": "1.3-2.5 %",
        "source": "the same hand-picked sections: one-pixel polylines, 1.3 to 2.5 % of the pixels"},
}
"""Targets from field statistics, printed beside a store's measures by :func:`realism_report`.

They are hand-picked, published or measured values (the project's field reference), not computed
here: the hand-picked sections cannot be shared, and F3 has no fault labels, so the label
measures (dip, faults per 100 traces, label fraction) can only be compared with these numbers.
``low``/``high`` bound a range (10th-90th percentile or min-max), ``median`` is a central
value; ``text`` is what the table prints.
"""

MEASURES: tuple[tuple[str, str, bool], ...] = (
    ("dominant_period_samples", "dominant period (samples)", False),
    ("peak_period_samples", "spectral peak period (samples)", False),
    ("zero_crossings_per_100", "zero crossings per 100 samples", False),
    ("adjacent_trace_correlation", "adjacent-trace correlation", False),
    ("excess_kurtosis", "amplitude excess kurtosis", False),
    ("apparent_dip_deg", "apparent dip in pixels (deg)", True),
    ("faults_per_100_traces", "faults per 100 traces", True),
    ("label_fraction_pct", "label fraction (%)", True),
    ("throw_m", "throw (m)", True),
    ("throw_samples", "throw (output samples)", True),
)
"""(key, table label, needs labels) of every measure of the report, in table order."""

#: histogram bins of the distributions in a report
HIST_BINS: dict[str, np.ndarray] = {
    "apparent_dip_deg": np.linspace(0.0, 90.0, 46),
    "faults_per_100_traces": np.linspace(0.0, 10.0, 41),
    "label_fraction_pct": np.linspace(0.0, 10.0, 41),
}


def _distribution(values: np.ndarray, bins: np.ndarray | int = 30) -> dict | None:
    v = np.asarray(values, np.float64)
    v = v[np.isfinite(v)]
    if v.size == 0:
        return None
    if not isinstance(bins, int):       # fixed bins: extend them, at their step, over every value
        bins = np.asarray(bins, np.float64)
        step = bins[1] - bins[0]
        if v.max() > bins[-1]:
            bins = np.append(bins, bins[-1] + step * np.arange(1, np.ceil((v.max() - bins[-1]) / step) + 1))
    counts, edges = np.histogram(v, bins=bins)
    p10, med, p90 = (float(x) for x in np.percentile(v, [10, 50, 90]))
    return {"median": med, "p10": p10, "p90": p90, "n": int(v.size),
            "hist": {"edges": [round(float(e), 6) for e in edges], "counts": counts.tolist()}}


def _rms(section: np.ndarray) -> float:
    s = np.asarray(section, np.float64)
    r = float(np.sqrt(np.mean(s[np.isfinite(s)] ** 2))) if np.isfinite(s).any() else 0.0
    return r if r > 0 else 1.0


def _spectrum_json(freq: np.ndarray, amp: np.ndarray) -> dict:
    top = float(amp.max()) or 1.0
    return {"freq_cycles_per_sample": [round(float(f), 6) for f in freq],
            "amplitude": [round(float(a) / top, 5) for a in amp]}


def section_measures(section: np.ndarray) -> dict:
    """The measures of a section without labels (a field section): dominant and peak period, zero
    crossings, adjacent-trace correlation (all windows), excess kurtosis, and the mean
    amplitude spectrum (``spectrum``, normalised to a peak of 1)."""
    s = _section(section)
    freq, amp = amplitude_spectrum(s)
    return {"measures": {
                "dominant_period_samples": centroid_period(freq, amp, s.shape[0]),
                "peak_period_samples": peak_period(freq, amp, s.shape[0]),
                "zero_crossings_per_100": zero_crossings(s),
                "adjacent_trace_correlation": adjacent_trace_correlation(s),
                "excess_kurtosis": excess_kurtosis(s)},
            "spectrum": _spectrum_json(freq, amp)}


class _StoreView:
    """What a report reads of a store: its layout, root attributes, done samples and noise."""

    def __init__(self, path) -> None:
        self.path = getattr(path, "path", path)     # a path or a demseis.Store
        root = open_store(self.path, "r")           # a missing or foreign store: StoreError
        self.layout = store_layout(root)
        self.attrs = dict(root.attrs)
        self.arrays = tuple(self.layout.arrays)
        self.done = done_samples(root, self.layout.n_samples, self.path, require_any=False)
        self.snr_db = (np.asarray(root["params"]["snr_db"][:], np.float64)
                       if "snr_db" in self.layout.params else None)

    def __len__(self) -> int:
        return self.layout.n_samples


def _draw(cands: np.ndarray, max_samples: int, seed: int) -> np.ndarray:
    if cands.size <= max_samples:
        return cands
    return np.sort(np.random.default_rng(seed).choice(cands, max_samples, replace=False))


def choose_samples(store, max_samples: int = 256, seed: int = 0) -> tuple[np.ndarray, np.ndarray, str]:
    """The samples a report measures of ``store`` (a path or a :class:`demseis.Store`), and a
    sentence saying which.

    Returns ``(seismic, labels, text)``: for the measures of the seismic, the complete samples
    without noise (``snr_db`` = inf) if the store has any, else all complete ones; for the
    measures of the labels (which noise does not change), all complete samples. Each set
    holds at most ``max_samples``, drawn without replacement by
    ``numpy.random.default_rng(seed)`` (the same store, number and seed: the same samples).
    """
    if max_samples < 1:
        raise InputError(f"max_samples must be >= 1, got {max_samples}")
    store = store if isinstance(store, _StoreView) else _StoreView(store)
    done = np.asarray(store.done, bool)
    if not done.any():
        raise InputError(f"store {str(store.path)!r} has no complete samples")
    clean = done & np.isposinf(store.snr_db) if store.snr_db is not None else np.zeros_like(done)
    if clean.any():
        sei, what = np.flatnonzero(clean), "noise-free (snr_db = inf)"
    else:
        sei, what = np.flatnonzero(done), "complete (none is noise-free)"
    lab = np.flatnonzero(done)
    sei_d, lab_d = _draw(sei, max_samples, seed), _draw(lab, max_samples, seed)

    def part(chosen, total, kind):
        return (f"{chosen.size} of {total.size} {kind} samples (seed {seed})"
                if chosen.size < total.size else f"all {total.size} {kind} samples")

    text = (f"seismic: {part(sei_d, sei, what)}; labels: {part(lab_d, lab, 'complete')}; "
            f"the store has {int(done.sum())} complete of {len(store)}")
    return sei_d, lab_d, text


def _column_velocity(layer: np.ndarray, depth_span_m: float, dt_s: float) -> np.ndarray:
    """Mean velocity (m/s) of each column of a time section: its ``depth_span_m`` over half
    the two-way time to the bottom of its rock (the last row with ``layer >= 0``)."""
    rock = np.asarray(layer) >= 0
    n_rows = np.where(rock.any(axis=0), rock.shape[0] - np.argmax(rock[::-1], axis=0), 0)
    with np.errstate(divide="ignore"):
        v = 2.0 * depth_span_m / (n_rows * dt_s)
    return np.where(n_rows > 0, v, np.nan)


def store_measures(path, max_samples: int = 256, seed: int = 0) -> dict:
    """The measures of a store's samples (:func:`choose_samples`), pooled as the docstring of
    :func:`realism_report` says."""
    store = _StoreView(path)
    if "seismic" not in store.arrays:
        raise InputError(f"store {str(store.path)!r} has no 'seismic' array")
    sei_idx, lab_idx, selection = choose_samples(store, max_samples, seed)
    grid = store.attrs.get("grid", {})
    domain = grid.get("domain", "depth")
    cell_m = float(grid.get("cell_m", np.nan))
    dt_s = float(grid.get("dt_s", np.nan)) if domain == "time" else None
    has = {a: a in store.arrays for a in ("fault", "fault_id", "slip_m", "dip_deg", "layer")}
    spectra, zc, corr, kurt = [], [], [], []
    dips, per100, frac, thr_m, thr_s = [], [], [], [], []
    freq = None
    sei_set, lab_set = set(sei_idx.tolist()), set(lab_idx.tolist()) if has["fault"] else set()
    for i in sorted(sei_set | lab_set):
        names = (["seismic"] if i in sei_set else []) + [a for a, ok in has.items() if ok]
        a = read_sample(store.path, int(i), names).arrays
        fault = np.asarray(a["fault"]) == 1 if has["fault"] else None
        if i in sei_set:
            sec = np.asarray(a["seismic"], np.float64)
            sec = np.where(np.isfinite(sec), sec, 0.0)
            freq, amp = amplitude_spectrum(sec / _rms(sec))
            spectra.append(amp)
            zc.append(zero_crossing_rates(sec))
            kurt.append(excess_kurtosis(sec))
            corr.append(trace_correlations(sec, None if fault is None else intact_mask(fault, 6)))
        if i not in lab_set:
            continue
        inst = fault_instances(fault, a.get("fault_id"))
        dips.append(local_dips(inst))
        per100.append(faults_per_100_traces(inst))
        frac.append(100.0 * label_fraction(fault))
        if has["slip_m"] and has["dip_deg"]:
            t = throws_m(fault, a["slip_m"], a["dip_deg"])
            thr_m.append(t)
            if domain == "time":
                if has["layer"]:
                    v = _column_velocity(a["layer"], float(grid["nz"]) * cell_m, dt_s)
                    v_px = np.broadcast_to(v, fault.shape)[fault]
                    s_ok = np.isfinite(np.asarray(a["slip_m"], np.float64)[fault]) \
                        & np.isfinite(np.asarray(a["dip_deg"], np.float64)[fault])
                    thr_s.append(2.0 * t / (v_px[s_ok] * dt_s))
            else:
                thr_s.append(t / cell_m)
    if lab_set:
        unfaulted = sum(1 for x in per100 if x == 0)
        selection += f"; {unfaulted} of the {len(per100)} label samples have no fault"
    amp = np.mean(spectra, axis=0)
    h, w = store.layout.shape
    cat = (lambda xs: np.concatenate(xs) if xs else np.empty(0))
    corr_all = cat(corr)
    measures = {
        "dominant_period_samples": centroid_period(freq, amp, h),
        "peak_period_samples": peak_period(freq, amp, h),
        "zero_crossings_per_100": float(np.median(cat(zc))) if cat(zc).size else float("nan"),
        "adjacent_trace_correlation": float(np.median(corr_all)) if corr_all.size else float("nan"),
        "excess_kurtosis": float(np.nanmedian(kurt)) if np.isfinite(kurt).any() else float("nan"),
        "apparent_dip_deg": _distribution(cat(dips), HIST_BINS["apparent_dip_deg"]),
        "faults_per_100_traces": _distribution(np.asarray(per100), HIST_BINS["faults_per_100_traces"]),
        "label_fraction_pct": _distribution(np.asarray(frac), HIST_BINS["label_fraction_pct"]),
        "throw_m": _distribution(cat(thr_m)),
        "throw_samples": _distribution(cat(thr_s)),
    }
    unit = (f"time samples of {dt_s * 1e3:g} ms" if domain == "time"
            else f"depth cells of {cell_m:g} m")
    return {"path": str(store.path), "shape": [h, w], "domain": domain, "cell_m": cell_m,
            "dt_s": dt_s, "pixels": unit, "selection": selection,
            "seismic_samples": [int(i) for i in sei_idx],
            "label_samples": sorted(int(i) for i in lab_set), "measures": measures,
            "spectrum": _spectrum_json(freq, amp)}


def realism_report(store, field=None, *, max_samples: int = 256, seed: int = 0) -> dict:
    """How a store compares with a field section, measure by measure.

    Parameters
    ----------
    store : path of a demseis store (or a :class:`demseis.Store`).
    field : path of a SEG-Y section (no labels), or None.
    max_samples : measure at most this many samples (:func:`choose_samples`).
    seed : the seed of that draw.

    Returns
    -------
    dict, JSON-ready: ``store`` (path, shape, domain, pixel unit, ``selection`` sentence,
    ``samples`` measured, ``measures``, ``spectrum``), ``field`` (path, shape, ``measures``,
    ``spectrum``; None without ``field``), ``targets`` (:data:`FIELD_TARGETS`) and ``notes``.

    Notes
    -----
    Measures of a store, over its chosen samples (noise-free where it has some):

    - ``dominant_period_samples``: period of the centroid of the mean amplitude spectrum of
      all traces (each sample scaled to unit RMS first; :func:`centroid_period`), and
      ``peak_period_samples`` that of its peak (:func:`peak_period`; arbitrary on a flat,
      whitened spectrum such as F3's);
    - ``zero_crossings_per_100``: median over all traces of their sign changes per 100 samples;
    - ``adjacent_trace_correlation``: median over all 32-sample half-overlapping windows of
      neighbouring traces at least 6 traces from any fault label (:func:`intact_mask`);
    - ``excess_kurtosis``: the median over samples of each one's excess kurtosis;
    - ``apparent_dip_deg``: local dips of every fault-label pixel (:func:`local_dips`);
    - ``faults_per_100_traces``, ``label_fraction_pct``: per sample;
    - ``throw_m``: ``slip_m * sin(dip_deg)`` at every fault pixel; ``throw_samples`` the same
      in output rows: ``/ cell_m`` in depth, ``2 throw / (v dt_s)`` in time with ``v`` the
      mean velocity of the pixel's column (depth of the grid over half the two-way time to
      the bottom of its rock, from the ``layer`` array).

    Distributions are ``{"median", "p10", "p90", "n", "hist": {"edges", "counts"}}``. A field
    section is measured over all its traces and windows (it has no labels).
    """
    path = getattr(store, "path", store)
    _StoreView(path)  # a missing or foreign store fails here, in one line
    field_part = None
    if field is not None:  # read before the store's samples: a bad file fails at once
        sec = read_segy_section(field)
        field_part = {"path": str(field), "shape": list(sec.shape), **section_measures(sec)}
    report: dict = {"store": store_measures(path, max_samples, seed), "field": field_part,
                    "targets": FIELD_TARGETS, "notes": []}
    if report["store"]["domain"] != "time":
        report["notes"].append(
            f"the store is in depth ({report['store']['pixels']}): its period, zero crossings and "
            "pixel dips count depth cells, a field section's count time samples (a time section "
            "is vertically exaggerated: steeper dips in pixels)")
    return report


def report_json(report: dict) -> str:
    """The report as strict JSON (NaN and infinities as null)."""
    def clean(x):
        if isinstance(x, dict):
            return {k: clean(v) for k, v in x.items()}
        if isinstance(x, (list, tuple)):
            return [clean(v) for v in x]
        if isinstance(x, float) and not np.isfinite(x):
            return None
        return x

    return json.dumps(clean(report), indent=1, allow_nan=False) + "\n"


def _fmt(value, key: str) -> str:
    if value is None:
        return "-"
    if isinstance(value, dict):
        return f"{_fmt(value['median'], key)} ({_fmt(value['p10'], key)}-{_fmt(value['p90'], key)})"
    if not np.isfinite(value):
        return "-"
    if key == "adjacent_trace_correlation":
        return f"{value:.3f}"
    return f"{value:.2f}" if abs(value) < 10 else f"{value:.1f}"


def report_rows(report: dict) -> list[tuple[str, str, str, str]]:
    """(measure, store, field section, target) rows of the report's table; distributions as
    ``median (p10-p90)``, '-' where a measure does not apply."""
    field = report.get("field") or {}
    rows = []
    for key, label, labels_only in MEASURES:
        f = "-" if labels_only or not field else _fmt(field["measures"].get(key), key)
        t = report["targets"].get(key, {}).get("text", "-")
        rows.append((label, _fmt(report["store"]["measures"].get(key), key), f, t))
    return rows


def _header(report: dict) -> list[str]:
    s = report["store"]
    lines = [f"store {s['path']}: {s['shape'][0]} x {s['shape'][1]} {s['pixels']}; measured "
             f"{s['selection']}"]
    if report.get("field"):
        f = report["field"]
        lines.append(f"field {f['path']}: {f['shape'][0]} x {f['shape'][1]} (samples x traces)")
    return lines


_FOOT = ("target: from field statistics (hand-picked field sections and F3, not computed "
         "here); distributions: median (p10-p90)")


def format_report(report: dict) -> str:
    """The report as a plain-text table (what ``demseis realism`` prints)."""
    head = ("measure", "store", "field section", "target")
    rows = [head, *report_rows(report)]
    widths = [max(len(r[c]) for r in rows) for c in range(4)]
    out = _header(report)
    out += ["  ".join(c.ljust(w) for c, w in zip(r, widths)).rstrip() for r in rows]
    out += [_FOOT, *("note: " + n for n in report["notes"])]
    return "\n".join(out)


def report_markdown(report: dict) -> str:
    """The report as a Markdown table with its header lines and notes."""
    out = [f"{line}  " for line in _header(report)] + [""]
    out += ["| measure | store | field section | target |", "| --- | --- | --- | --- |"]
    out += ["| " + " | ".join(r) + " |" for r in report_rows(report)]
    out += ["", _FOOT + ".", *(f"Note: {n}." for n in report["notes"])]
    return "\n".join(out) + "\n"
