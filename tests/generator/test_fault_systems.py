"""Fault-system sweep parameters: the variety preset's draws and the per-sample fault records."""

from __future__ import annotations

from collections import Counter

import numpy as np
import pytest

from demseis.dem import NormalFault
from demseis.generator.config.layout import param_codes, param_dtypes
from demseis.generator.config.sampling import plan_run
from demseis.generator.config.settings import load_config, parse_config
from demseis.generator.engines import get_engine
from demseis.generator.engines.runsetup import fault_system_of, run_info
from demseis.generator.render.section import render_run
from demseis.parameters import PARAMS


def test_new_parameters_are_declared_once_with_range_and_doc():
    p = PARAMS
    for name in ("structure", "n_faults", "fault_kind", "fault_spacing_frac",
                 "listric_radius_m", "strength_contrast"):
        assert p[name].doc
        assert p[name].choices or (p[name].lo is not None and p[name].hi is not None)
    assert "brittle" in p["contact_model"].choices
    assert param_codes()["structure"] == p["structure"].choices


def test_default_is_one_normal_fault_as_a_NormalFault():
    cfg = load_config(preset="quick")
    f = fault_system_of(cfg, plan_run(cfg, 0).params, 0)
    assert isinstance(f, NormalFault)


def test_variety_draws_every_structure_kind_and_count():
    cfg = load_config(preset="variety")
    structures, kinds, counts = Counter(), Counter(), Counter()
    for run in range(cfg.sweep.n_runs):
        system = run_info(cfg, plan_run(cfg, run).params, run).system
        structures[system.structure] += 1
        counts[len(system.faults)] += 1
        kinds.update(f.kind for f in system.faults)
    assert set(structures) == {"single", "domino", "graben", "horst", "half_graben"}
    assert set(kinds) == {"normal", "reverse", "listric"}
    assert set(counts) == {1, 2, 3, 4, 5}


def test_samples_record_their_basement_faults():
    raw = {"name": "g", "sweep": {"n_runs": 1, "structure": "graben", "dip_deg": 60,
                                  "throw_m": 60, "fault_spacing_frac": 0.35, "n_layers": 6,
                                  "freq_hz": 30, "strength_contrast": 4.0,
                                  "contact_model": "brittle"},
           "model": {"width_m": 1000.0, "height_m": 450.0, "n_snapshots": 3}}
    cfg = parse_config(raw)
    spec = plan_run(cfg, 0)
    engine = get_engine("dem")
    data = render_run(cfg, engine.simulate(cfg, spec), engine)
    p = data.params
    assert set(p) == set(param_dtypes(cfg))
    assert np.all(p["n_basement_faults"] == 2)
    kinds = param_codes()["fault_kind"]
    assert np.all(p["fault0_kind"] == kinds.index("normal"))
    assert np.all(p["fault2_kind"] == -1) and np.all(p["fault2_x_m"] == -1)
    assert not any(np.isnan(v).any() for v in p.values() if v.dtype.kind == "f")
    dirs = param_codes()["dip_direction"]
    assert p["fault0_dip_direction"][0] == dirs.index("right")
    assert p["fault1_dip_direction"][0] == dirs.index("left")
    assert p["fault1_x_m"][0] - p["fault0_x_m"][0] == pytest.approx(350.0, abs=0.01)
    snap = p["snapshot"]
    for k in (0, 1):  # throw so far grows with the snapshot to the target
        np.testing.assert_allclose(p[f"fault{k}_throw_m"], 60.0 * snap / 2, atol=1e-3)
        assert np.all(p[f"fault{k}_throw_target_m"] == 60.0)


def test_fault_distribution_counts_runs(tmp_path):
    from demseis.datasets import create_store, write_shard
    from demseis.generator.sweep.faultinfo import fault_distribution

    # 3 runs of 2 samples; the third is not done (never written)
    cols = {"sample_in_run": [0, 1, 0, 1, 0, 1], "n_basement_faults": [2, 2, 1, 1, 0, 0],
            "structure": [2, 2, 4, 4, 0, 0],
            "fault0_kind": [0, 0, 2, 2, 0, 0], "fault1_kind": [0, 0, -1, -1, 0, 0]}
    path = tmp_path / "s.zarr"
    create_store(path, n_shards=3, samples_per_shard=2, shape=(4, 4), arrays=["fault"],
                 params={name: "int8" for name in cols})
    for k in range(2):
        write_shard(path, k, {"fault": np.zeros((2, 4, 4), np.uint8)},
                    {name: np.array(v[2 * k: 2 * k + 2], np.int8) for name, v in cols.items()})
    lines = fault_distribution(tmp_path / "s.zarr")
    assert lines[0] == "basement faults over 2 runs:"
    assert "graben: 1" in lines[1] and "half_graben: 1" in lines[1] and "single" not in lines[1]
    assert lines[2].split(None, 1)[1] == "1: 1, 2: 1"
    assert "listric: 1, normal: 2 (3 faults)" in lines[3]
    # a run without basement fault (structure "none") counts as a run with 0 faults
    none = param_codes()["structure"].index("none")
    write_shard(path, 2, {"fault": np.zeros((2, 4, 4), np.uint8)},
                {name: np.array([none, none] if name == "structure" else
                                [0, 1] if name == "sample_in_run" else [0, 0] if
                                name == "n_basement_faults" else [-1, -1], np.int8)
                 for name in cols})
    lines = fault_distribution(tmp_path / "s.zarr")
    assert lines[0] == "basement faults over 3 runs:"
    assert "none: 1" in lines[1] and lines[2].split(None, 1)[1] == "0: 1, 1: 1, 2: 1"
