"""``demseis render --config`` / ``--like``: a store's runs drawn with another look from their
particle snapshots, byte for byte what ``demseis generate`` writes with that look."""

from __future__ import annotations

import numpy as np
import pytest

from demseis.cli import main
from demseis.errors import ConfigError
from demseis.generator.sweep.rerender import _is_look_key, fitted_look, look_config
from demseis.parameters import PARAMS
from tests._helpers import params_of

#: rendering keys of every kind a re-render may change: sampling, statics, wavelet, noise,
#: processing (sample-level [sweep] keys, one of them drawn) and labels
LOOK = """
[output]
domain = "time"
dt_s = 0.004
trace_spacing_m = 20.0
velocity_median_m = 100.0
[labels]
min_throw_samples = 0.5
[sweep]
wavelet = "ormsby"
band_octaves = 2.5
wavelet_phase_deg = { dist = "uniform", low = -30, high = 30 }
noise_kind = "coloured"
snr_db = [inf, 8]
quantise_bits = 8
renders_per_snapshot = 2
"""


def _arrays(path):
    import zarr

    root = zarr.open_group(str(path), mode="r")
    return root, {k: root[k][:] for k in ("seismic", "fault")}


def test_render_with_a_look_equals_generate_with_it(tiny_store, tmp_path):
    look = tmp_path / "look.toml"
    look.write_text(LOOK)
    rendered, generated = tmp_path / "r.zarr", tmp_path / "g.zarr"
    assert main(["render", str(tiny_store), "--config", str(look), "--out", str(rendered),
                 "--quiet"]) == 0
    assert main(["generate", str(look), "--preset", "tiny", "--out", str(generated),
                 "--workers", "0", "--quiet"]) == 0
    (_, src), (r_root, r) = _arrays(tiny_store), _arrays(rendered)
    g_root, g = _arrays(generated)
    for key in r:
        assert r[key].shape == g[key].shape
        np.testing.assert_array_equal(r[key].view(np.uint8), g[key].view(np.uint8))
    # the look took: time sections at 4 ms of another shape, drawn phases, 8-bit levels
    assert r["seismic"].shape[1:] != src["seismic"].shape[1:]
    assert r["seismic"].shape[0] == 2 * src["seismic"].shape[0]   # two renders per snapshot
    pr = params_of(r_root)
    assert set(pr["wavelet"].tolist()) == {PARAMS["wavelet"].choices.index("ormsby")}
    assert np.unique(pr["wavelet_phase_deg"]).size == pr["wavelet_phase_deg"].size > 1
    assert np.unique(r["seismic"][0]).size <= 256
    for key in ("run_id", "snapshot", "freq_hz", "snr_db", "wavelet", "wavelet_phase_deg"):
        np.testing.assert_array_equal(pr[key], params_of(g_root)[key])
    assert main(["validate", str(rendered)]) == 0


def test_a_look_may_repeat_run_keys_but_not_change_them(tiny_store):
    import zarr

    cfg = dict(zarr.open_group(str(tiny_store), mode="r").attrs)["config"]
    # the store's own config is a valid look (nothing changes)
    assert look_config(cfg, cfg).to_dict()["sweep"] == cfg["sweep"]
    same = look_config(cfg, {"sweep": {"n_runs": 3, "throw_m": 100.0, "freq_hz": 20}})
    assert same.to_dict()["sweep"]["freq_hz"] == 20
    with pytest.raises(ConfigError, match=r"\[sweep\] throw_m, \[model\] width_m differ from "
                                          r"the store's: the stored runs were simulated"):
        look_config(cfg, {"sweep": {"throw_m": 50.0}, "model": {"width_m": 800.0}})
    with pytest.raises(ConfigError, match=r"\[grid\] cell_m differs"):
        look_config(cfg, {"grid": {"cell_m": 5.0}})


def test_render_look_errors(tiny_store, tmp_path, capsys):
    out = tmp_path / "x.zarr"
    assert main(["render", str(tiny_store), "--out", str(out)]) == 2
    assert "give what to render" in capsys.readouterr().err
    assert main(["render", str(tiny_store), "--snr", "10", "--config", str(tmp_path / "no.toml"),
                 "--out", str(out)]) == 2
    assert "no such file" in capsys.readouterr().err
    bad = tmp_path / "bad.toml"
    bad.write_text("[sweep]\ndip_deg = 70\n")
    assert main(["render", str(tiny_store), "--config", str(bad), "--out", str(out)]) == 2
    assert "[sweep] dip_deg differs from the store's" in capsys.readouterr().err
    bad.write_text("[sweep]\nfreq_hz = 900\n")
    assert main(["render", str(tiny_store), "--config", str(bad), "--out", str(out)]) == 2
    assert "--config" in (err := capsys.readouterr().err) and "sweep.freq_hz = 900" in err
    assert main(["render", str(tiny_store), "--snr", "10", "--out", str(out)]) == 2
    assert "--snr and --noise go with --freq" in capsys.readouterr().err
    assert main(["render", str(tiny_store), "--config", str(bad), "--like", "s.sgy",
                 "--out", str(out)]) == 2
    assert "not both" in capsys.readouterr().err
    assert main(["render", str(tiny_store), "--dt-ms", "4", "--freq", "20",
                 "--out", str(out)]) == 2
    assert "go with --like" in capsys.readouterr().err
    assert not out.exists()


def test_fitted_look_keeps_the_sampling_and_sample_keys_only():
    from demseis.generator.config.settings import load_config

    fitted = load_config(preset="field").to_dict()
    fitted["output"].update(dt_s=0.002, trace_spacing_m=12.5)
    fitted["sweep"].update(freq_hz=33.0, quantise_bits=8)
    look = fitted_look(fitted)
    assert look["output"] == {"domain": fitted["output"]["domain"], "dt_s": 0.002,
                              "trace_spacing_m": 12.5}
    assert look["sweep"]["freq_hz"] == 33.0 and look["sweep"]["quantise_bits"] == 8
    assert "n_runs" not in look["sweep"] and "base_stretch" not in look["sweep"]
    assert set(look) == {"output", "sweep"}


@pytest.mark.slow
def test_render_like_a_section_takes_its_look_and_keeps_the_runs(tiny_store, tmp_path, capsys):
    import zarr

    from demseis.seismic.segy import write_segy

    rng = np.random.default_rng(1)
    sec = np.cumsum(rng.standard_normal((120, 60)), axis=0).astype(np.float32)
    sec -= sec.mean(axis=0)
    path = write_segy(sec, tmp_path / "s.sgy", x0_m=0.0, cell_m=20.0, top_m=0.0,
                      domain="time", dt_s=0.002, trace_spacing_m=20.0)
    out = tmp_path / "like.zarr"
    assert main(["render", str(tiny_store), "--like", str(path), "--out", str(out),
                 "--quiet"]) == 0
    assert "| dominant period samples |" in capsys.readouterr().out
    src = dict(zarr.open_group(str(tiny_store), mode="r").attrs)["config"]
    cfg = dict(zarr.open_group(str(out), mode="r").attrs)["config"]
    assert cfg["output"]["domain"] == "time"
    assert cfg["output"]["dt_s"] == 0.002 and cfg["output"]["trace_spacing_m"] == 20.0
    assert cfg["model"] == src["model"] and cfg["grid"] == src["grid"]
    run_keys = [k for k in src["sweep"] if not _is_look_key("sweep", k)]
    assert run_keys and all(cfg["sweep"][k] == src["sweep"][k] for k in run_keys)
    assert main(["validate", str(out)]) == 0


def test_render_with_a_fault_zone_impedance_equals_generate_with_it(tiny_store, tmp_path):
    look = tmp_path / "fz.toml"
    look.write_text("[sweep]\nfault_zone_impedance = -0.2\n")
    rendered, generated = tmp_path / "r.zarr", tmp_path / "g.zarr"
    assert main(["render", str(tiny_store), "--config", str(look), "--out", str(rendered),
                 "--quiet"]) == 0
    assert main(["generate", str(look), "--preset", "tiny", "--out", str(generated),
                 "--workers", "0", "--quiet"]) == 0
    (_, src), (r_root, r), (_, g) = (_arrays(p) for p in (tiny_store, rendered, generated))
    for key in r:
        np.testing.assert_array_equal(r[key].view(np.uint8), g[key].view(np.uint8))
    # the fault zones took (the seismic changed, the labels did not)
    np.testing.assert_array_equal(r["fault"], src["fault"])
    assert not np.array_equal(r["seismic"], src["seismic"])
    assert set(params_of(r_root)["fault_zone_impedance"].tolist()) == {np.float32(-0.2)}


def test_a_fault_zone_impedance_that_moves_the_runs_draws_is_refused(tiny_store):
    import zarr

    cfg = dict(zarr.open_group(str(tiny_store), mode="r").attrs)["config"]
    cfg = {**cfg, "sweep": {**cfg["sweep"], "dip_deg": [40.0, 60.0]}}
    # one value, or a distribution (drawn after every other run key): the runs are kept
    for value in (-0.3, {"dist": "uniform", "low": -0.3, "high": 0.0}):
        kept = look_config(cfg, {"sweep": {"fault_zone_impedance": value}})
        assert kept.to_dict()["sweep"]["dip_deg"] == [40.0, 60.0]
    # a list is crossed with dip_deg's: the runs would take other dips
    with pytest.raises(ConfigError, match=r"fault_zone_impedance as given would change the "
                                          r"stored runs' dip_deg"):
        look_config(cfg, {"sweep": {"fault_zone_impedance": [-0.1, -0.2, -0.3]}})
