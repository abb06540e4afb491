"""The planar engine (FaultSeg recipe): determinism, labels on the drawn fault planes, the
number and dips of the faults, the random reflectivity's statistics and its config errors."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from demseis.errors import ConfigError
from demseis.generator.config.sampling import plan_run
from demseis.generator.config.settings import load_config, parse_config
from demseis.generator.engines.planar import REFLECTIVITY_MAX, planar_model, reflectivity_strata

#: the benchmark's second variant, as the preset's comment gives it
MANY = {"planar_faults": {"dist": "choice", "values": list(range(3, 11))},
        "planar_dip_min_deg": 50, "planar_dip_max_deg": 86}


def planar_raw(n_runs: int = 4, **sweep) -> dict:
    """The planar preset as a config dict, ``sweep`` keys replaced (how a benchmark gives it
    to ``demseis.generate``)."""
    raw = load_config(preset="planar").to_dict()
    raw["sweep"].update({"n_runs": n_runs, **sweep})
    return raw


def one_fault_cfg(**sweep):
    """The planar preset with one fault per run and its largest throws (clear offsets)."""
    return parse_config(planar_raw(planar_faults=1, planar_throw_min_m=60,
                                   planar_throw_max_m=80, **sweep))


def test_same_config_same_bytes():
    from demseis.generator.sweep.pipeline import run_shard

    cfg = parse_config(planar_raw())
    a, b = run_shard(cfg, 1), run_shard(cfg, 1)
    for name in a.arrays:
        assert a.arrays[name].tobytes() == b.arrays[name].tobytes(), name
    for name in a.params:
        assert a.params[name].tobytes() == b.params[name].tobytes(), name
    assert a.snapshots == []
    other = run_shard(cfg, 2)
    assert other.arrays["seismic"].tobytes() != a.arrays["seismic"].tobytes()


def _pixel_scale(cfg, run: int) -> tuple[float, float]:
    """(metres per trace, metres of depth per time sample) of run ``run``: the planar engine's
    Vp is constant, so a time sample is vp dt / 2 of depth everywhere."""
    p = plan_run(cfg, run).params
    strata = reflectivity_strata(cfg, p, run, planar_model(cfg, p, run))
    vp = np.unique(strata.vp_m_s)
    assert vp.size == 1
    return float(cfg.output.trace_spacing_m), float(vp[0]) * cfg.output.dt_s / 2.0


def _final_samples(cfg):
    """(run, final-snapshot sample arrays) of every run of ``cfg``, rendered in-process."""
    from demseis.generator.sweep.pipeline import run_shard

    last = cfg.model.n_snapshots - 1
    for run in range(cfg.sweep.n_runs):
        shard = run_shard(cfg, run)
        i = int(np.flatnonzero(shard.params["snapshot"] == last)[0])
        yield run, {k: v[i] for k, v in shard.arrays.items()}, shard


def test_labels_lie_on_the_drawn_fault_planes_with_the_drawn_dips():
    """One fault per run: the expected trace in pixel space is computed here from the drawn
    fault (x at the base, dip, direction) and the constant Vp, independently of the engine's
    map; every label pixel lies within 1 px of it, the labels cover most rows, and the dip of
    a line fitted to the label pixels, taken back through the vertical exaggeration, is the
    drawn dip."""
    cfg = one_fault_cfg()
    H = cfg.model.height_m
    seen = set()
    for run, arrays, _ in _final_samples(cfg):
        fault = next(iter(planar_model(cfg, plan_run(cfg, run).params, run).faults))
        seen.add((fault.direction, fault.reverse))
        dx, dz = _pixel_scale(cfg, run)
        rows, cols = np.nonzero(arrays["fault"])
        assert rows.size > 0
        # expected: x(z) = x_base - direction (H - z) / tan(dip); pixel (row i, column j) is
        # at depth i dz and x (j + 0.5) dx, so column(i) = a + b i
        cot = 1.0 / math.tan(math.radians(fault.dip_deg))
        a = (fault.x_m - fault.direction * H * cot) / dx - 0.5
        b = fault.direction * dz * cot / dx
        dist = np.abs(cols - a - b * rows) / math.hypot(1.0, b)
        assert dist.max() <= 1.0, (run, dist.max())
        n_rows = arrays["fault"].shape[0]
        assert np.unique(rows).size >= 0.8 * n_rows
        # the label's dip: fit column = a' + b' row, dip = atan(dz / (|b'| dx))
        b_fit = np.polyfit(rows, cols, 1)[0]
        dip_fit = math.degrees(math.atan2(dz, abs(b_fit) * dx))
        assert dip_fit == pytest.approx(fault.dip_deg, abs=2.0), run
        assert np.sign(b_fit) == fault.direction
        # and the per-pixel dip, slip and sense labels are the drawn fault's
        on = arrays["fault"] > 0
        np.testing.assert_allclose(arrays["dip_deg"][on], fault.dip_deg, atol=0.01)
        np.testing.assert_allclose(arrays["slip_m"][on] * math.sin(math.radians(fault.dip_deg)),
                                   fault.throw_m, rtol=1e-4)
        assert set(np.unique(arrays["sense"][on])) == {2 if fault.reverse else 1}
    assert len(seen) >= 2  # both dip directions or both senses among the runs


def test_snapshot_zero_is_unfaulted_and_throws_grow():
    from demseis.generator.sweep.pipeline import run_shard

    cfg = parse_config(planar_raw())
    shard = run_shard(cfg, 0)
    snap = shard.params["snapshot"]
    assert not shard.arrays["fault"][snap == 0].any()
    assert shard.params["throw_m"][snap == 0].max() == 0.0
    assert shard.arrays["fault"][snap == snap.max()].any()
    throws = [float(shard.params["throw_m"][snap == k][0]) for k in range(snap.max() + 1)]
    np.testing.assert_allclose(np.diff(throws), throws[-1] / (len(throws) - 1), rtol=1e-5)
    assert np.all(shard.arrays["strain"] == 0)


@pytest.mark.parametrize("sweep, n_range, dip_range", [
    ({}, (1, 3), (40.0, 80.0)),
    (MANY, (3, 10), (50.0, 86.0)),
])
def test_number_and_dips_of_faults_in_range(sweep, n_range, dip_range):
    cfg = parse_config(planar_raw(n_runs=40, **sweep))
    counts = []
    for run in range(cfg.sweep.n_runs):
        p = plan_run(cfg, run).params
        faults = planar_model(cfg, p, run).faults
        counts.append(len(faults))
        dips = [f.dip_deg for f in faults]
        assert dip_range[0] <= min(dips) and max(dips) <= dip_range[1]
        throws = [f.throw_m for f in faults]
        assert 20.0 <= min(throws) and max(throws) <= 80.0
    assert min(counts) == n_range[0] and max(counts) == n_range[1]


def test_many_faults_variant_through_generate(tmp_path):
    """The 3-10 faults at 50-86 degrees variant as a config dict through demseis.generate:
    every sample records its faults, and the final snapshots are labelled with several."""
    import demseis

    store = demseis.generate(planar_raw(n_runs=2, **MANY), out=tmp_path / "many.zarr",
                             workers=0)
    assert not store.run_summary.failed
    p = store.params
    assert np.all((p["n_basement_faults"] >= 3) & (p["n_basement_faults"] <= 10))
    dips = p["fault0_dip_deg"]
    assert np.all((dips >= 50) & (dips <= 86))
    last = p["snapshot"] == p["snapshot"].max()
    assert np.all(p["n_faults"][last] >= 2)


def test_random_reflectivity_statistics():
    """The reflection coefficients of the series, computed from the beds' impedances as the
    imaging does, are independent and uniform in +-REFLECTIVITY_MAX: mean 0, standard
    deviation R / sqrt(3), kurtosis 1.8 (a Gaussian's is 3), no lag-one correlation, no value
    much beyond R; the density stays near the rock's."""
    cfg = parse_config(planar_raw())
    R = REFLECTIVITY_MAX
    for run in range(3):
        p = plan_run(cfg, run).params
        strata = reflectivity_strata(cfg, p, run, planar_model(cfg, p, run))
        np.testing.assert_allclose((strata.bed_top_m - strata.bed_bottom_m)[:-1], 2.0)  # the top
        # bed takes what is left
        z = strata.vp_m_s * strata.rho_kg_m3
        r = np.diff(z) / (z[1:] + z[:-1])
        n = r.size
        assert n > 500
        assert abs(r.mean()) < 3.0 * R / math.sqrt(3.0 * n)
        assert r.std() == pytest.approx(R / math.sqrt(3.0), rel=0.08)
        kurtosis = np.mean((r - r.mean()) ** 4) / r.var() ** 2
        assert 1.6 < kurtosis < 2.2
        assert abs(np.corrcoef(r[:-1], r[1:])[0, 1]) < 0.12
        assert np.abs(r).max() < 1.2 * R
        assert strata.rho_kg_m3.max() / strata.rho_kg_m3.min() < 2.0


def test_reflectivity_reaches_every_point_of_the_section():
    """The series covers every flat depth the folds, shear and faults bring into the model:
    no point of the section reads past the ends of the series (where it would have no
    reflections)."""
    cfg = parse_config(planar_raw(n_runs=8, **MANY, planar_tilt_deg=10.0))
    H, W = cfg.model.height_m, cfg.model.width_m
    X, D = np.meshgrid(np.linspace(0, W, 200), np.linspace(0, H, 100))
    for run in range(cfg.sweep.n_runs):
        p = plan_run(cfg, run).params
        model = planar_model(cfg, p, run)
        strata = reflectivity_strata(cfg, p, run, model)
        _, depth0 = model.unfault(1.0, X, D)
        y0 = H - depth0
        assert strata.bed_bottom_m[1] < y0.min() and y0.max() < strata.bed_top_m[-2]


@pytest.mark.parametrize("sweep, names", [
    ({"planar_dip_min_deg": 70, "planar_dip_max_deg": 60},
     ("sweep.planar_dip_min_deg", "sweep.planar_dip_max_deg")),
    ({"planar_throw_min_m": 50, "planar_throw_max_m": 30},
     ("sweep.planar_throw_min_m", "sweep.planar_throw_max_m")),
    ({"planar_dip_max_deg": 95}, ("sweep.planar_dip_max_deg = 95", "[10, 89]")),
    ({"planar_faults": 30}, ("sweep.planar_faults = 30", "[0, 20]")),
    ({"planar_reverse_fraction": 1.5}, ("sweep.planar_reverse_fraction",)),
    ({"planar_throw_max_m": 700}, ("sweep.planar_throw_max_m", "0.6 * height_m")),
    ({"fold_amplitude_m": 400}, ("sweep.fold_amplitude_m", "overturn")),
])
def test_config_errors_name_the_key(sweep, names):
    with pytest.raises(ConfigError) as err:
        parse_config(planar_raw(**sweep))
    for name in names:
        assert name in str(err.value)


def test_engine_checks_only_planar_configs():
    """The planar keys' rules are the planar engine's: the kinematic engine ignores them."""
    raw = planar_raw(fold_amplitude_m=400)
    raw["model"]["engine"] = "kinematic"
    assert parse_config(raw).model.engine == "kinematic"


def test_elements_rendering_images_the_same_series():
    """``rendering = "elements"``: the property grids are the series at the cell centres
    (constant Vp, density varying down a column)."""
    from demseis.generator.engines import get_engine

    cfg = parse_config(planar_raw())
    cfg = dataclasses.replace(cfg, output=dataclasses.replace(cfg.output, rendering="elements"))
    engine = get_engine("planar")
    run = engine.simulate(cfg, plan_run(cfg, 0))
    state = next(engine.states(cfg, run, [cfg.model.n_snapshots - 1]))
    assert np.unique(state.vp_m_s).size == 1
    assert np.all(np.std(state.rho_kg_m3, axis=0) > 0)
