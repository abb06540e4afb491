"""The kinematic engine: geometry against closed forms, and its store through the shared tools."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import quad

from demseis.errors import InputError
from demseis.generator.config.layout import grid_of
from demseis.generator.config.sampling import plan_run
from demseis.generator.engines.kinematic import fault_geometry, kinematic_state
from demseis.generator.engines.runsetup import run_info
from tests.generator._helpers import kinematic_cfg


@pytest.fixture(scope="module")
def kin_store(tmp_path_factory) -> Path:
    import demseis

    out = tmp_path_factory.mktemp("kin") / "k.zarr"
    store = demseis.generate(kinematic_cfg(), out=out, workers=0)
    assert not store.run_summary.failed
    return out


def test_planar_fault_is_the_line_through_its_base_point():
    d = np.linspace(-500.0, 1500.0, 401)
    for s in (1, -1):
        x, dip = fault_geometry(d, 600.0, 60.0, 400.0, s, None)
        np.testing.assert_allclose(x, 600.0 - s * (400.0 - d) / np.tan(np.radians(60.0)),
                                   atol=1e-9)
        assert np.all(dip == 60.0)


def test_listric_fault_against_quadrature():
    """x(d) = x_base - integral_d^H cot(dip) with cos dip = cos dip0 + d / R (scipy quad)."""
    R, H, dip0 = 3000.0, 1000.0, 70.0
    d = np.linspace(0.0, 1500.0, 3001)
    x, dip = fault_geometry(d, 500.0, dip0, H, 1, R)

    def cot(z):
        c = min(np.cos(np.radians(dip0)) + z / R, np.cos(np.radians(10.0)))
        return c / np.sqrt(1 - c * c)

    assert dip[0] == pytest.approx(dip0)
    assert np.all(np.diff(dip) <= 0)  # flattens with depth
    for z in (0.0, 300.0, 1000.0, 1400.0):
        ref = 500.0 - quad(cot, z, H)[0] if z <= H else 500.0 + quad(cot, H, z)[0]
        assert np.interp(z, d, x) == pytest.approx(ref, abs=0.05)


def test_hanging_wall_is_the_footwall_shifted_by_the_throw():
    """One planar normal fault, constant throw, no folds: far from the fault, the hanging
    wall's layer column is the footwall's shifted down by the throw (in cells)."""
    cfg = kinematic_cfg()
    spec = plan_run(cfg, 0)
    p = spec.params.replace(throw_taper=0.0, fold_amplitude_m=0.0, throw_m=100.0,
                            dip_direction="right", fault_x_frac=0.6, dip_deg=60.0)
    info = run_info(cfg, p, 0)
    layer, maps = kinematic_state(cfg, p, 0, info, 1.0)
    grid = grid_of(cfg)
    shift = int(round(100.0 / grid.cell_m))
    foot, hang = layer[:, 0], layer[:, -1]
    np.testing.assert_array_equal(hang[shift:], foot[:-shift])
    assert not np.array_equal(hang, foot)
    # the mask is one trace, labelled fault 1, slip = throw / sin(dip), sense normal
    on = maps["fault"] == 1
    assert on.any(axis=1).mean() > 0.9
    assert set(np.unique(maps["fault_id"][on])) == {1}
    np.testing.assert_allclose(maps["slip_m"][on], 100.0 / np.sin(np.radians(60.0)), rtol=1e-5)
    np.testing.assert_allclose(maps["dip_deg"][on], 60.0)
    assert np.all(maps["sense"][on] == 1)
    assert np.all(maps["damage"][on] == 2) and (maps["damage"] == 1).any()
    # the reference state holds no fault
    _, m0 = kinematic_state(cfg, p, 0, info, 0.0)
    assert not m0["fault"].any()


def test_throw_taper_kills_the_throw_at_the_tips():
    cfg = kinematic_cfg()
    spec = plan_run(cfg, 0)
    p = spec.params.replace(throw_taper=1.0, fold_amplitude_m=0.0)
    layer, maps = kinematic_state(cfg, p, 0, run_info(cfg, p, 0), 1.0)
    slip = maps["slip_m"][maps["fault"] == 1]
    assert slip.min() < 0.5 * slip.max()


def test_store_passes_validate_dataset_and_score(kin_store):
    import demseis
    from demseis.datasets import FaultSegDataset
    from demseis.datasets.validate import validate_store

    store = demseis.open(kin_store)
    assert store.config["model"]["engine"] == "kinematic"
    report = validate_store(kin_store)
    assert report.ok, report
    ds = FaultSegDataset(kin_store)
    x, y = ds[0][:2] if isinstance(ds[0], tuple) else (ds[0]["seismic"], ds[0]["fault"])
    assert x.shape[-2:] == y.shape[-2:]
    params = store.params
    assert params["has_fault"].sum() > 0 and params["max_slip_m"].max() > 0
    labels = np.stack([store.sample(i)["fault"] for i in range(len(store))]).astype(np.float32)
    perfect = demseis.score(labels, store)
    assert perfect.overall.f1 == pytest.approx(1.0)
    blank = demseis.score(np.zeros_like(labels), store)
    assert blank.overall.recall == 0.0


def test_same_config_same_bytes(tmp_path):
    from demseis.generator.sweep.pipeline import run_shard

    cfg = kinematic_cfg()
    a, b = run_shard(cfg, 1), run_shard(cfg, 1)
    for name in a.arrays:
        assert a.arrays[name].tobytes() == b.arrays[name].tobytes(), name
    assert a.snapshots == []


def test_particle_commands_refuse_a_kinematic_store(kin_store, tmp_path):
    from demseis.generator.sweep.rerender import relabel, rerender
    from demseis.plotting import preview

    with pytest.raises(InputError, match="kinematic"):
        preview(str(kin_store), tmp_path / "p")
    with pytest.raises(InputError, match="kinematic"):
        rerender(kin_store, tmp_path / "r.zarr", freqs_hz=[20.0], snrs_db=[np.inf])
    with pytest.raises(InputError, match="kinematic"):
        relabel(kin_store, tmp_path / "l.zarr", labels={"thickness_cells": 2.0})


def _population_cfg(stretch: float, n: int = 12):
    from demseis.generator.config.settings import load_config, parse_config

    raw = load_config(preset="quick").to_dict()
    raw["sweep"].update(base_stretch=stretch, population_faults=n, n_runs=2)
    raw["model"]["engine"] = "kinematic"
    return parse_config(raw)


@pytest.mark.parametrize("stretch", [0.08, -0.05])
def test_population_takes_up_the_stretch(stretch):
    from demseis.generator.engines.kinematic import population

    cfg = _population_cfg(stretch, n=15)
    for run in range(2):
        params = plan_run(cfg, run).params
        faults = population(cfg, params, run)
        assert len(faults) == 15
        heave = sum(f.throw_m / np.tan(np.radians(f.dip_deg)) for f in faults)
        np.testing.assert_allclose(heave, abs(stretch) * cfg.model.width_m, rtol=1e-9)
        assert {f.kind for f in faults} == {"normal" if stretch > 0 else "reverse"}
        throws = np.array([f.throw_m for f in faults])
        assert throws.max() <= 50.0 * throws.min() * (1 + 1e-9)       # the power law's cap
        assert all(15.0 <= f.dip_deg <= 80.0 and f.taper == 1.0 for f in faults)
    assert population(_population_cfg(0.0), plan_run(_population_cfg(0.0), 0).params, 0) == []


def test_population_throws_follow_the_power_law():
    """Cumulative N(> t) ~ t^-c: the maximum-likelihood (Hill) exponent of many faults."""
    from demseis.generator.engines.kinematic import population

    cfg = _population_cfg(0.1, n=100)
    throws = np.concatenate([[f.throw_m for f in population(cfg, plan_run(cfg, r).params, r)]
                             for r in range(2)])
    t = np.sort(throws)[: int(0.9 * throws.size)]          # below the cap
    c_hat = 1.0 / np.mean(np.log(t / t.min()))
    assert 0.75 < c_hat < 1.35, c_hat                        # population_throw_exponent = 1


def test_a_stretched_section_has_many_labelled_faults():
    cfg = _population_cfg(0.1, n=12)
    spec = plan_run(cfg, 0)
    info = run_info(cfg, spec.params, 0)
    _, none = kinematic_state(cfg, spec.params, 0, info, 0.0)
    _, maps = kinematic_state(cfg, spec.params, 0, info, 1.0)
    assert not none["fault"].any()
    assert len(np.unique(maps["fault_id"][maps["fault"] > 0])) >= 8   # 12 + 1 less tips/overlaps
    # without a stretch the same run has its one basement fault
    plain = _population_cfg(0.0)
    _, one = kinematic_state(plain, plan_run(plain, 0).params, 0, info, 1.0)
    assert len(np.unique(one["fault_id"][one["fault"] > 0])) == 1
