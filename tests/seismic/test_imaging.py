"""The imaging table: the dispatcher, the built-in modes and a mode registered at run time."""

import numpy as np
import pytest

from demseis.errors import InputError
from demseis.registry import IMAGING
from demseis.seismic import ImagingMode, imaged_sections, imaging_mode, psf_sections
from demseis.seismic.forward import synthetic_sections


def test_imaged_sections_dispatch_and_no_limit():
    rng = np.random.default_rng(9)
    vp = rng.uniform(2500, 3500, (50, 30))
    rho = np.full_like(vp, 2300.0)
    one_d = synthetic_sections(vp, rho, 10.0, [30.0])
    np.testing.assert_array_equal(imaged_sections("1d", vp, rho, 10.0, [30.0]), one_d)
    np.testing.assert_array_equal(psf_sections(vp, rho, 10.0, [30.0], 90.0), one_d)
    psf = imaged_sections("psf", vp, rho, 10.0, [30.0], psf_max_angle_deg=20.0)
    assert psf.shape == one_d.shape and not np.allclose(psf, one_d, atol=1e-3)
    with pytest.raises(InputError, match="imaging"):
        imaged_sections("2d", vp, rho, 10.0, [30.0])



def test_builtin_modes_group_by_their_options():
    one_d, psf = imaging_mode("1d"), imaging_mode("psf")
    values = {"psf_max_angle_deg": 30.0, "psf_aperture_m": 0.0, "freq_hz": 40.0}
    assert one_d.key_of(values) == () and one_d.title(values) == "1-D"
    assert psf.key_of(values) == (30.0, np.inf)
    assert psf.key_of({**values, "psf_aperture_m": 500.0}) == (30.0, 500.0)
    assert psf.title(values) == "PSF 30°"


def test_a_registered_mode_is_dispatched_with_its_options():
    calls = []

    def doubled(vp_g, rho_g, cell_m, freqs_hz, domain="depth", *, t_s=None, gain=1.0):
        calls.append(gain)
        return gain * synthetic_sections(vp_g, rho_g, cell_m, freqs_hz, domain, t_s=t_s)

    vp = np.linspace(2000.0, 3000.0, 40)[:, None] * np.ones((1, 8))
    rho = np.full_like(vp, 2300.0)
    with IMAGING.registered("doubled", ImagingMode(doubled, options=("gain",))):
        out = imaged_sections("doubled", vp, rho, 10.0, [30.0], gain=2.0, psf_max_angle_deg=5.0)
        np.testing.assert_array_equal(out, 2.0 * synthetic_sections(vp, rho, 10.0, [30.0]))
        assert calls == [2.0]   # only its own option was passed
    assert "doubled" not in IMAGING
    with pytest.raises(InputError, match="doubled"):
        imaging_mode("doubled")
