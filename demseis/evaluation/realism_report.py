"""A store beside a field section: ``demseis realism``. The measures of
:mod:`demseis.evaluation.realism` on a sample of a store's sections (and a field section's),
beside the field targets (:data:`FIELD_TARGETS`), as a dict, JSON, a table or Markdown."""

from __future__ import annotations

import json

import numpy as np

from demseis.datasets import open_store, read_sample, store_layout
from demseis.datasets.layout import domain_varies
from demseis.datasets.read import done_samples, read_params, rows_text
from demseis.errors import InputError
from demseis.evaluation.fieldio import read_amplitudes
from demseis.evaluation.realism import (_section, adjacent_trace_correlation, amplitude_spectrum,
                                        centroid_period, excess_kurtosis, fault_instances,
                                        faults_per_100_traces, intact_mask, label_fraction,
                                        local_dips, peak_period, throws_m, trace_correlations,
                                        zero_crossing_rates, zero_crossings)

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
        self.snr_db = (np.asarray(read_params(self.path)["snr_db"], np.float64)
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
    mixed = domain_varies(grid)                        # depth sections and time sections
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
                # a cropped section of its run's own dt (grid "sampling") does not span the
                # model: no velocity from its rows, no throw in samples
                if has["layer"] and not grid.get("sampling"):
                    v = _column_velocity(a["layer"], float(grid["nz"]) * cell_m, dt_s)
                    v_px = np.broadcast_to(v, fault.shape)[fault]
                    s_ok = np.isfinite(np.asarray(a["slip_m"], np.float64)[fault]) \
                        & np.isfinite(np.asarray(a["dip_deg"], np.float64)[fault])
                    thr_s.append(2.0 * t / (v_px[s_ok] * dt_s))
            elif not mixed:
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
    unit = rows_text(grid)
    return {"path": str(store.path), "shape": [h, w],
            "domain": "depth and time" if mixed else domain, "cell_m": cell_m,
            "dt_s": dt_s, "pixels": unit, "selection": selection,
            "seismic_samples": [int(i) for i in sei_idx],
            "label_samples": sorted(int(i) for i in lab_set), "measures": measures,
            "spectrum": _spectrum_json(freq, amp)}


def realism_report(store, field=None, *, max_samples: int = 256, seed: int = 0) -> dict:
    """How a store compares with a field section, measure by measure.

    Parameters
    ----------
    store : path of a demseis store (or a :class:`demseis.Store`).
    field : path of a field section (no labels; SEG-Y, ``.npy``, or a grey ``.png`` display
        image, read as its luminance less its median), or None.
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
        sec = read_amplitudes(field)
        field_part = {"path": str(field), "shape": list(sec.shape), **section_measures(sec)}
    report: dict = {"store": store_measures(path, max_samples, seed), "field": field_part,
                    "targets": FIELD_TARGETS, "notes": []}
    if report["store"]["domain"] == "depth":
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
