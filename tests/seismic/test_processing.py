"""Coloured and coherent noise, trace gains, AGC, clipping and quantisation, each against a slow
obvious reference or the statistic it promises."""

from __future__ import annotations

import math

import numpy as np
import pytest

from demseis.errors import InputError
from demseis.seismic import add_noise, snr_db
from demseis.seismic.processing import Processing, agc, linear_noise, process, quantise


def _section(seed: int = 0, shape=(256, 64)) -> np.ndarray:
    rng = np.random.default_rng(seed)
    x = np.cumsum(rng.standard_normal(shape), axis=0)
    return (x - x.mean(axis=0)).astype(np.float32)


@pytest.mark.parametrize("slope", [0.0, 1.0, 2.0])
def test_coloured_noise_has_its_spectral_slope_and_snr(slope):
    sec = _section(1, (512, 200))
    noisy = add_noise(sec, 3.0, "coloured", np.random.default_rng(2), slope=slope)
    assert snr_db(sec, noisy) == pytest.approx(3.0, abs=1e-3)
    noise = noisy.astype(np.float64) - sec
    psd = np.mean(np.abs(np.fft.rfft(noise, axis=0)) ** 2, axis=1)
    f = np.fft.rfftfreq(noise.shape[0])
    band = (f > 0.01) & (f < 0.45)
    fit = np.polyfit(np.log(f[band]), np.log(psd[band]), 1)[0]
    assert fit == pytest.approx(-slope, abs=0.1)


def test_linear_noise_is_one_trace_shifted_along_x_at_its_snr():
    sec = _section(3).astype(np.float64)
    noise = linear_noise(sec, 6.0, 3.0, np.random.default_rng(0))
    assert 20 * math.log10(np.sqrt(np.mean(sec ** 2)) / np.sqrt(np.mean(noise ** 2))) == \
        pytest.approx(6.0, abs=1e-9)
    for j in (1, 5, 20):
        np.testing.assert_allclose(noise[:, j], np.roll(noise[:, 0], 3 * j), atol=1e-9)


def test_agc_matches_a_loop():
    rng = np.random.default_rng(4)
    x = rng.standard_normal((50, 3)) * np.linspace(0.1, 10, 50)[:, None]
    out = agc(x, 7)
    ref = np.empty_like(x)
    for i in range(50):
        for j in range(3):
            win = x[max(0, i - 3):min(50, i + 4), j]
            ref[i, j] = x[i, j] / math.sqrt(np.mean(win ** 2))
    np.testing.assert_allclose(out, ref, rtol=1e-10)
    assert np.all(agc(np.zeros((5, 2)), 3) == 0)


def test_quantise_is_an_8_bit_display_image():
    x = _section(5).astype(np.float64)
    q = quantise(x, 8)
    m = np.abs(x).max()
    as_uint8 = np.round((x + m) / (2 * m) * 255).astype(np.uint8)      # what a PNG holds
    np.testing.assert_allclose(q, as_uint8 / 255.0 * 2 * m - m, atol=1e-12)
    assert np.unique(q).size <= 256
    assert np.abs(q - x).max() <= m / 255 + 1e-12


def test_process_steps_do_what_they_say():
    x = _section(6, (128, 400)).astype(np.float64)
    rng = np.random.default_rng(7)
    jittered = process(x, Processing(trace_gain_jitter=0.3), rng)
    gains = np.sqrt(np.sum(jittered ** 2, axis=0) / np.sum(x ** 2, axis=0))
    assert np.std(np.log(gains)) == pytest.approx(0.3, rel=0.15)
    bright = process(x, Processing(time_gain_jitter=0.5), rng)
    gain = bright[:, 0] / np.where(x[:, 0] == 0, 1, x[:, 0])
    np.testing.assert_allclose(bright, x * gain[:, None], rtol=1e-9)    # one gain per row
    assert np.all(gain > 0)
    logs = np.log(np.stack([process(np.ones((2000, 1)), Processing(time_gain_jitter=0.5), rng)[:, 0]
                            for _ in range(20)]))
    assert np.std(logs) == pytest.approx(0.5, rel=0.05)
    lag = np.mean(logs[:, 12:] * logs[:, :-12]) / np.mean(logs * logs)
    assert lag == pytest.approx(math.exp(-12 ** 2 / (4 * 12.0 ** 2)), abs=0.05)  # Gaussian smoothing
    striped = process(x, Processing(footprint_amplitude=0.5, footprint_period_traces=8.0), rng)
    ratio = (striped / np.where(x == 0, 1, x))[10]
    # 1 + 0.5 cos(2 pi j / 8 + phi): eight phases a period, mean square of the cosine 1/2
    assert np.abs(ratio - 1).max() <= 0.5 + 1e-9
    assert np.sqrt(np.mean((ratio - 1) ** 2)) == pytest.approx(0.5 / math.sqrt(2), rel=1e-6)
    spec = np.abs(np.fft.rfft(ratio - ratio.mean()))
    assert np.fft.rfftfreq(ratio.size)[int(np.argmax(spec))] == pytest.approx(1 / 8, abs=1e-3)
    clipped = process(x, Processing(clip_percentile=90.0), rng)
    c = np.percentile(np.abs(x), 90.0)
    assert np.abs(clipped).max() == pytest.approx(c)
    assert np.mean(np.abs(clipped) >= c - 1e-12) == pytest.approx(0.10, abs=0.01)


def test_the_defaults_return_the_same_bytes_and_draw_nothing():
    x = _section(8)
    rng = np.random.default_rng(9)
    state = rng.bit_generator.state
    out = process(x, Processing.of({"agc_window_samples": 0, "clip_percentile": 100.0}), rng)
    assert out.dtype == np.float32 and out.tobytes() == x.tobytes()
    assert rng.bit_generator.state == state
    assert Processing(footprint_period_traces=33.0, linear_noise_slope=-4.0).is_identity


def test_bad_processing_values_are_named():
    with pytest.raises(InputError, match="clip_percentile"):
        Processing(clip_percentile=0.0)
    with pytest.raises(InputError, match="footprint_amplitude"):
        Processing(footprint_amplitude=2.0)
    with pytest.raises(InputError, match="noise slope"):
        add_noise(np.ones((4, 4)), 10.0, "coloured", np.random.default_rng(0), slope=-1.0)
    with pytest.raises(InputError, match="one .rows, traces. section"):
        process(np.ones(5), Processing(quantise_bits=8), np.random.default_rng(0))
