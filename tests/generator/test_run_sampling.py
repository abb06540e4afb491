"""Section sampling drawn per run: ``[output] dt_s``, ``trace_spacing_m`` and ``domain`` as
lists or distributions, one shape per store by cropping, the sampling recorded per sample."""

from __future__ import annotations

import math

import numpy as np
import pytest

from demseis.errors import ConfigError
from demseis.generator.config.layout import (crop_to, param_dtypes, sample_shape, section_shape,
                                             trace_spacing)
from demseis.generator.config.params import DistSpec, GridSpec
from demseis.generator.config.sampling import config_of_run
from demseis.generator.config.settings import load_config, parse_config
from tests.generator._helpers import generate_tiny

VARIED = """
[sweep]
n_runs = 4
[model]
engine = "kinematic"
[output]
domain = "time"
dt_s = [0.002, 0.004]
trace_spacing_m = { dist = "uniform", low = 10.0, high = 25.0 }
"""


def _cfg(**output):
    return parse_config({"model": {"width_m": 1000.0, "height_m": 400.0},
                         "sweep": {"throw_m": 100.0, "n_layers": 8}, "output": output})


def test_lists_and_distributions_become_the_sampling_and_round_trip():
    cfg = _cfg(domain="time", dt_s=[0.004, 0.002],
               trace_spacing_m={"dist": "uniform", "low": 12.5, "high": 50.0})
    assert cfg.sampling == {"dt_s": GridSpec((0.004, 0.002)),
                            "trace_spacing_m": DistSpec("uniform", low=12.5, high=50.0)}
    assert (cfg.output.dt_s, cfg.output.trace_spacing_m) == (0.004, 12.5)  # the nominal values
    back = parse_config(cfg.to_dict())
    assert back == cfg and back.to_dict() == cfg.to_dict()
    assert cfg.to_dict()["output"]["dt_s"] == [0.004, 0.002]


def test_one_value_is_a_fixed_sampling_with_the_dict_it_always_had():
    for one in ([0.004], {"dist": "choice", "values": [0.004, 0.004]}):
        cfg = _cfg(domain="time", dt_s=one)
        assert cfg.sampling == {} and cfg.output.dt_s == 0.004
        assert cfg.to_dict() == _cfg(domain="time", dt_s=0.004).to_dict()
        assert config_of_run(cfg, 3) is cfg
    assert "dt_s" not in param_dtypes(cfg) and "trace_spacing_m" not in param_dtypes(cfg)


@pytest.mark.parametrize("output, match", [
    ({"domain": ["depth", "sideways"]}, r"output.domain\[1\] = 'sideways' is not allowed"),
    ({"domain": {"dist": "uniform", "low": 0, "high": 1}}, "needs a numeric parameter"),
    ({"dt_s": [0.002, 0.004]}, "dt_s samples only time-domain sections"),
    ({"domain": "time", "dt_s": [0.002, 0.5]}, r"output.dt_s\[1\] = 0.5"),
    ({"trace_spacing_m": {"dist": "uniform", "low": 30.0, "high": 10.0}}, "low = 30.0 must be <"),
    ({"rendering": ["strata"]}, "only .sweep. parameters and .output. dt_s, trace_spacing_m, "
                                "domain"),
])
def test_bad_sampling_is_one_clear_error(output, match):
    with pytest.raises(ConfigError, match=match):
        _cfg(**output)


def test_lists_cycle_over_runs_and_distributions_are_drawn_per_run():
    cfg = _cfg(domain="time", dt_s=[0.002, 0.004],
               trace_spacing_m={"dist": "uniform", "low": 10.0, "high": 25.0})
    runs = [config_of_run(cfg, k) for k in range(40)]
    assert [r.output.dt_s for r in runs[:4]] == [0.002, 0.004, 0.002, 0.004]
    dx = np.array([r.output.trace_spacing_m for r in runs])
    assert ((dx >= 10.0) & (dx <= 25.0)).all() and np.unique(dx).size == 40
    assert dx.min() < 12.0 and dx.max() > 23.0  # spread over the range
    again = [config_of_run(cfg, k).output for k in range(40)]
    assert again == [r.output for r in runs]  # the same run, the same sampling
    assert all(r.sampling == cfg.sampling and r.sweep == cfg.sweep for r in runs)


def test_the_store_shape_is_the_smallest_section_any_run_gives():
    cfg = _cfg(domain="time", dt_s={"dist": "uniform", "low": 0.002, "high": 0.004},
               trace_spacing_m=[10.0, 25.0, 12.5])
    shapes = [section_shape(config_of_run(cfg, k)) for k in range(60)]
    h, w = sample_shape(cfg)
    assert all(s[0] >= h and s[1] >= w for s in shapes)  # every run crops, none pads
    # the corners: dt 4 ms, 25 m traces (1000 m / 25 m = 40 traces)
    fixed = _cfg(domain="time", dt_s=0.004, trace_spacing_m=25.0)
    assert (h, w) == section_shape(fixed) and w == 40


def test_crop_keeps_the_top_rows_and_the_middle_traces():
    a = np.arange(2 * 7 * 9).reshape(2, 7, 9)
    out = crop_to(a, (4, 5))
    assert out.shape == (2, 4, 5)
    for s in range(2):  # a slow reference: rows 0..3, columns (9 - 5) // 2 = 2 .. 6
        for i in range(4):
            for j in range(5):
                assert out[s, i, j] == a[s, i, j + 2]
    np.testing.assert_array_equal(crop_to(a, (7, 9)), a)
    with pytest.raises(ValueError, match="cannot be cropped"):
        crop_to(a, (8, 9))


def test_each_sample_is_its_run_rendered_at_its_own_sampling_then_cropped(tmp_path):
    """The store against an independent path: every run rendered by a config with its drawn
    dt_s and trace spacing given as fixed values, then cropped by hand."""
    import demseis

    path = generate_tiny(tmp_path, VARIED, "varied")
    cfg = load_config(tmp_path / "varied.toml", preset="tiny")
    owns = _each_sample_is_its_run_alone_then_cropped(path, cfg)
    assert {own.output.dt_s for own in owns} == {0.002, 0.004}
    assert demseis.open(path).attrs["grid"]["sampling"]["dt_s"] == [0.002, 0.004]


def _each_sample_is_its_run_alone_then_cropped(path, cfg):
    """Every run of the store at ``path`` rendered by ``cfg`` with the run's drawn sampling
    given as fixed values, then cropped by hand, is what the store holds; the table records
    each sample's sampling. Returns each run's config."""
    import demseis
    from demseis.datasets import open_store
    from demseis.generator.config.settings import SAMPLING_KEYS
    from demseis.generator.sweep.pipeline import run_shard

    store = demseis.open(path)
    h, w = sample_shape(cfg)
    assert store.layout.shape == (h, w) and store.attrs["grid"]["nt"] == h
    g = open_store(path)
    seis, fault = np.asarray(g["seismic"][:]), np.asarray(g["fault"][:])
    params = store.params
    S = cfg.samples_per_run
    owns = []
    for run in range(cfg.sweep.n_runs):
        own = config_of_run(cfg, run)
        fixed = dict(cfg.to_dict())
        fixed["output"] = {**fixed["output"],
                           **{k: getattr(own.output, k) for k in SAMPLING_KEYS}}
        alone = parse_config(fixed)
        assert alone.sampling == {}
        data = run_shard(alone, run)
        H, W = data.arrays["seismic"].shape[1:]
        assert H >= h and W >= w
        left = (W - w) // 2
        rows = slice(run * S, (run + 1) * S)
        np.testing.assert_array_equal(seis[rows], data.arrays["seismic"][:, :h, left:left + w])
        np.testing.assert_array_equal(fault[rows], data.arrays["fault"][:, :h, left:left + w])
        dt = own.output.dt_s if own.output.domain == "time" else 0.0
        np.testing.assert_allclose(params["dt_s"][rows], dt, rtol=1e-6)
        np.testing.assert_allclose(params["trace_spacing_m"][rows], trace_spacing(own),
                                   rtol=1e-6)
        owns.append(own)
    return owns


MIXED = """
[sweep]
n_runs = 4
[model]
engine = "kinematic"
[output]
domain = ["depth", "time"]
dt_s = 0.004
"""


def test_a_store_of_depth_and_time_sections(tmp_path):
    """``domain`` as a list: runs alternate depth and time sections, each cut to the store's
    one shape (the fewer rows of the two), its dt_s 0 in the table where it is a depth
    section; the store validates, the xarray rows are plain rows, a SEG-Y export writes each
    sample's own axis."""
    import segyio

    from demseis.datasets import to_xarray, validate_store
    from demseis.datasets.read import export_segy
    from demseis.generator.sweep.driver import domain_text

    path = generate_tiny(tmp_path, MIXED, "mixed")
    cfg = load_config(tmp_path / "mixed.toml", preset="tiny")
    assert cfg.sampling == {"domain": GridSpec(("depth", "time"))}
    depth, time = (section_shape(parse_config({**cfg.to_dict(), "output": {
        **cfg.to_dict()["output"], "domain": d}})) for d in ("depth", "time"))
    assert sample_shape(cfg) == (min(depth[0], time[0]), min(depth[1], time[1]))
    owns = _each_sample_is_its_run_alone_then_cropped(path, cfg)
    assert [own.output.domain for own in owns] == ["depth", "time", "depth", "time"]
    assert validate_store(path).ok
    assert "row" in to_xarray(path).dims
    S = cfg.samples_per_run
    for run, own in enumerate(owns[:2]):
        out = export_segy(path, run * S, tmp_path / f"r{run}.sgy")
        with segyio.open(out, ignore_geometry=True) as f:
            step = segyio.tools.dt(f) / 1e6
        # a time section's dt in microseconds; a depth section's cell in millimetres
        want = 0.004 if own.output.domain == "time" else cfg.grid.cell_m / 1000.0
        assert math.isclose(step, want), (own.output.domain, step)
    assert domain_text(cfg) == "depth or time domain per run"      # generate --dry-run says it


def test_a_sample_exported_to_segy_carries_its_own_sampling(tmp_path):
    import segyio

    from demseis.datasets.read import export_segy

    path = generate_tiny(tmp_path, VARIED, "varied")
    for sample, dt in ((0, 0.002), (6, 0.004)):  # runs 0 and 1
        out = export_segy(path, sample, tmp_path / f"s{sample}.sgy")
        with segyio.open(out, ignore_geometry=True) as f:
            assert math.isclose(segyio.tools.dt(f) / 1e6, dt)


def test_realism_and_plot_of_a_store_whose_sampling_varies(tmp_path):
    """The cropped sections do not span the model: no throw in samples from their rows; the
    pixel unit says each run has its own dt; a plot draws it."""
    from demseis.evaluation.realism_report import store_measures
    from demseis.plotting import plot_sample

    path = generate_tiny(tmp_path, VARIED, "varied")
    got = store_measures(path)
    assert got["pixels"] == "time samples (each run its own dt_s)"
    assert got["measures"]["throw_samples"] is None and got["measures"]["throw_m"] is not None
    assert plot_sample(path, 7, tmp_path / "p.png").stat().st_size > 0
