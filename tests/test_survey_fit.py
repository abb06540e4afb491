"""demseis fit: sampling from SEG-Y headers (or asked for), the config written as loadable TOML,
and a calibrated config whose store measures like the section it was fitted to."""

from __future__ import annotations

import math
import subprocess
import sys
import tomllib

import numpy as np
import pytest

import demseis
from demseis.errors import InputError
from demseis.generator.config.settings import load_config, parse_config
from demseis.seismic.segy import write_segy
from demseis.survey_fit import MEASURES, SPREADS, _with_ranges, fit, read_sampling, to_toml
from tests._helpers import ROOT


def _segy(tmp_path, section, dt_s=0.004, spacing=12.5, name="s.sgy"):
    return write_segy(section, tmp_path / name, x0_m=0.0, cell_m=spacing, top_m=0.0,
                      domain="time", dt_s=dt_s, trace_spacing_m=spacing)


def test_sampling_comes_from_the_headers_or_is_asked_for(tmp_path):
    sec = np.random.default_rng(0).standard_normal((64, 30)).astype(np.float32)
    s = read_sampling(_segy(tmp_path, sec, dt_s=0.002, spacing=12.5))
    assert s.dt_s == pytest.approx(0.002) and s.trace_spacing_m == pytest.approx(12.5)
    assert s.section.shape == (64, 30) and not s.display_image
    assert read_sampling(tmp_path / "s.sgy", dt_s=0.004).dt_s == 0.004      # the user overrides
    np.save(tmp_path / "s.npy", sec)
    with pytest.raises(InputError, match="sample interval is unknown.*--dt-ms"):
        read_sampling(tmp_path / "s.npy")
    with pytest.raises(InputError, match="trace spacing is unknown.*--trace-spacing-m"):
        read_sampling(tmp_path / "s.npy", dt_s=0.004)
    with pytest.raises(InputError, match="dt_s must be > 0"):
        read_sampling(tmp_path / "s.npy", dt_s=-1.0, trace_spacing_m=25.0)


def test_the_toml_reads_back_as_the_config():
    raw = load_config(preset="field").to_dict()
    raw["sweep"]["snr_db"] = {"dist": "choice", "values": [math.inf, 10.0]}
    text = to_toml(raw, ["a header"])
    assert text.startswith("# a header\n")
    back = tomllib.loads(text)
    expect = {k: ({kk: vv for kk, vv in v.items() if vv is not None} if isinstance(v, dict) else v)
              for k, v in raw.items() if v is not None}
    assert back == expect
    assert load_config_from_text(text) == parse_config(raw).to_dict()   # the same config


def _calibrated(freq_hz: float, snr_db: float, dt_s: float = 0.004) -> dict:
    """The field preset with a calibrated point (what calibrate leaves before the ranges)."""
    raw = load_config(preset="field").to_dict()
    raw["output"]["dt_s"] = dt_s
    raw["sweep"].update({"freq_hz": freq_hz, "snr_db": snr_db, "wavelet_phase_deg": 10.0,
                         "time_gain_jitter": 0.0, "noise_kind": "band"})
    return raw


def test_the_narrow_spread_is_the_fitted_look_only():
    sweep = _with_ranges(_calibrated(36.0, 14.0))["sweep"]
    assert sweep["freq_hz"] == {"dist": "uniform", "low": 32.4, "high": 39.6}
    assert sweep["snr_db"] == {"dist": "uniform", "low": 11.0, "high": 17.0}
    assert sweep["noise_kind"] == "band"
    assert sweep["wavelet_phase_deg"] == {"dist": "uniform", "low": -5.0, "high": 25.0}


def test_the_preset_spread_is_the_presets_moved_onto_the_fitted_centre():
    preset = load_config(preset="field").to_dict()["sweep"]          # 15-60 Hz, SNR inf..5 dB
    raw = _with_ranges(_calibrated(24.0, 12.0, dt_s=0.002), "preset", preset)
    sweep = raw["sweep"]
    lo, hi = sweep["freq_hz"]["low"], sweep["freq_hz"]["high"]
    assert math.sqrt(lo * hi) == pytest.approx(24.0)                      # centred (geometric)
    assert hi / lo == pytest.approx(preset["freq_hz"]["high"] / preset["freq_hz"]["low"])
    snr = sweep["snr_db"]["values"]
    finite = [v for v in snr if math.isfinite(v)]
    assert np.median(finite) == pytest.approx(12.0)                       # centred
    preset_snr = [float(v) for v in preset["snr_db"]["values"]]           # "inf" is a string
    assert np.ptp(finite) == pytest.approx(np.ptp([v for v in preset_snr if math.isfinite(v)]))
    assert snr.count(math.inf) == preset_snr.count(math.inf) == 1          # noise-free stays
    assert sweep["noise_kind"] == preset["noise_kind"]                     # white and band
    assert sweep["wavelet_phase_deg"] == {"dist": "uniform", "low": -5.0, "high": 25.0}
    parse_config(raw)                                                      # a valid config
    # at 4 ms the top of 18-72 Hz passes 0.45 Nyquist (56.25 Hz) and is cut there
    top = _with_ranges(_calibrated(36.0, 12.0), "preset", preset)["sweep"]["freq_hz"]
    assert top == {"dist": "uniform", "low": 18.0, "high": 56.25}
    # a low, noisy centre stays inside the parameters' bounds (1 Hz, -40 dB)
    low = _with_ranges(_calibrated(1.5, -30.0), "preset", preset)
    assert low["sweep"]["freq_hz"]["low"] == 1.0 and min(low["sweep"]["snr_db"]["values"]) == -40.0
    parse_config(low)
    # a preset value that is one number keeps the narrow range
    one = dict(preset, freq_hz=30.0, snr_db=10.0)
    sweep = _with_ranges(_calibrated(36.0, 14.0), "preset", one)["sweep"]
    assert sweep["freq_hz"]["low"] == 32.4 and sweep["snr_db"]["low"] == 11.0


def test_an_unknown_spread_is_refused_and_the_cli_offers_every_spread(tmp_path):
    with pytest.raises(InputError, match="spread must be one of fit, preset"):
        fit(tmp_path / "none.sgy", spread="wide")
    from demseis.cli import build_parser

    commands = build_parser()._subparsers._group_actions[0].choices
    for command in ("fit", "generate"):                       # generate --like ... --spread
        action = next(a for a in commands[command]._actions if a.dest == "spread")
        assert tuple(action.choices) == SPREADS, command


def test_the_sampling_and_spread_flags_of_generate_go_with_like(tmp_path, capsys):
    from demseis.cli import main

    assert main(["generate", "--preset", "tiny", "--out", str(tmp_path / "s.zarr"),
                 "--spread", "preset"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "--spread go with --like" in err
    assert not (tmp_path / "s.zarr").exists()


def load_config_from_text(text: str) -> dict:
    import tempfile
    from pathlib import Path

    with tempfile.TemporaryDirectory() as tmp:
        p = Path(tmp) / "c.toml"
        p.write_text(text)
        return load_config(p).to_dict()


@pytest.mark.slow
def test_a_fitted_config_measures_like_its_section(tmp_path):
    """A section of known look (a kinematic store's, 30 Hz Ricker rotated 40 deg, band noise at
    12 dB, 4 ms, 12.5 m traces) is fitted; the calibrated store measures like it (period, zero
    crossings and correlation within 15 %, kurtosis within 0.3), the phase is found, and the
    written config generates."""
    raw = load_config(preset="field").to_dict()
    raw["model"]["engine"] = "kinematic"
    raw["output"].update({"dt_s": 0.004, "trace_spacing_m": 12.5})
    raw["sweep"].update({"n_runs": 2, "freq_hz": 30.0, "wavelet_phase_deg": 40.0,
                         "snr_db": 12.0, "noise_kind": "band", "renders_per_snapshot": 1})
    store = demseis.generate(raw, out=tmp_path / "src.zarr", workers=0, progress=False)
    sec = np.asarray(store.sample(len(store) - 1)["seismic"])
    path = _segy(tmp_path, sec, dt_s=0.004, spacing=12.5)
    result = fit(path, tmp_path / "fit.toml", rounds=2)
    got = result.rounds[-1]["measures"]
    for name in MEASURES[:3]:
        assert got[name] == pytest.approx(result.target[name], rel=0.15), name
    assert abs(got["excess_kurtosis"] - result.target["excess_kurtosis"]) < 0.3
    assert result.target["phase_deg"] == pytest.approx(40.0, abs=25.0)
    cfg = load_config(tmp_path / "fit.toml").to_dict()
    assert cfg["output"]["dt_s"] == 0.004 and cfg["output"]["trace_spacing_m"] == 12.5
    assert cfg["sweep"]["freq_hz"]["dist"] == "uniform"
    assert "| dominant period samples |" in (tmp_path / "fit.toml").read_text()


def testcmd_fit_asks_for_the_sampling_of_an_image(tmp_path):
    from PIL import Image

    Image.fromarray((np.random.default_rng(0).random((40, 30)) * 255).astype(np.uint8)).save(
        tmp_path / "s.png")
    run = subprocess.run([sys.executable, "-m", "demseis", "fit", str(tmp_path / "s.png"),
                          "--out", str(tmp_path / "f.toml")], cwd=ROOT, capture_output=True,
                         text=True, timeout=300)
    assert run.returncode == 2
    assert run.stderr.count("\n") == 1 and "--dt-ms" in run.stderr
    assert not (tmp_path / "f.toml").exists()


@pytest.mark.slow
def test_generate_like_a_section_fits_then_generates(tmp_path):
    rng = np.random.default_rng(1)
    sec = np.cumsum(rng.standard_normal((120, 60)), axis=0).astype(np.float32)
    sec -= sec.mean(axis=0)
    path = _segy(tmp_path, sec, dt_s=0.002, spacing=20.0)
    out = tmp_path / "like.zarr"
    run = subprocess.run([sys.executable, "-m", "demseis", "generate", "--like", str(path),
                          "--preset", "tiny", "--out", str(out), "--workers", "0", "--quiet"],
                         cwd=ROOT, capture_output=True, text=True, timeout=900)
    assert run.returncode == 0, run.stderr[-2000:]
    assert "| dominant period samples |" in run.stdout
    cfg = demseis.open(out).config
    assert cfg["output"]["dt_s"] == 0.002 and cfg["output"]["trace_spacing_m"] == 20.0
    assert cfg["name"] == "fit:s.sgy"
