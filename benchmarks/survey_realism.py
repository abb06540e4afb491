"""Does a section look like a survey's? ``elements`` vs ``strata`` rendering at 4 ms, against F3.

Generates `quick`-sized stores sampled like a survey (two-way time at 4 ms, traces 25 m apart,
noise-free, 20/40/60 Hz) for each engine and rendering, and prints one JSON line per measure
and store, then the same measures of the F3 field section
(../shared/field/f3_inline.sgy: "F3 Netherlands data courtesy of dGB Earth Sciences, CC BY-SA
3.0"). Measures (demseis.evaluation.realism, ../shared/field/README.md):

- ``adjacent_trace_correlation`` (F3 0.92) and ``zero_crossings`` per 100 samples (F3 34), in
  windows at least 6 traces from any fault label;
- ``horizon_roughness``: RMS (samples) of tracked peaks from a smooth curve, intact rock;
- ``reflectivity_slope``: slope of the reflectivity's log power vs log frequency, 5-120 Hz
  (> 0: rising with frequency, as in well logs);
- ``offset_agreement``: the fraction of fault pixels with a throw of at least one sample
  whose best-aligning lag between traces 3 either side equals the lag the throw makes
  (``expected_lags``: from the sample's impedance, Vp by Gardner's law) within one sample;
- ``render_s``: seconds to render one snapshot's 3 frequencies (median of 5), and
  ``generate_s``: the wall of the whole store (2 workers).

    PYTHONPATH=$PWD python benchmarks/survey_realism.py [--runs 4] [--out DIR]
        [--field ../shared/field/f3_inline.sgy] [--engines dem,kinematic] [--reuse]
"""

from __future__ import annotations

import argparse
import json
import statistics
import tempfile
import time
from pathlib import Path

import numpy as np

from demseis.datasets import open_store, read_sample
from demseis.evaluation.realism import (adjacent_trace_correlation, expected_lags,
                                        horizon_roughness, intact_mask, offset_agreement,
                                        spectral_slope, zero_crossings)
from demseis.evaluation.segyfile import read_segy_section
from demseis.generator.config.sampling import plan_run
from demseis.generator.config.settings import load_config
from demseis.generator.engines import get_engine
from demseis.generator.render.section import imaging_input, labels_at_traces, state_maps
from demseis.generator.sweep.driver import run_sweep
from demseis.seismic import interface_times

FIELD = Path(__file__).resolve().parents[2] / "shared" / "field" / "f3_inline.sgy"


def survey_config(engine: str, rendering: str, runs: int, extra: str = "") -> str:
    """A `quick`-sized TOML sampled like a survey, noise-free."""
    return f"""
[sweep]
n_runs = {runs}
snr_db = inf
{extra}
[model]
engine = "{engine}"
[output]
domain = "time"
dt_s = 0.004
trace_spacing_m = 25.0
impedance = true
rendering = "{rendering}"
"""


def reflectivity_slope(vp: np.ndarray, rho: np.ndarray, dz_m: float, dt_s: float = 0.0005) -> float:
    """Spectral slope of the reflectivity of property columns (rows of ``dz_m``), resampled to
    a regular two-way-time axis of ``dt_s`` (nearest row)."""
    t_bottom, t_centre = interface_times(vp, dz_m)
    logz = np.log(vp * rho)
    t_max = float(t_bottom[-1].min())
    t = np.arange(0.0, t_max, dt_s)
    cols = []
    for j in range(vp.shape[1]):
        k = np.clip(np.searchsorted(t_bottom[:, j], t), 0, vp.shape[0] - 1)
        cols.append(np.diff(logz[k, j]) / 2.0)
    return spectral_slope(np.stack(cols, axis=1), dt_s)


def store_measures(path: Path, toml: Path, engine: str, rendering: str) -> list[dict]:
    cfg = load_config(toml)
    root = open_store(path)
    n = root["seismic"].shape[0]
    dt = float(cfg.output.dt_s)
    corr, zc, rough, hits, tested = [], [], [], [], 0
    gardner_a = float(cfg.sweep.params["gardner_a"].value)
    gardner_b = float(cfg.sweep.params["gardner_b"].value)
    for i in range(n):
        smp = read_sample(path, i, ("seismic", "fault", "slip_m", "dip_deg", "sense",
                                    "impedance"))
        sec = smp.arrays["seismic"]
        fault = smp.arrays["fault"]
        intact = intact_mask(fault, 6) & (sec != 0)
        corr.append(adjacent_trace_correlation(sec, intact))
        zc.append(zero_crossings(sec, intact))
        rough.append(horizon_roughness(sec, intact))
        z = np.asarray(smp.arrays["impedance"], dtype=np.float64)
        vp = (np.maximum(z, 1.0) / gardner_a) ** (1.0 / (1.0 + gardner_b))
        throw_m = smp.arrays["slip_m"] * np.sin(np.radians(smp.arrays["dip_deg"]))
        lags = expected_lags(fault, throw_m, smp.arrays["sense"], vp, dt)
        frac, k = offset_agreement(sec, fault, lags)
        if k:
            hits.append(frac * k)
            tested += k
    out = []
    for name, vals in (("adjacent_trace_correlation", corr), ("zero_crossings", zc),
                       ("horizon_roughness", rough)):
        v = [x for x in vals if np.isfinite(x)]
        out.append({"measure": name, "engine": engine, "rendering": rendering,
                    "median": round(statistics.median(v), 4) if v else None, "samples": len(v)})
    out.append({"measure": "offset_agreement", "engine": engine, "rendering": rendering,
                "fraction": round(sum(hits) / tested, 4) if tested else None,
                "pixels": tested})
    return out


def snapshot_measures(cfg_path: Path, engine: str, rendering: str, repeats: int = 5) -> list[dict]:
    """Render cost of the last snapshot of run 0 and the reflectivity slope of its properties."""
    cfg = load_config(cfg_path)
    eng = get_engine(cfg.model.engine)
    spec = plan_run(cfg, 0)
    run = eng.simulate(cfg, spec)
    k = cfg.model.n_snapshots - 1
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        state = next(iter(eng.states(cfg, run, [k])))
        maps = labels_at_traces(cfg, state_maps(state, {}))
        img = imaging_input(cfg, state, maps, spec.params)
        from demseis.seismic import imaged_sections
        t_s = np.arange(0, 200) * cfg.output.dt_s
        imaged_sections("1d", img.vp, img.rho, img.dz_m, [20.0, 40.0, 60.0], "time", t_s=t_s,
                        col_step_m=img.col_step_m)
        times.append(time.perf_counter() - t0)
    slope = reflectivity_slope(img.vp, img.rho, img.dz_m)
    return [{"measure": "render_s", "engine": engine, "rendering": rendering,
             "median": round(statistics.median(times), 4), "repeats": repeats},
            {"measure": "reflectivity_slope", "engine": engine, "rendering": rendering,
             "slope": round(slope, 3)}]


def field_measures(path: Path) -> list[dict]:
    sec = read_segy_section(path).astype(np.float64)
    return [{"measure": "adjacent_trace_correlation", "engine": "field F3", "median":
             round(adjacent_trace_correlation(sec), 4)},
            {"measure": "zero_crossings", "engine": "field F3", "median": round(zero_crossings(sec), 2)},
            {"measure": "horizon_roughness", "engine": "field F3",
             "median": round(horizon_roughness(sec), 4)}]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--runs", type=int, default=4)
    ap.add_argument("--out", type=Path, default=None)
    ap.add_argument("--field", type=Path, default=FIELD)
    ap.add_argument("--engines", default="dem,kinematic")
    ap.add_argument("--renderings", default="elements,strata")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--extra", default="", help="extra [sweep] TOML lines")
    ap.add_argument("--reuse", action="store_true",
                    help="measure the stores already in --out instead of generating them")
    ap.add_argument("--skip-snapshot", action="store_true",
                    help="leave out render_s and reflectivity_slope (they simulate run 0)")
    args = ap.parse_args()
    out = args.out or Path(tempfile.mkdtemp(prefix="survey_realism_"))
    out.mkdir(parents=True, exist_ok=True)
    for engine in args.engines.split(","):
        for rendering in args.renderings.split(","):
            toml = out / f"{engine}_{rendering}.toml"
            toml.write_text(survey_config(engine, rendering, args.runs, args.extra))
            store = out / f"{engine}_{rendering}.zarr"
            lines = []
            if not (args.reuse and store.exists()):
                t0 = time.perf_counter()
                run_sweep(load_config(toml), store, workers=args.workers, overwrite=True,
                          progress=False)
                lines.append({"measure": "generate_s", "engine": engine, "rendering": rendering,
                              "wall": round(time.perf_counter() - t0, 2),
                              "workers": args.workers})
            for line in [*lines, *store_measures(store, toml, engine, rendering),
                         *([] if args.skip_snapshot else
                           snapshot_measures(toml, engine, rendering))]:
                print(json.dumps(line), flush=True)
    if args.field.is_file():
        for line in field_measures(args.field):
            print(json.dumps(line), flush=True)


if __name__ == "__main__":
    main()
