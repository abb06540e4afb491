"""Config parsing and validation: every key checked, clear one-line errors, nothing written."""

from __future__ import annotations

import math
import subprocess
import sys

import pytest

from demseis.cli import main
from demseis.errors import ConfigError
from demseis.generator.config.params import DistSpec, Fixed, GridSpec
from demseis.generator.config.settings import PRESETS, load_config, parse_config

# (TOML text, a fragment the one-line error must contain)
MALFORMED = [
    ("bogus = 1", "bogus"),
    ("[sweep]\nfoo = 3", "sweep.foo"),
    ("[sweep]\ndip_deg = 95", "sweep.dip_deg"),
    ("[sweep]\ndip_deg = \"steep\"", "sweep.dip_deg"),
    ("[sweep]\nthrow_m = -50", "sweep.throw_m"),
    ("[sweep]\nfreq_hz = []", "sweep.freq_hz"),
    ("[sweep]\ndip_deg = { dist = \"gauss\", low = 30, high = 60 }", "sweep.dip_deg.dist"),
    ("[sweep]\ndip_deg = { dist = \"uniform\", low = 60, high = 30 }", "sweep.dip_deg"),
    ("[sweep]\ndip_deg = { dist = \"uniform\", low = 30 }", "sweep.dip_deg"),
    ("[sweep]\ndip_deg = { dist = \"uniform\", low = 30, high = 60, mode = 4 }", "sweep.dip_deg"),
    ("[sweep]\nkn_n_m = { dist = \"loguniform\", low = -1, high = 1e10 }", "sweep.kn_n_m"),
    ("[sweep]\nsnr_db = { dist = \"choice\", values = [] }", "sweep.snr_db.values"),
    ("[sweep]\nnoise_kind = \"pink\"", "sweep.noise_kind"),
    ("[sweep]\nn_runs = 0", "sweep.n_runs"),
    ("[sweep]\nn_layers = 2.5", "sweep.n_layers"),
    ("[sweep]\nfriction = { dist = \"truncnormal\", mean = 0.4, std = -1, low = 0.2, high = 0.6 }",
     "sweep.friction.std"),
    ("[model]\nwidth_m = \"wide\"", "model.width_m"),
    ("[model]\nn_snapshots = 1", "model.n_snapshots"),
    ("[model]\nradius_min_m = 30.0\nradius_max_m = 20.0", "model.radius_min_m"),
    ("[grid]\ncell_m = [5, 10]", "grid.cell_m"),
    ("[output]\nimpedance = \"yes\"", "output.impedance"),
    ("[labels]\nnonsense = 1", "labels.nonsense"),
    ("sweep = 3", "[sweep]"),
    ("[sweep]\nfreq_hz = [20, -40]", "sweep.freq_hz[1]"),
]


@pytest.mark.parametrize("text,fragment", MALFORMED)
def test_malformed_config_exits_2_naming_the_key(tmp_path, capsys, text, fragment):
    cfg = tmp_path / "bad.toml"
    cfg.write_text(text)
    out = tmp_path / "out.zarr"
    code = main(["generate", str(cfg), "--preset", "tiny", "--out", str(out), "--workers", "0"])
    err = capsys.readouterr().err.strip()
    assert code == 2
    assert len(err.splitlines()) == 1, err
    assert err.startswith("demseis: error: ")
    assert fragment in err, err
    assert not out.exists()


def test_invalid_toml_and_missing_file(tmp_path, capsys):
    bad = tmp_path / "broken.toml"
    bad.write_text("[sweep\nseed = ")
    assert main(["generate", str(bad), "--out", str(tmp_path / "o")]) == 2
    assert "not valid TOML" in capsys.readouterr().err
    assert main(["generate", str(tmp_path / "nope.toml"), "--out", str(tmp_path / "o")]) == 2
    assert "does not exist" in capsys.readouterr().err
    assert main(["generate", "--preset", "huge", "--out", str(tmp_path / "o")]) == 2
    assert "--preset 'huge'" in capsys.readouterr().err
    assert not (tmp_path / "o").exists()


def test_cli_process_exit_code_and_no_traceback(tmp_path):
    cfg = tmp_path / "bad.toml"
    cfg.write_text("[sweep]\ndip_deg = 85\n")  # the DEM refuses > 80: refused at load
    proc = subprocess.run([sys.executable, "-m", "demseis", "generate", str(cfg), "--out",
                           str(tmp_path / "x.zarr")], capture_output=True, text=True)
    assert proc.returncode == 2
    assert "Traceback" not in proc.stderr
    assert proc.stderr.strip().splitlines() == [
        "demseis: error: sweep.dip_deg = 85 is not allowed: expected a number in [10, 80]"
    ]


@pytest.mark.parametrize("name", PRESETS)
def test_presets_parse_and_roundtrip(name):
    cfg = load_config(preset=name)
    again = parse_config(cfg.to_dict())
    assert again == cfg
    assert again.to_dict() == cfg.to_dict()


def test_spec_forms():
    cfg = parse_config({
        "sweep": {
            "dip_deg": 50,
            "throw_m": [100, 200],
            "friction": {"dist": "truncnormal", "mean": 0.4, "std": 0.1, "low": 0.2, "high": 0.6},
            "snr_db": {"dist": "choice", "values": ["inf", 10]},
        }
    })
    p = cfg.sweep.params
    assert p["dip_deg"] == Fixed(50.0)
    assert p["throw_m"] == GridSpec((100.0, 200.0))
    assert isinstance(p["friction"], DistSpec) and p["friction"].dist == "truncnormal"
    assert p["snr_db"].values == (math.inf, 10.0)


def test_tiny_sizes():
    cfg = load_config(preset="tiny")
    assert cfg.n_samples >= 8
    assert cfg.samples_per_run * cfg.sweep.n_runs == cfg.n_samples


def test_quick_has_at_least_24_samples():
    assert load_config(preset="quick").n_samples >= 24


def test_file_overrides_preset(tmp_path):
    f = tmp_path / "c.toml"
    f.write_text("[sweep]\nn_runs = 3\n")
    cfg = load_config(f, preset="tiny")
    assert cfg.sweep.n_runs == 3
    assert cfg.model.width_m == load_config(preset="tiny").model.width_m


def test_configerror_is_valueerror():
    with pytest.raises(ConfigError):
        parse_config({"sweep": {"dip_deg": 120}})


def test_file_without_preset_layers_on_quick(tmp_path):
    f = tmp_path / "c.toml"
    f.write_text("[sweep]\nn_runs = 30\nseed = 1\n")
    cfg = load_config(f)
    quick = load_config(preset="quick")
    assert cfg.sweep.n_runs == 30 and cfg.sweep.seed == 1
    assert cfg.sweep.params == quick.sweep.params
    assert cfg.model == quick.model and cfg.samples_per_run == quick.samples_per_run == 12


def test_generate_help_names_every_preset_and_every_file_is_a_preset(capsys):
    """issue 38: `generate --help` named four of the six presets; it names each one, and the
    presets folder holds exactly PRESETS."""
    from importlib import resources

    from demseis.cli import main

    with pytest.raises(SystemExit):
        main(["generate", "--help"])
    text = " ".join(capsys.readouterr().out.split())
    listed = text.split("built-in preset:")[1].split("(")[0]
    assert [p.strip(" ,") for p in listed.replace(" or ", ", ").split(",") if p.strip(" ,")] \
        == list(PRESETS)
    folder = resources.files("demseis.generator") / "presets"
    assert sorted(p.name[:-5] for p in folder.iterdir() if p.name.endswith(".toml")) \
        == sorted(PRESETS)


@pytest.mark.parametrize("raw, message", [
    ({"sweep": {"dip_degs": 50}}, "sweep.dip_degs: unknown key; did you mean 'dip_deg'? (79 keys"),
    ({"sweep": {"engine": "dem"}}, "sweep.engine: unknown key; it belongs in [model] ("),
    ({"model": {"widht_m": 100.0}}, "model.widht_m: unknown key; did you mean 'width_m'?; allowed "
                                    "keys are engine, height_m,"),
    ({"labels": {"fault_stlye": "picks"}}, "labels.fault_stlye: unknown key; did you mean "
                                           "'fault_style'? (34 keys are allowed there: "
                                           "`demseis params` lists them)"),
    ({"swep": {}}, "swep: unknown top-level key; did you mean 'sweep'?; allowed are grid,"),
])
def test_a_mistyped_key_gets_did_you_mean_not_a_list_of_every_key(raw, message):
    """issue 38: a mistyped [sweep] key listed all ~1,000 characters of keys; now the closest
    key, or the section a known key belongs in, and short lists only."""
    with pytest.raises(ConfigError) as err:
        parse_config(raw)
    text = str(err.value)
    assert text.startswith(message) and len(text) < 200, text


def test_a_store_written_before_a_parameter_existed_resumes_at_its_default():
    """A stored config lacking a parameter declared since compares equal when the new config
    leaves it at its default, and differs when it does not."""
    from demseis.generator.sweep.driver import _first_difference, _with_new_defaults

    new = load_config(preset="tiny").to_dict()
    old = {k: dict(v) if isinstance(v, dict) else v for k, v in new.items()}
    for key in ("wavelet", "linear_noise_snr_db", "quantise_bits"):
        del old["sweep"][key]
    assert _with_new_defaults(old, new) == new
    changed = {**new, "sweep": {**new["sweep"], "quantise_bits": 8}}
    assert _first_difference(_with_new_defaults(old, changed), changed) == "sweep.quantise_bits"
