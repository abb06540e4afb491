"""The stratigraphy of the ``strata`` rendering: beds, lookup, statistics against field targets."""

import dataclasses
import math

import numpy as np
import pytest

from demseis.errors import ConfigError, InputError
from demseis.generator.config.sampling import run_params
from demseis.generator.config.settings import load_config
from demseis.generator.engines.runsetup import bed_model_of
from demseis.seismic import (BedModel, LayerProperties, PropertyModel, draw_layer_properties,
                             draw_strata, strata_properties)
from demseis.seismic.strata import undulation_bound
from demseis_dev.strata_stats import (adjacent_trace_correlation, column_reflectivity,
                                      default_setup, flat_section, zero_crossings)


def _props(n, seed=0):
    return draw_layer_properties(n, PropertyModel(), np.random.default_rng(seed))


def _reference(s, x, y, unit):
    """Slow, obvious lookup: a linear scan of the beds, bed limits interpolated at x."""
    vp = np.empty(x.size)
    rho = np.empty(x.size)
    n_tab = s.lateral.shape[1]
    for i in range(x.size):
        u = int(unit[i])
        if u < 0:
            u = s.n_prekinematic - 1
            for k in range(s.n_prekinematic):
                if y[i] < s.unit_top_m[k]:
                    u = k
                    break
        pos = min(max(x[i] / s.dx_m, 0.0), n_tab - 1.0)
        k = min(int(pos), n_tab - 2)
        w = pos - k

        def at(table, j):
            return table[j, k] * (1.0 - w) + table[j, k + 1] * w

        j = s.unit_first_bed[u]
        for b in range(s.unit_first_bed[u] + 1, s.unit_first_bed[u + 1]):
            if y[i] >= s.bed_bottom_m[b] + at(s.undulation, b):
                j = b
        f = at(s.lateral, j)
        vp[i] = s.vp_m_s[j] * (1.0 + s.lateral_amplitude_vp * f)
        rho[i] = s.rho_kg_m3[j] * (1.0 + s.lateral_amplitude_rho * f)
    return vp, rho


def test_unit_boundaries_are_bed_boundaries_and_beds_tile_units():
    edges = np.array([0.0, 100.0, 130.0, 400.0, 401.0])
    s = draw_strata(edges[:-1], edges[1:], _props(4), 1000.0, BedModel(),
                    np.random.default_rng(1))
    for u in range(4):
        b0, b1 = s.unit_first_bed[u], s.unit_first_bed[u + 1]
        assert b1 > b0
        assert s.bed_bottom_m[b0] == edges[u] and s.bed_top_m[b1 - 1] == edges[u + 1]
        np.testing.assert_array_equal(s.bed_top_m[b0:b1 - 1], s.bed_bottom_m[b0 + 1:b1])
        assert np.all(s.undulation[b0] == 0.0)             # unit boundaries stay flat
        assert np.all(s.bed_top_m[b0:b1] > s.bed_bottom_m[b0:b1])
    # undulating boundaries never cross: each moves less than half of either adjacent bed
    t = s.bed_top_m - s.bed_bottom_m
    inner = np.ones(s.n_beds, bool)
    inner[s.unit_first_bed[:-1]] = False
    half = 0.5 * np.minimum(t, np.roll(t, 1))
    assert np.all(undulation_bound(s)[inner] < half[inner])


def test_bed_thickness_is_the_configured_lognormal():
    m = BedModel(bed_thickness_median_m=3.0, bed_thickness_log_sigma=0.7,
                 bed_thickness_min_m=0.1, bed_thickness_max_m=1000.0)
    s = draw_strata([0.0], [40000.0], _props(1), 500.0, m, np.random.default_rng(2))
    t = (s.bed_top_m - s.bed_bottom_m)[:-1]                 # the top bed is the remainder
    assert t.size > 10000
    assert np.median(t) == pytest.approx(3.0, rel=0.03)
    assert np.std(np.log(t)) == pytest.approx(0.7, rel=0.03)
    c = BedModel(bed_thickness_min_m=1.0, bed_thickness_max_m=10.0)
    s = draw_strata([0.0], [5000.0], _props(1), 500.0, c, np.random.default_rng(3))
    t = s.bed_top_m - s.bed_bottom_m
    assert t.min() >= 1.0 - 1e-9 and t[:-1].max() <= 10.0 + 1e-9   # cumsum rounding


def test_constant_along_a_bed_without_lateral_variation():
    m = BedModel(lateral_amplitude=0.0, boundary_undulation=0.0)
    s = draw_strata([0.0, 50.0], [50.0, 120.0], _props(2), 2000.0, m, np.random.default_rng(4))
    yc = 0.5 * (s.bed_bottom_m + s.bed_top_m)
    x = np.linspace(-100.0, 2100.0, 301)
    vp, rho = strata_properties(s, np.broadcast_to(x, (yc.size, x.size)),
                                np.broadcast_to(yc[:, None], (yc.size, x.size)))
    np.testing.assert_array_equal(vp, np.broadcast_to(s.vp_m_s[:, None], vp.shape))
    np.testing.assert_array_equal(rho, np.broadcast_to(s.rho_kg_m3[:, None], rho.shape))


def test_continuous_along_a_bed_with_lateral_variation():
    m = BedModel(boundary_undulation=0.0)
    s = draw_strata([0.0], [200.0], _props(1), 3000.0, m, np.random.default_rng(5))
    j = int(np.argmax(s.bed_top_m - s.bed_bottom_m))
    x = np.linspace(0.0, 3000.0, 30001)                      # 0.1 m steps
    vp, _ = strata_properties(s, x, np.full(x.size, 0.5 * (s.bed_bottom_m[j] + s.bed_top_m[j])))
    rel = np.abs(np.diff(vp)) / vp[:-1]
    assert np.std(vp) / np.mean(vp) > 0.02                   # it does vary ...
    assert rel.max() < 0.01                                  # ... without jumps


def test_density_variation_along_a_bed_keeps_vp_and_the_draws():
    """lateral_density_amplitude varies density along a bed by that relative std, on the field
    Vp would follow, and leaves Vp (so the travel times) and every draw as they were."""
    base = BedModel(lateral_amplitude=0.0, boundary_undulation=0.0)
    dens = dataclasses.replace(base, lateral_density_amplitude=0.1)
    s0, s1 = (draw_strata([0.0], [400.0], _props(1), 20000.0, m, np.random.default_rng(6))
              for m in (base, dens))
    np.testing.assert_array_equal(s0.lateral, s1.lateral)
    np.testing.assert_array_equal(s0.rho_kg_m3, s1.rho_kg_m3)
    yc = 0.5 * (s1.bed_bottom_m + s1.bed_top_m)
    x = np.linspace(0.0, 20000.0, 2001)
    xx = np.broadcast_to(x, (yc.size, x.size))
    yy = np.broadcast_to(yc[:, None], xx.shape)
    vp0, rho0 = strata_properties(s0, xx, yy)
    vp1, rho1 = strata_properties(s1, xx, yy)
    np.testing.assert_array_equal(vp1, vp0)                  # no time shift
    np.testing.assert_array_equal(rho0, np.broadcast_to(s0.rho_kg_m3[:, None], rho0.shape))
    rel = rho1 / s1.rho_kg_m3[:, None] - 1.0
    x_tab = np.arange(s1.lateral.shape[1]) * s1.dx_m
    f = np.array([np.interp(x, x_tab, row) for row in s1.lateral])
    np.testing.assert_allclose(rel, 0.1 * f, atol=1e-12)
    assert np.std(rel) == pytest.approx(0.1, rel=0.15)       # unit-variance fields


def _two_way_times(model: BedModel, depth_m: float, seed: int) -> np.ndarray:
    """Two-way time (s) from the top of a flat 1200 m pile down to ``depth_m`` below it, at
    traces 25 m apart over 5 km: the sum of 2 dz / Vp over 0.25 m steps."""
    s = draw_strata([0.0], [1200.0], _props(1, seed), 5000.0, model,
                    np.random.default_rng(seed))
    x = np.arange(12.5, 5000.0, 25.0)
    y = 1200.0 - np.arange(0.125, depth_m, 0.25)
    vp, _ = strata_properties(s, np.broadcast_to(x, (y.size, x.size)),
                              np.broadcast_to(y[:, None], (y.size, x.size)))
    return (2.0 * 0.25 / vp).sum(axis=0)


def test_field_preset_beds_put_no_static_jumps_between_traces():
    """The strata defaults shift each trace's two-way time to 600 m depth from its
    neighbour's (seeds 0-2: median 0.6-1.0 ms, 90th percentile 1.6-2.3 ms; up to half a 4 ms
    sample of random offset between traces, which a network trained on DEM runs paints as
    faults: docs/benchmarks.md); the `field` preset's beds, constant along their length,
    shift none."""
    field = bed_model_of(run_params(load_config(preset="field"), 0))    # as a run draws it
    for seed in (0, 1):
        jumps = np.abs(np.diff(_two_way_times(BedModel(), 600.0, seed)))
        assert 0.5e-3 < np.percentile(jumps, 90) < 3e-3, seed
        flat = _two_way_times(field, 600.0, seed)
        assert np.ptp(flat) < 1e-9, seed


def test_kernel_matches_the_slow_reference():
    edges = np.array([0.0, 60.0, 90.0, 200.0])
    props = _props(5)
    rng = np.random.default_rng(6)
    s = draw_strata(list(edges[:-1]) + [150.0, 190.0], list(edges[1:]) + [230.0, 260.0], props,
                    800.0, BedModel(boundary_undulation=0.17), rng, n_prekinematic=3)
    x = rng.uniform(-50.0, 850.0, 4000)
    y = rng.uniform(-20.0, 280.0, 4000)
    unit = rng.integers(-1, 5, 4000)
    # points hugging undulating boundaries, where the walk across them matters
    b = rng.integers(0, s.n_beds, 1000)
    x[:1000] = rng.uniform(0.0, 800.0, 1000)
    y[:1000] = s.bed_bottom_m[b] + rng.uniform(-1.0, 1.0, 1000) * undulation_bound(s)[b]
    unit[:1000] = np.searchsorted(s.unit_first_bed, b, side="right") - 1
    vp, rho = strata_properties(s, x, y, unit)
    rvp, rrho = _reference(s, x, y, unit)
    np.testing.assert_allclose(vp, rvp, rtol=1e-12, atol=0)
    np.testing.assert_allclose(rho, rrho, rtol=1e-12, atol=0)
    vp2, _ = strata_properties(s, x.reshape(40, 100), y.reshape(40, 100))
    np.testing.assert_array_equal(vp2.ravel(), _reference(s, x, y, np.full(x.size, -1))[0])


def test_growth_units_are_looked_up_by_unit():
    props = LayerProperties(lithology=np.zeros(3, np.int16), vp=np.array([2000., 3000., 4500.]),
                            rho=np.array([2100., 2300., 2500.]))
    m = BedModel(facies_contrast=0.0, fluctuation_sigma=0.0, lateral_amplitude=0.0,
                 vp_gradient_per_km=0.0, rho_gradient_per_km=0.0)
    s = draw_strata([0.0, 100.0, 150.0], [100.0, 200.0, 250.0], props, 500.0, m,
                    np.random.default_rng(7), n_prekinematic=2)
    y = np.array([160.0, 160.0, 160.0, -5.0, 300.0])
    vp, rho = strata_properties(s, np.full(5, 10.0), y, np.array([2, -1, 1, -1, -1]))
    np.testing.assert_allclose(vp, [4500.0, 3000.0, 3000.0, 2000.0, 3000.0])
    np.testing.assert_allclose(rho, [2500.0, 2300.0, 2300.0, 2100.0, 2300.0])


def test_same_seed_same_bytes():
    a = default_setup(11)
    b = default_setup(11)
    for f in dataclasses.fields(a):
        va, vb = getattr(a, f.name), getattr(b, f.name)
        if isinstance(va, np.ndarray):
            assert va.tobytes() == vb.tobytes(), f.name
        else:
            assert va == vb, f.name
    assert not np.array_equal(default_setup(12).vp_m_s[:50], a.vp_m_s[:50])


def test_reflectivity_is_heavy_tailed_and_blue():
    """Heavy-tailed in every column; the spectrum rises with frequency (the median slope of
    12 columns: one 1.2 km column is too short a record for a stable slope)."""
    slopes = []
    for seed in range(3):
        for x in (500.0, 1500.0, 2500.0, 3500.0):
            stats = column_reflectivity(default_setup(seed), x_m=x, dz_m=0.25)
            assert stats["kurtosis_depth"] > 0
            assert stats["kurtosis_time"] > 0                # 1 ms two-way-time bins
            slopes.append(stats["spectral_slope"])
    assert np.median(slopes) > 0.1, slopes


@pytest.fixture(scope="module")
def section_35hz():
    return [flat_section(default_setup(seed), 35.0) for seed in range(2)]


def test_adjacent_trace_correlation_below_a_flat_model(section_35hz):
    """Undeformed beds with the default lateral variation: continuous (F3 is 0.92, and
    deformation lowers it further, benchmarks/survey_realism.py) but not perfectly flat."""
    r = [adjacent_trace_correlation(s) for s in section_35hz]
    assert 0.9 < np.mean(r) < 0.99, r
    flat = flat_section(default_setup(0, BedModel(lateral_amplitude=0.0,
                                                   boundary_undulation=0.0)), 35.0)
    assert adjacent_trace_correlation(flat) > 0.999          # a flat-layer model is too smooth


def test_zero_crossings_reported(section_35hz):
    z = [zero_crossings(s) for s in section_35hz]
    print(f"zero crossings per 100 samples at 35 Hz, 4 ms: {z} (F3: 34)")
    assert all(20.0 < v < 45.0 for v in z)


@pytest.mark.parametrize("changes,match", [
    ({"bed_thickness_median_m": 0.01}, r"strata.bed_thickness_median_m = 0.01.*\[0.1, 100.0\]"),
    ({"bed_thickness_log_sigma": -1.0}, r"bed_thickness_log_sigma"),
    ({"bed_thickness_min_m": 5.0}, r"bed_thickness_min_m = 5.0 m exceeds"),
    ({"bed_thickness_max_m": 2.0}, r"bed_thickness_max_m = 2.0 m is below"),
    ({"facies_switch_probability": 1.5}, r"facies_switch_probability"),
    ({"fluctuation_ar1": 1.0}, r"fluctuation_ar1"),
    ({"boundary_undulation": 0.3}, r"boundary_undulation = 0.3.*\[0.0, 0.17\]"),
    ({"lateral_correlation_m": float("nan")}, r"lateral_correlation_m"),
    ({"lateral_amplitude": "0.1"}, r"lateral_amplitude"),
    ({"vp_gradient_per_km": True}, r"vp_gradient_per_km"),
])
def test_invalid_bed_model_names_the_field(changes, match):
    with pytest.raises(ConfigError, match=match):
        draw_strata([0.0], [10.0], _props(1), 100.0, BedModel(**changes),
                    np.random.default_rng(0))


def test_bad_inputs_are_input_errors():
    props = _props(2)
    rng = np.random.default_rng(0)
    with pytest.raises(InputError, match="contiguous"):
        draw_strata([0.0, 60.0], [50.0, 100.0], props, 100.0, BedModel(), rng)
    with pytest.raises(InputError, match="covers 2 layers"):
        draw_strata([0.0, 1.0, 2.0], [1.0, 2.0, 3.0], props, 100.0, BedModel(), rng)
    with pytest.raises(InputError, match="width_m"):
        draw_strata([0.0], [1.0], props, 0.0, BedModel(), rng)
    s = draw_strata([0.0], [10.0], props, 100.0, BedModel(), rng)
    with pytest.raises(InputError, match="unit entries"):
        strata_properties(s, [1.0], [1.0], np.array([1]))
    with pytest.raises(InputError, match="one shape"):
        strata_properties(s, [1.0, 2.0], [1.0])
    assert math.isfinite(strata_properties(s, [1.0], [1.0])[0][0])


def test_fine_blocky_grids_image_as_without_the_shortcuts(monkeypatch):
    """The zero-spike compression adds the same terms in the same order (same bytes), and
    rows_per_cell evaluates exactly the cell-centre rows of the fine section."""
    import demseis.seismic.forward as fwd
    from demseis.seismic import synthetic_sections

    rng = np.random.default_rng(3)
    n = 11
    blocks = rng.uniform(2000.0, 4000.0, (60, 5))
    vp = np.repeat(blocks, 2 * n, axis=0)[: 40 * n]          # beds 22 rows thick
    rho = 310.0 * vp ** 0.25
    fast = synthetic_sections(vp, rho, 10.0 / n, [20.0, 45.0])
    cells = synthetic_sections(vp, rho, 10.0 / n, [20.0, 45.0], rows_per_cell=n)
    monkeypatch.setattr(fwd, "_live_spikes", lambda t, a: (t, a))
    slow = synthetic_sections(vp, rho, 10.0 / n, [20.0, 45.0])
    assert fast.tobytes() == slow.tobytes()
    np.testing.assert_array_equal(cells, slow[:, n // 2::n])
