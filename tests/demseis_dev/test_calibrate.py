"""Biaxial test machinery: the servo holds sigma3 and strength follows Mohr-Coulomb trends."""

from __future__ import annotations

import math

import pytest

from demseis.dem import Material
from demseis.errors import InputError
from demseis_dev.calibrate import biaxial_test, mohr_coulomb_fit


def test_mohr_coulomb_fit_recovers_known_envelope():
    phi, c = 35.0, 5e6
    s = math.sin(math.radians(phi))
    s3 = [1e6, 5e6, 20e6]
    s1 = [2 * c * math.cos(math.radians(phi)) / (1 - s) + x * (1 + s) / (1 - s) for x in s3]
    got_phi, got_c = mohr_coulomb_fit(s3, s1)
    assert got_phi == pytest.approx(phi, abs=1e-9)
    assert got_c == pytest.approx(c, rel=1e-9)
    with pytest.raises(InputError):
        mohr_coulomb_fit([1e6], [2e6])


def test_biaxial_strength_grows_with_confinement_and_cohesion(tmp_path):
    kw = dict(max_axial_strain=0.08, cache_dir=tmp_path)
    low = biaxial_test(Material(cohesion_n=0.0), 5e6, **kw)
    high = biaxial_test(Material(cohesion_n=0.0), 20e6, **kw)
    coh = biaxial_test(Material(cohesion_n=2e8), 5e6, **kw)
    assert high["peak_sigma1_pa"] > low["peak_sigma1_pa"] > 5e6
    assert coh["peak_sigma1_pa"] > low["peak_sigma1_pa"]
