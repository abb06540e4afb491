"""Ricker wavelets against bruges.filters.ricker."""

import numpy as np
import pytest

from demseis.errors import InputError
from demseis.seismic import ricker
from demseis.seismic.wavelet import ricker_half_width_s, ricker_table, ricker_value


@pytest.mark.parametrize("f", [5.0, 20.0, 40.0, 60.0, 125.0])
@pytest.mark.parametrize("dt,duration", [(0.001, 0.128), (0.002, 0.256), (0.004, 0.2),
                                         (0.0005, 0.101), (0.002, 0.13)])
def test_ricker_matches_bruges(bruges, f, dt, duration):
    ours = ricker(f, dt, duration)
    ref = bruges.filters.ricker(duration, dt, f).amplitude
    assert ours.shape == ref.shape
    np.testing.assert_allclose(ours, ref, rtol=0, atol=1e-6)


def test_ricker_bank_matches_bruges(bruges):
    freqs = [20.0, 40.0, 60.0]
    ours = ricker(freqs, 0.001, 0.2)
    ref = bruges.filters.ricker(0.2, 0.001, freqs).amplitude
    assert ours.shape == (3, 201) == ref.shape
    np.testing.assert_allclose(ours, ref, rtol=0, atol=1e-6)


@pytest.mark.parametrize("dt,duration", [(0.002, 0.1), (0.002, 0.098), (0.0007, 0.05)])
def test_ricker_odd_zero_phase_peak_one(dt, duration):
    w = ricker(30.0, dt, duration)
    n = w.size
    assert n % 2 == 1
    assert w[n // 2] == 1.0
    assert np.argmax(w) == n // 2
    np.testing.assert_array_equal(w, w[::-1])  # symmetric = zero phase


def test_ricker_spectrum_peaks_at_freq():
    dt = 0.0005
    w = ricker(40.0, dt, 0.4)
    spec = np.abs(np.fft.rfft(w, 1 << 16))
    freqs = np.fft.rfftfreq(1 << 16, dt)
    assert abs(freqs[np.argmax(spec)] - 40.0) < 0.05


def test_ricker_bad_input():
    with pytest.raises(InputError, match="freq_hz"):
        ricker(-5.0, 0.001, 0.1)
    with pytest.raises(InputError, match="dt_s"):
        ricker(20.0, 0.0, 0.1)
    with pytest.raises(InputError, match="duration_s"):
        ricker(20.0, 0.01, 0.001)


@pytest.mark.parametrize("f", [20.0, 60.0])
def test_table_interpolation_error_is_tiny(f):
    table, inv_step, half = ricker_table(f)
    assert half == pytest.approx(ricker_half_width_s(f))
    assert abs(ricker_value(f, half)) < 6e-7  # truncated tail
    t = np.random.default_rng(0).uniform(0, half * 0.999, 20000)
    u = t * inv_step
    p = u.astype(int)
    interp = table[p] + (u - p) * (table[p + 1] - table[p])
    assert np.max(np.abs(interp - ricker_value(f, t))) < 3e-7
