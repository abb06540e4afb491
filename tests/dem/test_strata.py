"""Mechanical stratigraphy: the lithology -> contact material mapping."""

from __future__ import annotations

import dataclasses
import math

import pytest

from demseis.dem import Material
from demseis.dem.integrator import validate_material
from demseis.dem.strata import alternation, is_strong, layer_materials
from demseis.errors import InputError
from demseis.parameters import PARAMS


def test_contrast_9_scales_cohesion_both_ways_and_softens_and_weakens_shale():
    base = Material(cohesion_n=1.0e8, friction=0.4, kn_n_m=1.0e10)
    strong, weak = layer_materials(["sandstone", "shale"], base, 9.0)
    assert strong.cohesion_n == pytest.approx(3.0e8) and weak.cohesion_n == pytest.approx(1.0e8 / 3)
    assert (strong.kn_n_m, strong.friction) == (1.0e10, 0.4)
    assert weak.kn_n_m == pytest.approx(2.5e9) and weak.friction == pytest.approx(0.2)
    assert weak.bond_strain == strong.bond_strain == base.bond_strain


def test_mild_contrast_and_uniform():
    base = Material()
    strong, weak = layer_materials(["limestone", "mudstone"], base, 2.0)
    assert weak.kn_n_m == pytest.approx(base.kn_n_m / 2)
    assert weak.friction == pytest.approx(base.friction / math.sqrt(2))
    assert strong.cohesion_n == pytest.approx(base.cohesion_n * math.sqrt(2))
    assert layer_materials(["sandstone", "shale"], base, 1.0) == [base, base]


def test_layers_stay_inside_the_stage_domain():
    """Layers are clipped to what the DEM accepts (the stage domain), not to the config range:
    a weak layer of the lowest declared Kn is 4x softer than it."""
    top = PARAMS["cohesion_n"].stage().hi
    low_kn = PARAMS["kn_n_m"].stage().lo
    base = dataclasses.replace(Material(), cohesion_n=0.99 * top, kn_n_m=low_kn)
    strong, weak = layer_materials(["sandstone", "shale"], base, 16.0)
    assert strong.cohesion_n == top and weak.kn_n_m == low_kn
    validate_material(strong)
    validate_material(weak)
    lowest = dataclasses.replace(Material(), kn_n_m=PARAMS["kn_n_m"].lo)
    weak = layer_materials(["shale"], lowest, 16.0)[0]
    assert weak.kn_n_m == pytest.approx(PARAMS["kn_n_m"].lo / 4)
    validate_material(weak)


def test_contrast_below_one_is_refused():
    with pytest.raises(InputError, match="contrast"):
        layer_materials(["shale"], Material(), 0.5)


def test_alternation_starts_strong_at_the_base():
    lith = alternation(7, 2)
    assert lith == ["sandstone"] * 2 + ["shale"] * 2 + ["sandstone"] * 2 + ["shale"]
    assert [is_strong(x) for x in lith[:3]] == [True, True, False]
    with pytest.raises(InputError):
        alternation(0, 2)
