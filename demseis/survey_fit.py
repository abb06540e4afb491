"""``demseis fit``: a config whose sections look like a given survey's.

:func:`fit` reads one or more sections (SEG-Y, or a ``.png`` display image or ``.npy`` with the
sampling given), measures what ``demseis realism`` measures (dominant period, zero crossings,
adjacent-trace correlation, amplitude excess kurtosis) and the wavelet
(:func:`demseis.seismic.wavelet.estimate_wavelet`: band, dominant frequency, constant phase),
clipping and display quantisation, and writes a complete config: a preset (``field`` by
default) with the survey's sampling (``[output] dt_s``, ``trace_spacing_m``), wavelet, noise
and processing, each a range centred on what was measured.

The measures of a synthetic section depend on the geology as well as on the wavelet and noise,
so the first guess is calibrated: a store of the kinematic engine (seconds a run) is generated
from the config, measured like the section, and three knobs are moved towards the section's
values, for ``rounds`` rounds (default 3):

- the frequency scale, by the ratio of dominant periods (the period goes as 1/f);
- the SNR (dB), by ``10 / ln 10`` times the difference of the adjacent-trace correlations'
  logits (the correlation of signal plus independent noise is ``S / (S + N)``);
- the time-gain jitter ``s`` (:mod:`demseis.seismic.processing`), which scales amplitudes
  down the section and so the kurtosis: a scale mixture multiplies ``kurtosis + 3`` by
  ``exp(4 s^2)``; at most :data:`MAX_TIME_GAIN`, so a section more heavy-tailed than that
  reaches keeps a lower kurtosis (the table says so).

From the second round on, the SNR and jitter steps use the slope measured between the last
two rounds (a secant step) where it has the expected sign and is between 1/20 and 5 times the
model's.

Each round's store draws the narrow ranges (``spread="fit"``, :data:`SPREADS`), so that with
that spread what is calibrated is what is written, and the knobs move their centres. With
``spread="preset"`` the preset's spread of frequency, SNR and noise kind is written around the
calibrated centre. The result records every round's measures; ``demseis realism`` on a store
generated from the written config compares it with the section.
"""

from __future__ import annotations

import math
import shutil
import tempfile
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import segyio

from demseis.errors import InputError
from demseis.evaluation.fieldio import read_amplitudes
from demseis.evaluation.realism_report import section_measures, store_measures
from demseis.evaluation.segyfile import is_segy
from demseis.generator.config.settings import load_config, parse_config
from demseis.generator.sweep.driver import run_sweep
from demseis.parameters import PARAMS
from demseis.seismic.wavelet import Wavelet, estimate_wavelet

#: the measures calibrated and compared (those of ``demseis realism``)
MEASURES = ("dominant_period_samples", "zero_crossings_per_100", "adjacent_trace_correlation",
            "excess_kurtosis")

MAX_TIME_GAIN = 0.6
"""The largest time-gain jitter the calibration sets. Above it one bright interval outshines
the rest of a section and the faults labelled elsewhere cannot be seen: fitted to the
tutorial-03 images without a cap (1.4-2.0, to reach their kurtosis of 11.7), a store taught
the field benchmark's U-Net ODS F1 0.18 on those images, against 0.21 for the same store
without the gain (5 seeds each, docs/realism.md). At the cap (0.48-0.72 written) it still cost
0.06-0.07 there (0.17 against 0.23 narrow, 0.18 against 0.26 with ``spread="preset"``): for a
training store on such images, set ``time_gain_jitter = 0`` in the written config."""

CLIP_SHARE = 0.002
"""A section is clipped when more than this share of its samples sit at its extreme values
(within 0.1 % of its range of its minimum or maximum)."""


@dataclass
class Sampling:
    """A section and its sampling."""

    path: str
    section: np.ndarray
    dt_s: float
    trace_spacing_m: float
    display_image: bool


@dataclass
class FitResult:
    """What :func:`fit` found and wrote.

    Attributes
    ----------
    config : the complete config (a dict, TOML-ready).
    sections : the measures of each section (and their median in ``target``).
    target : the median measures of the sections.
    rounds : each calibration round's store measures and the knobs it used.
    toml : the config as TOML text (what ``out`` holds).
    """

    config: dict[str, Any]
    sections: list[dict[str, Any]]
    target: dict[str, float]
    rounds: list[dict[str, Any]] = field(default_factory=list)
    toml: str = ""

    def table(self) -> str:
        """A markdown table: the section's measures beside the last round's store."""
        last = self.rounds[-1]["measures"] if self.rounds else {}
        rows = ["| measure | section(s) | fitted store | difference |", "| --- | --- | --- | --- |"]
        for name in MEASURES:
            t, s = self.target.get(name, math.nan), last.get(name, math.nan)
            diff = (f"{100 * (s - t) / t:+.1f} %" if name != "excess_kurtosis"
                    else f"{s - t:+.2f}")
            rows.append(f"| {name.replace('_', ' ')} | {t:.3g} | {s:.3g} | {diff} |")
        return "\n".join(rows)


def _segy_sampling(path: str) -> tuple[float | None, float | None]:
    """(sample interval in s, trace spacing in m) from a SEG-Y file's headers; None where the
    headers do not say (no interval; no CDP or source/group coordinates)."""
    with segyio.open(path, "r", ignore_geometry=True) as f:
        us = int(f.bin[segyio.BinField.Interval]) or int(
            f.header[0][segyio.TraceField.TRACE_SAMPLE_INTERVAL])
        n = f.tracecount
        spacing = None
        for fx, fy in ((segyio.TraceField.CDP_X, segyio.TraceField.CDP_Y),
                       (segyio.TraceField.SourceX, segyio.TraceField.SourceY),
                       (segyio.TraceField.GroupX, segyio.TraceField.GroupY)):
            idx = range(0, n, max(1, n // 200))
            xy = np.array([[f.header[i][fx], f.header[i][fy]] for i in idx], dtype=np.float64)
            if not np.any(xy):
                continue
            scalar = int(f.header[0][segyio.TraceField.SourceGroupScalar])
            scale = 1.0 if scalar == 0 else (1.0 / -scalar if scalar < 0 else float(scalar))
            step = np.hypot(*np.diff(xy, axis=0).T) * scale / (idx.step or 1)
            step = step[step > 0]
            if step.size:
                spacing = float(np.median(step))
                break
    return (us * 1e-6 if us > 0 else None), spacing


def read_sampling(path: str | Path, dt_s: float | None = None,
                  trace_spacing_m: float | None = None) -> Sampling:
    """A section and its sampling: from a SEG-Y file's headers where they say, else from the
    arguments (which override the headers).

    Raises
    ------
    InputError
        The file cannot be read, or its sample interval or trace spacing is known neither
        from its headers nor from the arguments (the message names the option to give).
    """
    p = str(path)
    section = read_amplitudes(p)
    head_dt, head_dx = _segy_sampling(p) if is_segy(p) else (None, None)
    dt = dt_s if dt_s is not None else head_dt
    dx = trace_spacing_m if trace_spacing_m is not None else head_dx
    where = "its headers do not say" if is_segy(p) else "an image or array has no headers"
    if dt is None:
        raise InputError(f"{p!r}: the sample interval is unknown ({where}); give it with "
                         "--dt-ms (dt_s=)")
    if dx is None:
        raise InputError(f"{p!r}: the trace spacing is unknown ({where}); give it with "
                         "--trace-spacing-m (trace_spacing_m=)")
    for name, v in (("dt_s", dt), ("trace_spacing_m", dx)):
        if not (math.isfinite(v) and v > 0):
            raise InputError(f"{p!r}: {name} must be > 0, got {v!r}")
    return Sampling(p, section, float(dt), float(dx), p.lower().endswith(".png"))


def _band(freqs: np.ndarray, amp: np.ndarray) -> tuple[float, float]:
    """The contiguous band around the spectrum's peak where it is at least half the peak."""
    k = int(np.argmax(amp))
    lo = k
    while lo > 0 and amp[lo - 1] >= 0.5:
        lo -= 1
    hi = k
    while hi < amp.size - 1 and amp[hi + 1] >= 0.5:
        hi += 1
    return float(max(freqs[lo], freqs[1])), float(freqs[hi])


def _ricker_band_octaves() -> float:
    """Octaves between the half-amplitude points of a Ricker's spectrum (any peak)."""
    f = np.linspace(0.001, 4.0, 40000)
    a = Wavelet("ricker", 1.0).amplitude(f)
    lo, hi = _band(f, a / a.max())
    return math.log2(hi / lo)


def measure_section(s: Sampling) -> dict[str, Any]:
    """The measures of one section: those of ``demseis realism``, the wavelet (band at half
    amplitude, dominant frequency, constant phase), the share of clipped samples and whether
    it holds at most 256 distinct values (an 8-bit image)."""
    sec = s.section.astype(np.float64)
    out = dict(section_measures(sec)["measures"])
    est = estimate_wavelet(sec, s.dt_s)
    lo, hi = _band(est.freqs_hz, est.amplitude)
    lo_v, hi_v = float(sec.min()), float(sec.max())
    tol = 1e-3 * (hi_v - lo_v)
    out.update({
        "dominant_hz": est.dominant_hz, "band_low_hz": lo, "band_high_hz": hi,
        "phase_deg": est.phase_deg,
        "clipped_share": float(np.mean((sec <= lo_v + tol) | (sec >= hi_v - tol)))
        if hi_v > lo_v else 0.0,
        "levels": int(np.unique(s.section).size),
    })
    return out


def _median(values: Sequence[float]) -> float:
    v = np.asarray(values, dtype=np.float64)
    v = v[np.isfinite(v)]
    return float(np.median(v)) if v.size else math.nan


def first_guess(target: dict[str, float], sampling: Sampling, preset: str) -> dict[str, Any]:
    """The uncalibrated config: ``preset`` with the survey's sampling, wavelet, noise and
    processing (see the module docstring)."""
    raw = load_config(preset=preset).to_dict()
    raw["output"].update({"domain": "time", "dt_s": sampling.dt_s,
                          "trace_spacing_m": sampling.trace_spacing_m})
    lo, hi = target["band_low_hz"], target["band_high_hz"]
    octaves = math.log2(hi / lo)
    sweep = raw["sweep"]
    if abs(octaves - _ricker_band_octaves()) <= 0.35:
        sweep.update({"wavelet": "ricker", "freq_hz": target["dominant_hz"]})
    else:  # the Ormsby's half-amplitude points sit mid-ramp, a quarter octave outside f2, f3
        sweep.update({"wavelet": "ormsby", "freq_hz": math.sqrt(lo * hi),
                      "band_octaves": float(np.clip(octaves - 0.5, 0.5, 5.0))})
    nyquist = 0.5 / sampling.dt_s
    sweep["freq_hz"] = float(min(sweep["freq_hz"], 0.45 * nyquist))
    sweep.update({"wavelet_phase": "zero", "wavelet_phase_deg": target["phase_deg"],
                  "noise_kind": "band", "snr_db": 15.0, "time_gain_jitter": 0.0})
    if target["clipped_share"] > CLIP_SHARE:
        sweep["clip_percentile"] = float(np.clip(100.0 * (1.0 - target["clipped_share"]), 50, 99.9))
    if sampling.display_image or target["levels"] <= 256:
        sweep["quantise_bits"] = 8
    return raw


def _knobs(sweep: dict[str, Any]) -> dict[str, float]:
    return {"freq_hz": float(sweep["freq_hz"]), "snr_db": float(sweep["snr_db"]),
            "time_gain_jitter": float(sweep["time_gain_jitter"])}


SPREADS = ("fit", "preset")
"""How wide the written ranges are around the calibrated centre (``fit(spread=...)``):

- ``fit``: narrow, the survey's look only: frequency +-10 %, SNR +-3 dB, the fitted noise kind;
- ``preset``: the preset's own spread moved onto the calibrated centre: its frequency range
  scaled so that its geometric centre is the fitted frequency (the field preset's 15-60 Hz is
  a factor of 2 either side), its SNR values shifted so that their median finite value is the
  fitted SNR (noise-free samples stay noise-free), its noise kinds.

Both keep the fitted sampling, wavelet family, phase +-15 deg, time-gain jitter +-20 %,
clipping and display quantisation. The centre is calibrated with the narrow spread either way:
``demseis realism`` measures only a store's noise-free samples where it has any (the preset's
SNR values include them), so a spread store's measures do not see the SNR."""


def _geo_centre(values: Sequence[float]) -> float:
    v = np.asarray(values, dtype=np.float64)
    return float(np.sqrt(v.min() * v.max()))


def _preset_spread(sweep: dict[str, Any], f: float, snr: float, preset_sweep: dict[str, Any],
                   nyquist: float) -> None:
    """Set the frequency, SNR and noise kind of ``sweep`` (in place) to ``preset_sweep``'s
    distributions moved onto the calibrated ``f`` and ``snr`` (:data:`SPREADS`), kept inside
    the parameters' bounds (1 Hz to 0.45 of Nyquist, SNR at least -40 dB); where the preset
    gives one number, ``sweep`` keeps what it has."""
    f_lo, snr_lo = PARAMS["freq_hz"].lo, PARAMS["snr_db"].lo
    top = 0.45 * nyquist

    def freq(x: Any) -> float:
        return round(max(min(float(x), top), f_lo), 3)

    def noise(x: Any) -> float:
        return round(max(float(x), snr_lo), 2)

    pf = preset_sweep.get("freq_hz")
    if isinstance(pf, dict) and pf.get("dist") == "uniform":
        k = f / _geo_centre([pf["low"], pf["high"]])
        hi = freq(k * float(pf["high"]))
        sweep["freq_hz"] = {"dist": "uniform", "low": min(freq(k * float(pf["low"])), hi),
                            "high": hi}
    elif isinstance(pf, dict) and pf.get("dist") == "choice":
        k = f / _geo_centre(pf["values"])
        sweep["freq_hz"] = {"dist": "choice",
                            "values": sorted({freq(k * float(v)) for v in pf["values"]})}
    ps = preset_sweep.get("snr_db")
    if isinstance(ps, dict) and ps.get("dist") == "choice":
        values = [float(v) for v in ps["values"]]                 # "inf" is a string there
        finite = [v for v in values if math.isfinite(v)]
        shift = snr - float(np.median(finite)) if finite else 0.0
        sweep["snr_db"] = {"dist": "choice",
                           "values": [noise(v + shift) if math.isfinite(v) else v for v in values]}
    elif isinstance(ps, dict) and ps.get("dist") == "uniform":
        shift = snr - 0.5 * (float(ps["low"]) + float(ps["high"]))
        sweep["snr_db"] = {"dist": "uniform", "low": noise(float(ps["low"]) + shift),
                           "high": noise(float(ps["high"]) + shift)}
    if "noise_kind" in preset_sweep:
        sweep["noise_kind"] = preset_sweep["noise_kind"]


def _with_ranges(raw: dict[str, Any], spread: str = "fit",
                 preset_sweep: dict[str, Any] | None = None) -> dict[str, Any]:
    """The calibrated point turned into ranges centred on it (:data:`SPREADS`): frequency
    +-10 %, SNR +-3 dB, phase +-15 deg, time-gain jitter +-20 %, band +-0.25 octave; with
    ``spread="preset"`` the frequency, SNR and noise kind take ``preset_sweep``'s spread
    instead."""
    sweep = raw["sweep"]
    f = float(sweep["freq_hz"])
    sweep["freq_hz"] = {"dist": "uniform", "low": round(0.9 * f, 3), "high": round(1.1 * f, 3)}
    snr = float(sweep["snr_db"])
    sweep["snr_db"] = {"dist": "uniform", "low": round(max(snr - 3.0, -40.0), 2),
                       "high": round(snr + 3.0, 2)}
    if spread == "preset" and preset_sweep is not None:
        _preset_spread(sweep, f, snr, preset_sweep, 0.5 / float(raw["output"]["dt_s"]))
    ph = float(sweep["wavelet_phase_deg"])
    sweep["wavelet_phase_deg"] = {"dist": "uniform", "low": round(max(ph - 15.0, -180.0), 1),
                                  "high": round(min(ph + 15.0, 180.0), 1)}
    tg = float(sweep["time_gain_jitter"])
    if tg > 0:
        sweep["time_gain_jitter"] = {"dist": "uniform", "low": round(0.8 * tg, 4),
                                     "high": round(min(1.2 * tg, 2.0), 4)}
    if sweep.get("wavelet") == "ormsby":
        b = float(sweep["band_octaves"])
        sweep["band_octaves"] = {"dist": "uniform", "low": round(max(b - 0.25, 0.5), 3),
                                 "high": round(min(b + 0.25, 5.0), 3)}
    return raw


def _logit(c: float) -> float:
    c = min(max(c, 1e-4), 1.0 - 1e-4)
    return math.log(c / (1.0 - c))


def _secant(x0: float, x1: float, y0: float, y1: float, default: float) -> float:
    """The slope ``dy/dx`` between two rounds, or ``default`` when they are too close or the
    slope has the wrong sign (noise in the measures)."""
    if abs(x1 - x0) < 1e-9:
        return default
    slope = (y1 - y0) / (x1 - x0)
    return slope if slope * default > 0 and 0.05 <= slope / default <= 5.0 else default


def _corr_y(measures: dict[str, float]) -> float:
    """What the SNR moves linearly: the logit of the adjacent-trace correlation."""
    return _logit(measures["adjacent_trace_correlation"])


def _kurt_y(measures: dict[str, float]) -> float:
    """What the squared time-gain jitter moves linearly: ``ln(kurtosis + 3)``."""
    return math.log(max(measures["excess_kurtosis"] + 3.0, 0.5))


def _step(x: float, y: float, y_want: float, default: float,
          prev: tuple[float, float] | None) -> float:
    """The knob ``x`` moved so that ``y`` reaches ``y_want``: by the slope ``default``, or by
    the secant through the previous round ``prev = (x, y)`` (:func:`_secant`)."""
    slope = default if prev is None else _secant(prev[0], x, prev[1], y, default)
    return x + (y_want - y) / slope


def calibrate(raw: dict[str, Any], target: dict[str, float], rounds: int, work: Path,
              progress: bool = False) -> list[dict[str, Any]]:
    """Move the frequency, SNR and time-gain jitter of ``raw`` (in place) towards ``target``
    over ``rounds`` rounds (module docstring); the rounds' records. Each round generates the
    config as it would be written (its runs, renders and seed) with the kinematic engine, so
    the last round's measures are those of ``demseis generate`` on the written config with
    ``[model] engine = "kinematic"`` and the narrow spread (``spread="fit"``)."""
    records = []
    for k in range(rounds + 1):
        trial = _with_ranges({sec: dict(v) if isinstance(v, dict) else v
                              for sec, v in raw.items()})
        trial["model"] = {**raw["model"], "engine": "kinematic"}
        out = work / f"round{k}.zarr"
        run_sweep(parse_config(trial), out, workers=0, progress=progress)
        got = store_measures(out, max_samples=10**6)["measures"]
        got = {m: float(got[m]["median"] if isinstance(got[m], dict) else got[m]) for m in MEASURES}
        records.append({"round": k, "knobs": _knobs(raw["sweep"]), "measures": got})
        shutil.rmtree(out, ignore_errors=True)
        if k == rounds:
            break
        sweep = raw["sweep"]
        ratio = got["dominant_period_samples"] / target["dominant_period_samples"]
        nyquist = 0.5 / float(raw["output"]["dt_s"])
        sweep["freq_hz"] = float(np.clip(sweep["freq_hz"] * ratio, 1.0, 0.45 * nyquist))
        prev = records[-2] if len(records) > 1 else None
        # SNR: the logit of the correlation moves 1 per 10/ln10 dB; time-gain jitter:
        # ln(kurtosis + 3) moves 4 per unit of s^2; then the secant of the rounds
        snr = _step(sweep["snr_db"], _corr_y(got), _corr_y(target), math.log(10.0) / 10.0,
                    None if prev is None else (prev["knobs"]["snr_db"], _corr_y(prev["measures"])))
        sweep["snr_db"] = float(np.clip(snr, -10.0, 40.0))
        s2 = _step(float(sweep["time_gain_jitter"]) ** 2, _kurt_y(got), _kurt_y(target), 4.0,
                   None if prev is None else (prev["knobs"]["time_gain_jitter"] ** 2,
                                              _kurt_y(prev["measures"])))
        sweep["time_gain_jitter"] = float(min(math.sqrt(max(s2, 0.0)), MAX_TIME_GAIN))
    return records


def to_toml(raw: dict[str, Any], header: Sequence[str] = ()) -> str:
    """A config dict as TOML text: top-level keys first, then one table per section; a key
    whose value is None (TOML has no null: the key's default) is left out."""
    def value(v: Any) -> str:
        if isinstance(v, bool):
            return "true" if v else "false"
        if isinstance(v, (int, np.integer)):
            return str(int(v))
        if isinstance(v, (float, np.floating)):
            f = float(v)
            return ("inf" if f > 0 else "-inf") if math.isinf(f) else repr(f)
        if isinstance(v, str):
            return '"' + v.replace("\\", "\\\\").replace('"', '\\"') + '"'
        if isinstance(v, (list, tuple)):
            return "[" + ", ".join(value(x) for x in v) + "]"
        if isinstance(v, dict):
            return "{ " + ", ".join(f"{k} = {value(x)}" for k, x in v.items()) + " }"
        raise InputError(f"cannot write {v!r} ({type(v).__name__}) to TOML")

    lines = [f"# {h}" if h else "#" for h in header]
    tables = {k: v for k, v in raw.items() if isinstance(v, dict)}
    lines += [f"{k} = {value(v)}" for k, v in raw.items() if k not in tables and v is not None]
    for name, table in tables.items():
        lines += ["", f"[{name}]"] + [f"{k} = {value(v)}" for k, v in table.items()
                                      if v is not None]
    return "\n".join(lines) + "\n"


def fit(sections: str | Path | Sequence[str | Path], out: str | Path | None = None, *,
        dt_s: float | None = None, trace_spacing_m: float | None = None,
        preset: str = "field", rounds: int = 3, spread: str = "fit",
        progress: bool = False) -> FitResult:
    """Fit a config to one or more sections of a survey.

    Parameters
    ----------
    sections : SEG-Y files (or ``.png`` / ``.npy`` with ``dt_s`` and ``trace_spacing_m``) of
        one survey: one sample interval. A ``.png`` is a grey display image: its luminance
        less its median is the amplitude.
    out : write the config here as TOML (None: only return it).
    dt_s, trace_spacing_m : the sampling, where the headers do not give it (they override
        the headers).
    preset : the preset the config starts from (its geology, faults and model).
    rounds : calibration rounds (0: the first guess only).
    spread : how wide the written ranges are around the calibrated centre (:data:`SPREADS`):
        ``"fit"`` (the survey's look only) or ``"preset"`` (the preset's spread of frequency,
        SNR and noise kind, moved onto the survey's centre).
    progress : progress bars of the calibration stores.

    Returns
    -------
    :class:`FitResult`.
    """
    paths = [sections] if isinstance(sections, (str, Path)) else list(sections)
    if not paths:
        raise InputError("give at least one section to fit")
    if not (isinstance(rounds, int) and 0 <= rounds <= 10):
        raise InputError(f"rounds must be an integer in [0, 10], got {rounds!r}")
    if spread not in SPREADS:
        raise InputError(f"spread must be one of {', '.join(SPREADS)}, got {spread!r}")
    samplings = [read_sampling(p, dt_s, trace_spacing_m) for p in paths]
    if len({s.dt_s for s in samplings}) > 1:
        raise InputError("the sections have different sample intervals "
                         f"({sorted({s.dt_s for s in samplings})} s): fit one survey at a time")
    measured = [measure_section(s) for s in samplings]
    target = {k: _median([m[k] for m in measured]) for k in measured[0]}
    raw = first_guess(target, samplings[0], preset)
    preset_sweep = load_config(preset=preset).to_dict()["sweep"]
    with tempfile.TemporaryDirectory(prefix="demseis-fit-") as tmp:
        records = calibrate(raw, target, rounds, Path(tmp), progress=progress)
    raw = _with_ranges(raw, spread, preset_sweep)
    raw["name"] = f"fit:{Path(paths[0]).name}" + (f"+{len(paths) - 1}" if len(paths) > 1 else "")
    result = FitResult(raw, [{"path": s.path, **m} for s, m in zip(samplings, measured)],
                       target, records)
    header = [f"demseis fit {' '.join(str(p) for p in paths)}",
              f"sampling: dt {samplings[0].dt_s * 1e3:g} ms, traces every "
              f"{samplings[0].trace_spacing_m:g} m; preset {preset}, spread {spread}; {rounds} "
              "calibration rounds",
              ""] + result.table().splitlines() + [""] + [
        f"round {r['round']}: " + ", ".join(f"{k} {v:.4g}" for k, v in r["knobs"].items())
        + " -> " + ", ".join(f"{k} {v:.3g}" for k, v in r["measures"].items())
        for r in records]
    result.toml = to_toml(raw, header)
    if out is not None:
        load_config(_write(out, result.toml))  # what is written must load
    return result


def _write(out: str | Path, text: str) -> Path:
    """Write ``text`` to ``out`` atomically."""
    out = Path(out)
    tmp = out.with_name(f".{out.name}.tmp")
    tmp.write_text(text)
    tmp.replace(out)
    return out
