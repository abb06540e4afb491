"""Property model, layer and element properties, property grids."""

import dataclasses

import numpy as np
import pytest
import scipy.ndimage as ndi

from demseis.errors import ConfigError, InputError
from demseis.seismic import (PropertyModel, draw_layer_properties, element_properties,
                             property_grids)
from demseis.types import Grid
from demseis_dev.toys import faulted_sequence


def test_defaults_validate_and_lists_become_tuples():
    m = PropertyModel().validate()
    assert m.vp_lower_bound_m_s == pytest.approx(2200 * 0.91)
    m2 = PropertyModel(lithologies=["a", "b"], lithology_weights=[1, 1], vp_min_m_s=[2000, 3000],
                       vp_max_m_s=[2500, 3500], rho_min_kg_m3=[2000, 2100],
                       rho_max_kg_m3=[2200, 2300]).validate()
    assert isinstance(m2.vp_min_m_s, tuple)
    hash(m2)
    for f in dataclasses.fields(PropertyModel):
        assert f.type in ("tuple[str, ...]", "tuple[float, ...]", "str", "float", "int"), f


@pytest.mark.parametrize("changes,match", [
    ({"vp_min_m_s": (2200.0, 2600.0)}, r"vp_min_m_s.*3 numbers"),
    ({"vp_min_m_s": (2200.0, 9000.0, 3800.0)}, r"vp_min_m_s.*\[1200.0, 8000.0\]"),
    ({"vp_max_m_s": (2000.0, 4000.0, 5500.0)}, r"vp_min_m_s\[0\] = 2200.0 m/s exceeds"),
    ({"density": "wyllie"}, r"density = 'wyllie'.*gardner"),
    ({"background": "zero"}, r"background"),
    ({"gardner_b": 0.9}, r"gardner_b = 0.9.*\[0.1, 0.5\]"),
    ({"vp_scatter": -0.1}, r"vp_scatter"),
    ({"median_size_cells": 4}, r"median_size_cells = 4.*odd"),
    ({"gaussian_sigma_cells": 9.0}, r"gaussian_sigma_cells"),
    ({"lithology_weights": (0.0, 0.0, 0.0)}, r"lithology_weights.*positive sum"),
    ({"lithologies": ("a", "a", "b")}, r"unique"),
])
def test_validate_names_field_value_range(changes, match):
    with pytest.raises(ConfigError, match=match):
        PropertyModel(**changes).validate()


def test_layer_properties_ranges_and_prefix_stability():
    m = PropertyModel()
    lp = draw_layer_properties(60, m, np.random.default_rng(4))
    lo = np.asarray(m.vp_min_m_s)[lp.lithology]
    hi = np.asarray(m.vp_max_m_s)[lp.lithology]
    assert np.all((lp.vp >= lo) & (lp.vp <= hi))
    np.testing.assert_allclose(lp.rho, 310.0 * lp.vp ** 0.25)
    assert set(np.unique(lp.lithology)) == {0, 1, 2}
    # growth layers appended after the pre-kinematic ones do not change the earlier draws
    lp48 = draw_layer_properties(48, m, np.random.default_rng(4))
    np.testing.assert_array_equal(lp48.vp, lp.vp[:48])
    np.testing.assert_array_equal(lp48.lithology, lp.lithology[:48])


def test_layer_properties_density_ranges_and_weights():
    m = PropertyModel(density="range", lithology_weights=(0.0, 1.0, 0.0))
    lp = draw_layer_properties(500, m, np.random.default_rng(5))
    assert np.all(lp.lithology == 1)
    assert np.all((lp.rho >= 2100.0) & (lp.rho <= 2450.0))
    assert np.ptp(lp.rho) > 300  # uniform over the range, not Gardner
    with pytest.raises(InputError, match="n_layers_total"):
        draw_layer_properties(0, m, np.random.default_rng(0))


def test_element_properties_are_a_function_of_id():
    m = PropertyModel(vp_scatter=0.05, rho_scatter=0.02)
    lp = draw_layer_properties(10, m, np.random.default_rng(0))
    rng = np.random.default_rng(1)
    n = 20000
    ids = rng.permutation(10 * n)[:n].astype(np.int64)
    layer = rng.integers(0, 10, n).astype(np.int16)
    vp, rho = element_properties(ids, layer, lp, m, seed=7)
    perm = rng.permutation(n)[: n // 2]
    vp2, rho2 = element_properties(ids[perm], layer[perm], lp, m, seed=7)
    np.testing.assert_array_equal(vp2, vp[perm])
    np.testing.assert_array_equal(rho2, rho[perm])
    vp3, _ = element_properties(ids, layer, lp, m, seed=8)
    assert not np.allclose(vp3, vp)
    ev = vp / lp.vp[layer] - 1
    er = rho / lp.rho[layer] - 1
    assert np.mean(ev) == pytest.approx(0.0, abs=0.002)
    assert np.std(ev) == pytest.approx(0.05, rel=0.03)
    assert np.std(er) == pytest.approx(0.02, rel=0.03)
    assert abs(np.corrcoef(ev, er)[0, 1]) < 0.03
    assert np.max(np.abs(ev)) <= 0.15 + 1e-12  # clipped at 3 sigma
    with pytest.raises(InputError, match="layer indices"):
        element_properties(ids, layer + 5, lp, m, seed=7)
    with pytest.raises(InputError, match="seed"):
        element_properties(ids, layer, lp, m, seed=-1)


def _grids_reference(xy, radius, vp_e, rho_e, layer, grid, model):
    """Slow property grids: per-cell loops, brute-force nearest element, scipy filters."""
    nz, nx = grid.shape
    out = []
    for vals in (vp_e, rho_e):
        g = np.empty((nz, nx))
        for i in range(nz):
            yc = grid.top_m - (i + 0.5) * grid.cell_m
            for j in range(nx):
                xc = grid.x0_m + (j + 0.5) * grid.cell_m
                d2 = (xc - xy[:, 0]) ** 2 + (yc - xy[:, 1]) ** 2
                inside = d2 <= radius ** 2
                if inside.any():
                    g[i, j] = vals[inside].mean()
                elif model.background == "global":
                    g[i, j] = vals.mean()
                else:
                    g[i, j] = vals[layer == layer[np.argmin(d2)]].mean()
        g = ndi.gaussian_filter(g, model.gaussian_sigma_cells, mode="nearest")
        out.append(ndi.median_filter(g, model.median_size_cells, mode="nearest"))
    return out


@pytest.mark.parametrize("background", ["layer", "global"])
def test_property_grids_match_slow_reference(background):
    snaps = faulted_sequence(600.0, 400.0, n_layers=6, throw_m=100.0, n_snapshots=3,
                             rng=np.random.default_rng(2))
    snap = snaps[-1]
    m = PropertyModel(background=background)
    lp = draw_layer_properties(int(snap.layer.max()) + 1, m, np.random.default_rng(3))
    vp_e, rho_e = element_properties(snap.ids, snap.layer, lp, m, seed=1)
    grid = Grid.covering(600.0, 400.0, 10.0)
    vp_g, rho_g = property_grids(snap.xy, snap.radius, vp_e, rho_e, snap.layer, grid, m)
    ref_vp, ref_rho = _grids_reference(snap.xy, snap.radius, vp_e, rho_e, snap.layer, grid, m)
    np.testing.assert_allclose(vp_g, ref_vp, rtol=1e-12)
    np.testing.assert_allclose(rho_g, ref_rho, rtol=1e-12)
    assert vp_g.min() >= m.vp_lower_bound_m_s


def test_property_grids_bad_shapes():
    grid = Grid.covering(100.0, 100.0)
    with pytest.raises(InputError, match="property_grids"):
        property_grids(np.zeros((3, 2)), np.ones(3), np.ones(2), np.ones(3), np.zeros(3, int),
                       grid, PropertyModel())
