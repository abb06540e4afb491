"""Noise at a stated SNR: measured SNR, spectra, determinism."""

import math

import numpy as np
import pytest

from demseis.errors import InputError
from demseis.seismic import add_noise, synthetic_sections


@pytest.fixture(scope="module")
def section():
    rng = np.random.default_rng(11)
    nz, nx = 160, 60
    vp = np.repeat(rng.uniform(2200, 4500, (nz, 1)), nx, axis=1)
    rho = 310 * vp ** 0.25
    return synthetic_sections(vp, rho, 10.0, [40.0])[0]


def _measured_snr(clean, noisy):
    c = clean.astype(np.float64)
    n = noisy.astype(np.float64) - c
    return 20 * math.log10(np.sqrt(np.mean(c ** 2)) / np.sqrt(np.mean(n ** 2)))


@pytest.mark.parametrize("kind", ["white", "band"])
@pytest.mark.parametrize("snr", [-3.0, 0.0, 6.0, 20.0])
def test_median_measured_snr_within_0p2_db(section, kind, snr):
    rng = np.random.default_rng(12)
    vals = [_measured_snr(section, add_noise(section, snr, kind, rng)) for _ in range(100)]
    assert abs(np.median(vals) - snr) < 0.2
    assert max(abs(v - snr) for v in vals) < 0.01  # every draw is scaled to the request


def _power_fraction_above(noise, k):
    p = np.mean(np.abs(np.fft.rfft(noise, axis=0)) ** 2, axis=1)
    return p[k:].sum() / p.sum()


def test_band_noise_has_the_signal_band_white_is_flat():
    rng = np.random.default_rng(13)
    nz, nx = 200, 60
    vp = np.repeat(rng.uniform(2200, 4500, (nz, 1)), nx, axis=1)
    section = synthetic_sections(vp, 310 * vp ** 0.25, 10.0, [20.0])[0]
    white = add_noise(section, 0.0, "white", rng).astype(np.float64) - section
    band = add_noise(section, 0.0, "band", rng).astype(np.float64) - section
    nk = section.shape[0] // 2 + 1
    k_cut = nk // 2  # upper half of the wavenumbers
    assert _power_fraction_above(white, k_cut) == pytest.approx(0.5, abs=0.05)
    sig = _power_fraction_above(section.astype(np.float64), k_cut)
    assert sig < 0.2  # a 20 Hz section lives in the lower wavenumbers
    assert _power_fraction_above(band, k_cut) == pytest.approx(sig, abs=0.03)
    # spectra shapes: band noise correlates with the signal spectrum, white does not
    ps = np.mean(np.abs(np.fft.rfft(section, axis=0)) ** 2, axis=1)
    pb = np.mean(np.abs(np.fft.rfft(band, axis=0)) ** 2, axis=1)
    assert np.corrcoef(ps, pb)[0, 1] > 0.9


def test_noise_is_seeded_and_inf_is_a_copy(section):
    a = add_noise(section, 5.0, "band", np.random.default_rng(1))
    b = add_noise(section, 5.0, "band", np.random.default_rng(1))
    c = add_noise(section, 5.0, "band", np.random.default_rng(2))
    assert a.dtype == np.float32 and a.tobytes() == b.tobytes() and a.tobytes() != c.tobytes()
    clean = add_noise(section, math.inf, "white", np.random.default_rng(1))
    assert clean is not section and np.array_equal(clean, section)


def test_stack_of_sections_each_at_its_snr():
    rng = np.random.default_rng(3)
    stack = rng.standard_normal((3, 40, 20)) * np.array([1.0, 10.0, 0.1])[:, None, None]
    noisy = add_noise(stack, 10.0, "white", rng)
    for k in range(3):
        assert _measured_snr(stack[k], noisy[k]) == pytest.approx(10.0, abs=1e-6)
    trace = rng.standard_normal(64)
    assert _measured_snr(trace, add_noise(trace, 3.0, "band", rng)) == pytest.approx(3.0, abs=1e-6)


def test_bad_noise_arguments(section):
    rng = np.random.default_rng(0)
    with pytest.raises(InputError, match="kind"):
        add_noise(section, 5.0, "pink", rng)
    with pytest.raises(InputError, match="snr_db"):
        add_noise(section, float("nan"), "white", rng)
    with pytest.raises(InputError, match="snr_db"):
        add_noise(section, "loud", "white", rng)
