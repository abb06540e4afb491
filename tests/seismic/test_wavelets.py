"""Wavelet families, phase rotation, minimum phase and the statistical wavelet estimate, each
against an independent reference: bruges (Ormsby, phase rotation), scipy's analog Butterworth
filters (amplitude spectrum, and the causal filter as the minimum-phase reference), and a
section made from a known wavelet (the estimate)."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from scipy.signal import butter, fftconvolve, freqs, impulse

from demseis.errors import InputError
from demseis.seismic import synthetic_sections
from demseis.seismic.wavelet import (WAVELETS, Wavelet, as_wavelets, estimate_wavelet, kurtosis,
                                     ricker, rotate_phase)

DT = 0.0005


def _butterworth_analog(w: Wavelet):
    """(b, a) of scipy's analog low-cut and high-cut Butterworth filters of the wavelet's order
    and corners, in cascade."""
    lo, hi = w.band_hz()
    bl, al = butter(4, 2 * np.pi * hi, "low", analog=True)
    bh, ah = butter(4, 2 * np.pi * lo, "high", analog=True)
    return np.polymul(bl, bh), np.polymul(al, ah)


def test_ormsby_matches_bruges(bruges):
    w = Wavelet("ormsby", 40.0, band_octaves=2.0)
    f1, f2, f3, f4 = w.ormsby_corners()
    assert (f2, f3) == pytest.approx((20.0, 80.0))
    length = 2 * w.half_width_s()
    ours = w.samples(DT, length)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DeprecationWarning)
        ref = bruges.filters.ormsby(length, DT, [f1, f2, f3, f4], return_t=True).amplitude
    t = (np.arange(ours.size) - ours.size // 2) * DT
    core = np.abs(t) <= 0.75 * w.half_width_s()           # inside the taper
    assert ours.size == ref.size
    np.testing.assert_allclose(ours[core], ref[core], atol=1e-3)
    assert np.abs(ours[~core]).max() < 2e-3                 # the truncated tail is small


def test_butterworth_amplitude_is_scipys_analog_filters_squared():
    w = Wavelet("butterworth", 30.0, band_octaves=1.5)
    b, a = _butterworth_analog(w)
    f = np.linspace(0.5, 400.0, 800)
    _, h = freqs(b, a, 2 * np.pi * f)
    np.testing.assert_allclose(w.amplitude(f), np.abs(h) ** 2, rtol=1e-9, atol=1e-15)
    np.testing.assert_allclose(np.exp(w.log_amplitude(f)), np.abs(h) ** 2, rtol=1e-9, atol=1e-15)
    # and the sampled wavelet carries that spectrum (zero phase: its amplitude is the spectrum)
    s = w.samples(DT, 2 * w.half_width_s())
    spec = np.abs(np.fft.rfft(s, 1 << 15))
    fr = np.fft.rfftfreq(1 << 15, DT)
    ref = w.amplitude(fr)
    np.testing.assert_allclose(spec / spec.max(), ref / ref.max(), atol=3e-3)


@pytest.mark.parametrize("phase", [30.0, 90.0, -120.0, 180.0])
def test_phase_rotation_matches_bruges(bruges, phase):
    r = ricker(30.0, DT, 0.6)
    ref = bruges.filters.rotate_phase(r, phase, degrees=True)
    np.testing.assert_allclose(rotate_phase(r, phase), ref, atol=1e-12)
    rotated = Wavelet("ricker", 30.0, phase_deg=phase).samples(DT, 0.6)
    t = (np.arange(r.size) - r.size // 2) * DT
    core = np.abs(t) <= 0.075                      # the analytic Ricker's long Hilbert tail
    np.testing.assert_allclose(rotated[core], ref[core], atol=5e-4)


def test_minimum_phase_butterworth_is_the_causal_analog_filter():
    """The minimum-phase wavelet of |H|^2 is the causal filter H^2 (poles in the left half
    plane): scipy's impulse response of the analog cascade, run twice."""
    w = Wavelet("butterworth", 40.0, phase="minimum")
    b, a = _butterworth_analog(w)
    t = np.arange(0.0, 0.15, 2e-4)
    _, ref = impulse((np.polymul(b, b), np.polymul(a, a)), T=t)
    ours = w.samples(2e-4, 0.3)
    assert np.sum(ours[:ours.size // 2] ** 2) < 1e-9 * np.sum(ours ** 2)   # causal
    ours = ours[ours.size // 2:][:t.size]
    assert np.corrcoef(ours, ref)[0, 1] > 0.99
    assert abs(int(np.argmax(np.abs(ours))) - int(np.argmax(np.abs(ref)))) <= 2


@pytest.mark.parametrize("family", WAVELETS)
def test_every_variant_keeps_the_zero_phase_amplitude_spectrum(family):
    zero = Wavelet(family, 30.0).samples(DT, 1.0)
    n = 1 << 14
    ref = np.abs(np.fft.rfft(zero, n))
    for w, tol in ((Wavelet(family, 30.0, phase_deg=60.0), 0.005),
                   (Wavelet(family, 30.0, phase="minimum"), 0.05 if family == "ormsby" else 0.005)):
        spec = np.abs(np.fft.rfft(w.samples(DT, 1.0), n))
        assert np.abs(spec - ref).max() < tol * ref.max(), w
    assert zero[zero.size // 2] == pytest.approx(1.0, abs=1e-3)  # peak 1 at t = 0
    # minimum phase puts the energy first: of the wavelets of one amplitude spectrum, each
    # started where it starts, it has the most energy in its first 30 ms
    def first_30ms(w: Wavelet) -> float:
        x = w.samples(DT, 1.0)
        start = int(np.flatnonzero(np.abs(x) > 1e-4 * np.abs(x).max())[0])
        return float(np.sum(x[start:start + 60] ** 2) / np.sum(x ** 2))

    mp = first_30ms(Wavelet(family, 30.0, phase="minimum"))
    for phase in (0.0, 45.0, 90.0):
        assert mp > first_30ms(Wavelet(family, 30.0, phase_deg=phase)), phase


def test_plain_ricker_wavelet_renders_the_same_bytes_as_a_frequency():
    rng = np.random.default_rng(3)
    vp = rng.uniform(2000, 4000, (60, 5))
    rho = 310.0 * vp ** 0.25
    a = synthetic_sections(vp, rho, 5.0, [20.0, 40.0])
    b = synthetic_sections(vp, rho, 5.0, [Wavelet("ricker", 20.0), 40.0])
    assert a.tobytes() == b.tobytes()


@pytest.mark.parametrize("wavelet", [Wavelet("ormsby", 35.0), Wavelet("ricker", 30.0, phase_deg=70.0),
                                     Wavelet("butterworth", 25.0, phase="minimum")])
def test_a_wavelet_section_is_the_direct_sum_over_interfaces(wavelet):
    """The table kernel against the obvious sum s(t) = sum_i R_i w(t - T_i) at the cell-centre
    times, w from Wavelet.samples on a 0.01 ms grid."""
    rng = np.random.default_rng(4)
    vp = rng.uniform(2000, 4000, (80, 3))
    rho = 310.0 * vp ** 0.25
    sec = synthetic_sections(vp, rho, 4.0, [40.0, wavelet, 20.0])
    assert sec.shape == (3, 80, 3)
    fine = 1e-5
    half = wavelet.half_width_s()
    w = wavelet.samples(fine, 2 * half + 2 * fine)
    tw = (np.arange(w.size) - w.size // 2) * fine
    z = vp * rho
    refl = (z[1:] - z[:-1]) / (z[1:] + z[:-1])
    t_bot = 2 * np.cumsum(4.0 / vp, axis=0)
    t_ctr = t_bot - 4.0 / vp
    for c in range(3):
        expect = [np.sum(refl[:, c] * np.interp(t - t_bot[:-1, c], tw, w, left=0, right=0))
                  for t in t_ctr[:, c]]
        np.testing.assert_allclose(sec[1, :, c], expect, atol=2e-5)
    np.testing.assert_array_equal(sec[[0, 2]], synthetic_sections(vp, rho, 4.0, [40.0, 20.0]))


@pytest.mark.parametrize("phase", [0.0, 50.0, -70.0, 85.0])
def test_estimate_finds_the_phase_and_band_of_a_known_wavelet(phase):
    rng = np.random.default_rng(0)
    refl = rng.laplace(size=(600, 200)) * (rng.random((600, 200)) < 0.1)   # sparse
    true = Wavelet("ricker", 30.0, phase_deg=phase)
    section = fftconvolve(refl, true.samples(0.002, 0.3)[:, None], mode="same", axes=0)
    est = estimate_wavelet(section, 0.002)
    assert est.phase_deg == pytest.approx(phase, abs=2.0)
    assert est.dominant_hz == pytest.approx(30.0, rel=0.05)
    ref = true.amplitude(est.freqs_hz)
    assert np.corrcoef(est.amplitude, ref)[0, 1] > 0.98
    # the returned samples are the true wavelet (same band and phase), up to scale
    w = est.samples
    t_w = true.samples(0.002, 0.128)
    assert w.size == t_w.size and np.corrcoef(w, t_w)[0, 1] > 0.95


def test_kurtosis_of_known_distributions():
    rng = np.random.default_rng(1)
    assert kurtosis(rng.standard_normal(200_000)) == pytest.approx(0.0, abs=0.05)
    assert kurtosis(rng.laplace(size=200_000)) == pytest.approx(3.0, abs=0.15)
    assert kurtosis(np.sin(np.linspace(0, 200 * np.pi, 100_000))) == pytest.approx(-1.5, abs=1e-3)
    assert np.isnan(kurtosis(np.ones(10)))


def test_bad_wavelets_are_named():
    with pytest.raises(InputError, match="family"):
        Wavelet("morlet", 30.0)
    with pytest.raises(InputError, match="phase must be one of"):
        Wavelet("ricker", 30.0, phase="maximum")
    with pytest.raises(InputError, match="band_octaves"):
        Wavelet("ormsby", 30.0, band_octaves=0.0)
    with pytest.raises(InputError, match="a frequency .* or a Wavelet"):
        as_wavelets(["40"])
    with pytest.raises(InputError, match="constant"):
        estimate_wavelet(np.ones((100, 4)), 0.002)


def test_the_parameters_offer_the_families_and_phases_of_the_module():
    from demseis.parameters import PARAMS
    from demseis.seismic.noise import NOISE_KINDS
    from demseis.seismic.wavelet import WAVELET_PHASES

    assert tuple(PARAMS["wavelet"].choices) == WAVELETS
    assert tuple(PARAMS["wavelet_phase"].choices) == WAVELET_PHASES
    assert tuple(PARAMS["noise_kind"].choices) == NOISE_KINDS
