"""Configs that cannot make a quasi-static fault are refused at load, with the reason."""

from __future__ import annotations

import math

import numpy as np
import pytest

from demseis.errors import ConfigError
from demseis.generator.config.params import spec_values_hint
from demseis.generator.config.settings import load_config, parse_config
from demseis.generator.engines.physics import MAX_WALL_MACH, check_physics, p_wave_speed_m_s
from tests.generator._helpers import generate_tiny


@pytest.mark.parametrize("preset", ["tiny", "quick", "seed", "field"])
def test_presets_pass(preset):
    """The shipped presets load (the physics rules run at load) and pass the rules again when
    checked directly."""
    cfg = load_config(preset=preset)
    assert cfg.name == preset
    assert check_physics(cfg) is None


def test_examples_pass():
    cfg = load_config("examples/readme.toml")
    assert check_physics(cfg) is None and cfg.sweep.n_runs >= 1


@pytest.mark.parametrize("raw, words", [
    ({"model": {"wall_speed_m_s": 100.0}}, ["wall_speed_m_s", "quasi-static", "p-wave"]),
    # the strongest declared damping with a 15 m/s wall: the smallest element sinks at
    # 8.7 m/s, below the basement's 10.6 m/s at 45 deg (the paper's damping 3e9 did the same
    # at 5 m/s: the hanging wall detached, docs/dem.md)
    ({"sweep": {"damping_scale": 5.0e8}, "model": {"wall_speed_m_s": 15.0}},
     ["damping_scale", "detaches"]),
    # 1 m of throw at 5 m/s is over before the heaviest element's energy has relaxed
    ({"sweep": {"throw_m": 1.0, "dip_deg": 45.0}}, ["damping_scale", "dynamic", "throw"]),
    # without a basement fault a run lasts its base stretch: 0.001 x 2500 m at 5 m/s is 0.5 s
    ({"sweep": {"structure": "none", "base_stretch": 0.001}},
     ["damping_scale", "dynamic", "base stretch"]),
])
def test_degenerate_physics_refused(raw, words):
    with pytest.raises(ConfigError) as exc:
        parse_config(raw)
    msg = str(exc.value)
    for w in words:
        assert w in msg, msg


@pytest.mark.parametrize("raw, key", [
    # no overburden, no dissipation, no shear strength: excluded by the declared ranges
    ({"sweep": {"gravity_m_s2": 0.0}}, "sweep.gravity_m_s2"),
    ({"sweep": {"damping_scale": 0.0}}, "sweep.damping_scale"),
    ({"sweep": {"friction": 0.0, "cohesion_n": 0.0}}, "sweep.friction"),
    ({"sweep": {"friction": {"dist": "uniform", "low": 0.0, "high": 0.5}}}, "sweep.friction"),
    ({"sweep": {"damping_scale": 3.0e9}}, "sweep.damping_scale"),
])
def test_degenerate_mechanics_refused_by_the_range(raw, key):
    with pytest.raises(ConfigError, match=key + r".* is not allowed: expected a number in \["):
        parse_config(raw)


def test_weakest_declared_material_is_accepted():
    """Cohesion 0 with the lowest declared friction (0.2; a frictionless, cohesionless pack
    flows like a fluid, docs/dem.md) is accepted."""
    cfg = parse_config({"sweep": {"cohesion_n": 0.0, "friction": 0.2}})
    assert spec_values_hint(cfg.sweep.params["cohesion_n"]) == (0.0, 0.0)
    assert spec_values_hint(cfg.sweep.params["friction"]) == (0.2, 0.2)


def test_wall_speed_bound_is_the_p_wave_fraction():
    c = p_wave_speed_m_s(1.0e10, 2500.0)
    assert c == pytest.approx(2 * math.sqrt(1e10 / (math.pi * 2500)))
    # independent check: a chain of disks of radius r, spacing 2r, spring Kn: c = 2r sqrt(Kn/m)
    r = 17.0
    assert c == pytest.approx(2 * r * math.sqrt(1e10 / (2500 * math.pi * r * r)))
    v_max = MAX_WALL_MACH * c
    damp = {"dip_deg": 30.0}  # so that the hanging wall can follow this fast a base
    parse_config({"model": {"wall_speed_m_s": 0.99 * v_max}, "sweep": damp})
    with pytest.raises(ConfigError, match="quasi-static"):
        parse_config({"model": {"wall_speed_m_s": 1.01 * v_max}, "sweep": damp})


def test_run_without_fault_is_recorded(tmp_path, capsys):
    """A run whose last snapshot has no fault pixel is named in the sweep summary."""
    # 4 m of throw (slowly, to stay quasi-static) is below the labels' minimum slip: no fault
    out = generate_tiny(tmp_path, "[sweep]\nn_runs = 1\nthrow_m = 4.0\ndip_deg = 60\n"
                        "[model]\nwall_speed_m_s = 0.4\n", "nf")
    text = capsys.readouterr().out
    assert "1 run(s) ended with no fault" in text and ": 0" in text
    import zarr

    assert not np.any(zarr.open_group(str(out), mode="r")["fault"][:])


def test_a_long_stretch_makes_a_short_throw_quasi_static():
    """A run lasts the longer of its slip and its base stretch: 1 m of throw passes with a
    0.1 stretch, and so does a run without basement fault whose stretch lasts long enough."""
    for raw in ({"throw_m": 1.0, "dip_deg": 45.0, "base_stretch": 0.1},
                {"structure": "none", "base_stretch": -0.05},
                {"structure": "none", "base_stretch": [0.1, -0.1]}):
        cfg = parse_config({"sweep": raw})
        assert check_physics(cfg) is None
        lo, hi = spec_values_hint(cfg.sweep.params["base_stretch"])
        assert (lo, hi) == (min(np.ravel(raw["base_stretch"])), max(np.ravel(raw["base_stretch"])))
    # the same 1 m of throw without the long stretch is dynamic
    with pytest.raises(ConfigError, match="dynamic"):
        parse_config({"sweep": {"throw_m": 1.0, "dip_deg": 45.0}})
    with pytest.raises(ConfigError, match="dynamic"):   # a range through 0 draws near-0 runs
        parse_config({"sweep": {"structure": "none",
                                "base_stretch": {"dist": "uniform", "low": -0.1, "high": 0.1}}})
