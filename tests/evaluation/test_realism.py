"""The realism measures against sections whose answer is known."""

from __future__ import annotations

import numpy as np
import pytest

from demseis.errors import InputError
from demseis.evaluation.realism import (adjacent_trace_correlation, best_lag, expected_lags,
                                        horizon_roughness, intact_mask, offset_agreement,
                                        spectral_slope, zero_crossings)


def _layered(n_rows: int = 200, n_traces: int = 40, shift=None, seed: int = 0) -> np.ndarray:
    """Band-limited random reflectivity, the same in every trace (shifted by ``shift[j]``)."""
    rng = np.random.default_rng(seed)
    r = rng.standard_normal(n_rows + 40)
    w = np.exp(-0.5 * (np.arange(-6, 7) / 2.0) ** 2) * np.cos(np.arange(-6, 7) * 0.9)
    trace = np.convolve(r, w, mode="same")
    shift = np.zeros(n_traces, int) if shift is None else np.asarray(shift)
    return np.stack([trace[20 + s:20 + s + n_rows] for s in shift], axis=1)


def test_correlation_matches_numpy_per_window():
    rng = np.random.default_rng(1)
    sec = rng.standard_normal((64, 3))
    want = []
    for w in (slice(0, 32), slice(16, 48), slice(32, 64)):
        for j in range(2):
            want.append(np.corrcoef(sec[w, j], sec[w, j + 1])[0, 1])
    assert adjacent_trace_correlation(sec) == pytest.approx(float(np.median(want)), abs=1e-12)


def test_correlation_of_identical_traces_is_one_and_masked_windows_are_skipped():
    sec = _layered()
    assert adjacent_trace_correlation(sec) == pytest.approx(1.0, abs=1e-12)
    noisy = sec.copy()
    noisy[:, 20:] = np.random.default_rng(2).standard_normal((200, 20))
    assert adjacent_trace_correlation(noisy) < 0.6
    keep = np.zeros(sec.shape, bool)
    keep[:, :20] = True
    assert adjacent_trace_correlation(noisy, keep) == pytest.approx(1.0, abs=1e-12)


def test_zero_crossings_of_a_sinusoid():
    t = np.arange(400)
    # period 10 samples: 2 sign changes per period = 20 per 100 samples
    sec = np.sin(2 * np.pi * (t + 0.25) / 10.0)[:, None].repeat(3, axis=1)
    assert zero_crossings(sec) == pytest.approx(20.0, abs=0.3)


def test_roughness_is_zero_for_flat_reflectors_and_grows_with_jitter():
    flat = horizon_roughness(_layered(shift=np.zeros(40, int)))
    assert flat == pytest.approx(0.0, abs=1e-9)
    rough = horizon_roughness(_layered(shift=np.random.default_rng(3).integers(0, 2, 40)))
    assert rough > 0.3


def test_best_lag_and_offset_agreement_find_a_known_throw():
    a = _layered(n_traces=2)[:, 0]
    b = np.roll(a, 4)
    assert best_lag(a, b, 8) == 4
    shift = np.where(np.arange(40) < 20, 0, 5)          # a 5-sample offset at trace 20
    sec = _layered(shift=shift)
    fault = np.zeros(sec.shape, np.uint8)
    fault[:, 20] = 1
    # trace j + 3 is trace j - 3 moved up by 5 samples: a[t] = b[t - 5], lag -5
    frac, n = offset_agreement(sec, fault, np.full(sec.shape, -5.0))
    assert n > 100 and frac == 1.0
    frac_wrong, _ = offset_agreement(sec, fault, np.full(sec.shape, 5.0))    # wrong sense
    assert frac_wrong == 0.0


def test_expected_lags_at_constant_velocity():
    """2 * throw / vp / dt samples, + where the hanging wall is on the right of a normal
    fault, - for a reverse one and for a fault dipping the other way."""
    nt, nx = 60, 20
    right = np.zeros((nt, nx), np.uint8)
    for t in range(nt):
        right[t, 5 + t // 6] = 1                                    # moves right with depth
    vp = np.full((nt, nx), 2500.0)
    throw = np.full((nt, nx), 20.0)                                  # 2 * 20 / 2500 / 4 ms = 4
    normal = np.ones((nt, nx), np.uint8)
    lags = expected_lags(right, throw, normal, vp, 0.004)
    inner = lags[10:50][right[10:50] > 0]
    np.testing.assert_allclose(inner, 4.0, atol=1e-9)
    np.testing.assert_allclose(expected_lags(right, throw, 2 * normal, vp, 0.004)[10:50][
        right[10:50] > 0], -4.0, atol=1e-9)
    left = right[:, ::-1]
    np.testing.assert_allclose(expected_lags(left, throw, normal, vp, 0.004)[10:50][
        left[10:50] > 0], -4.0, atol=1e-9)
    assert np.isnan(lags[right == 0]).all()


def test_intact_mask_keeps_pixels_away_from_faults():
    f = np.zeros((3, 20), np.uint8)
    f[:, 10] = 1
    m = intact_mask(f, 6)
    assert not m[:, 5:16].any() and m[:, :5].all() and m[:, 16:].all()


def test_spectral_slope_of_white_and_differenced_noise():
    x = np.random.default_rng(4).standard_normal((4096, 16))
    assert abs(spectral_slope(x, 0.001, (5.0, 120.0))) < 0.3
    # differencing multiplies the power by 4 sin^2(pi f dt) ~ f^2 at low frequency
    assert spectral_slope(np.diff(x, axis=0), 0.001, (5.0, 120.0)) == pytest.approx(2.0, abs=0.3)
    with pytest.raises(InputError, match="fewer than 3 frequencies"):
        spectral_slope(x[:8], 0.001, (5.0, 10.0))
