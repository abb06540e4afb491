"""The realism measures against sections whose answer is known."""

from __future__ import annotations

import numpy as np
import pytest

from demseis.errors import InputError
from demseis.evaluation.realism import (adjacent_trace_correlation, amplitude_spectrum,
                                        best_lag, centroid_period, dominant_period,
                                        excess_kurtosis, expected_lags, fault_instances,
                                        faults_per_100_traces, horizon_roughness, intact_mask,
                                        label_fraction, local_dips, offset_agreement,
                                        peak_period, spectral_slope, throws_m, zero_crossings)
from demseis.evaluation.realism_report import _column_velocity, choose_samples, realism_report


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


# ---- the measures of `demseis realism` ----------------------------------------------------------

def _sinusoid(period: float, n_rows: int = 400, n_traces: int = 3) -> np.ndarray:
    t = np.arange(n_rows)
    return np.sin(2 * np.pi * (t + 0.25) / period)[:, None].repeat(n_traces, axis=1)


@pytest.mark.parametrize("period", [6.0, 10.0, 13.3])
def test_period_and_zero_crossings_of_a_sinusoid(period):
    sec = _sinusoid(period)
    assert dominant_period(sec) == pytest.approx(period, rel=0.01)
    s = np.asarray(sec, np.float64)
    assert peak_period(*amplitude_spectrum(s), s.shape[0]) == pytest.approx(period, rel=0.005)
    assert zero_crossings(sec) == pytest.approx(200.0 / period, rel=0.02)


def test_centroid_period_of_a_flat_band():
    """A flat (whitened) band: the centroid is its middle, whatever the ripple's peak says."""
    f = np.linspace(0.0, 0.5, 1001)
    amp = ((f >= 0.05) & (f <= 0.25)).astype(float)
    amp[f == 0.2] += 0.01                           # a ripple the peak would jump to
    assert centroid_period(f, amp, 200) == pytest.approx(1 / 0.15, rel=1e-3)
    assert peak_period(f, amp, 200) == pytest.approx(5.0, rel=1e-3)
    assert np.isnan(centroid_period(f, np.zeros_like(f), 200))


def test_excess_kurtosis_of_known_distributions():
    assert excess_kurtosis(_sinusoid(10.0, 4000)) == pytest.approx(-1.5, abs=1e-3)
    rng = np.random.default_rng(5)
    assert excess_kurtosis(rng.standard_normal((2000, 100))) == pytest.approx(0.0, abs=0.03)
    assert excess_kurtosis(rng.uniform(-1, 1, (2000, 100))) == pytest.approx(-1.2, abs=0.02)
    assert excess_kurtosis(rng.laplace(size=(2000, 100))) == pytest.approx(3.0, abs=0.2)
    spiky = np.zeros((100, 10))
    spiky[::7] = 1.0                                # zeros are dead samples, not amplitudes
    assert np.isnan(excess_kurtosis(spiky))


def _line(dip_deg: float, shape=(300, 300), start=(20, 20), length=250.0, width=1) -> np.ndarray:
    """A rasterised straight line of ``dip_deg`` from horizontal in pixel space (rows down)."""
    m = np.zeros(shape, np.uint8)
    t = np.linspace(0.0, length, int(20 * length))
    r = np.round(start[0] + t * np.sin(np.radians(dip_deg))).astype(int)
    c = np.round(start[1] + t * np.cos(np.radians(dip_deg)) + 0.3).astype(int)
    for k in range(width):
        m[r, c + k] = 1
    return m


@pytest.mark.parametrize("dip", [0.0, 20.0, 45.0, 70.0, 81.0, 85.0, 90.0])
def test_local_dips_of_a_line_of_known_dip(dip):
    d = local_dips(fault_instances(_line(dip)))
    assert d.size > 200
    assert np.median(d) == pytest.approx(dip, abs=0.6)
    assert np.all((d >= 0) & (d <= 90))


def test_local_dips_of_a_line_dipping_the_other_way_and_a_thick_one():
    assert np.median(local_dips(fault_instances(_line(60.0)[:, ::-1]))) == pytest.approx(60, abs=0.6)
    assert np.median(local_dips(fault_instances(_line(60.0, width=2)))) == pytest.approx(60, abs=1.0)


def test_instances_by_id_and_by_connected_components():
    a, b = _line(30.0, start=(10, 10), length=100), _line(80.0, start=(150, 200), length=100)
    fault = a | b
    by_cc = fault_instances(fault)
    assert np.unique(by_cc[by_cc > 0]).size == 2
    fid = np.where(a > 0, 7, 0) + np.where(b > 0, 3, 0)
    d = local_dips(fault_instances(fault, fid))
    assert np.sort(np.percentile(d, [25, 75])) == pytest.approx([30.0, 80.0], abs=1.0)
    assert faults_per_100_traces(fault_instances(fault, fid)) == pytest.approx(200 / 300)


def test_a_blob_has_no_dip():
    blob = np.zeros((40, 40), np.uint8)
    blob[10:30, 10:30] = 1
    d = local_dips(fault_instances(blob))
    assert d.size < 0.5 * blob.sum()                # only its edges are elongated


def test_label_fraction_faults_per_100_traces_and_throw():
    fault = np.zeros((10, 200), np.uint8)
    fault[:, 20] = fault[:, 90] = fault[2:8, 150] = 1
    assert label_fraction(fault) == pytest.approx(26 / 2000)
    assert faults_per_100_traces(fault_instances(fault)) == pytest.approx(1.5)
    slip = np.where(fault > 0, 10.0, 0.0)
    dip = np.full(fault.shape, 30.0)
    np.testing.assert_allclose(throws_m(fault, slip, dip), 5.0)
    slip[0, 20] = np.nan
    assert throws_m(fault, slip, dip).size == 25


def test_column_velocity_from_the_rock_in_time():
    layer = np.full((100, 3), -1, np.int16)
    layer[:50, 0] = 1                               # 400 m in 50 samples of 4 ms: 4000 m/s
    layer[:80, 1] = 2
    layer[10:12, 1] = -1                            # a gap inside the rock does not count
    v = _column_velocity(layer, 400.0, 0.004)
    np.testing.assert_allclose(v[:2], [4000.0, 2500.0])
    assert np.isnan(v[2])


# ---- realism_report on stores with a known answer ------------------------------------------------

def test_noise_free_samples_are_chosen_deterministically(tmp_path):
    import demseis
    from tests.evaluation._helpers import toy_store

    toy_store(tmp_path / "s.zarr", n_shards=4, per_shard=4)         # snr_db: inf, 10, inf, 10
    store = demseis.open(tmp_path / "s.zarr")
    sei, lab, text = choose_samples(store, max_samples=100)
    assert sei.tolist() == list(range(0, 16, 2)) and lab.tolist() == list(range(16))
    assert "all 8 noise-free" in text
    a = choose_samples(store, max_samples=3, seed=1)
    b = choose_samples(store, max_samples=3, seed=1)
    assert a[0].tolist() == b[0].tolist() and len(a[0]) == 3 and set(a[0]) <= set(sei)
    assert "3 of 8 noise-free" in a[2] and "3 of 16 complete" in a[2]
    with pytest.raises(InputError, match="max_samples"):
        choose_samples(store, max_samples=0)


def test_report_of_a_store_of_identical_sinusoid_traces(tmp_path):
    """Every trace the same sinusoid of period 8: period 8, 15 crossings in 64 samples,
    correlation 1;
    one vertical label per sample: dip 90, 100 / 20 faults per 100 traces, 1 / 20 of the pixels."""
    from tests.evaluation._helpers import toy_store

    h, w = 64, 20
    sinus = _sinusoid(8.0, h, w).astype(np.float32)

    def one_line(labs):
        out = np.zeros_like(labs)
        out[:, :, 7] = 1
        return out

    toy_store(tmp_path / "s.zarr", n_shards=3, per_shard=4, h=h, w=w, fault_fn=one_line,
              seismic_fn=lambda secs: np.broadcast_to(sinus, secs.shape).copy())
    r = realism_report(tmp_path / "s.zarr")
    m = r["store"]["measures"]
    assert m["dominant_period_samples"] == pytest.approx(8.0, rel=0.02)
    assert m["zero_crossings_per_100"] == pytest.approx(100 * 15 / 63)   # 15 in 64 samples
    assert m["adjacent_trace_correlation"] == pytest.approx(1.0, abs=1e-9)
    assert m["apparent_dip_deg"]["median"] == pytest.approx(90.0)
    assert m["faults_per_100_traces"]["median"] == pytest.approx(5.0)
    assert m["label_fraction_pct"]["median"] == pytest.approx(5.0)
    assert m["throw_m"] is None                     # no slip_m / dip_deg arrays
    assert r["store"]["seismic_samples"] == list(range(0, 12, 2))
    assert r["field"] is None and r["notes"]        # a depth store: the note says so


def test_report_of_the_tiny_store(tiny_store):
    import json

    from demseis.evaluation.realism_report import MEASURES, format_report, report_json

    r = realism_report(tiny_store, max_samples=5, seed=3)
    m = r["store"]["measures"]
    for key in ("dominant_period_samples", "zero_crossings_per_100", "adjacent_trace_correlation",
                "excess_kurtosis"):
        assert np.isfinite(m[key]), key
    assert 0 < m["adjacent_trace_correlation"] <= 1
    assert 0 <= m["apparent_dip_deg"]["p10"] <= m["apparent_dip_deg"]["p90"] <= 90
    # a depth store: throw in samples is throw in cells
    assert m["throw_samples"]["median"] == pytest.approx(m["throw_m"]["median"] / r["store"]["cell_m"])
    assert len(r["store"]["seismic_samples"]) == 5 and len(r["store"]["label_samples"]) == 5
    assert realism_report(tiny_store, max_samples=5, seed=3) == r
    text = format_report(r)
    assert all(label in text for _, label, _ in MEASURES) and "81-88, median 85" in text
    assert json.loads(report_json(r))["store"]["shape"] == r["store"]["shape"]


def test_distribution_bins_cover_every_value():
    from demseis.evaluation.realism_report import _distribution

    d = _distribution(np.array([1.0, 2.0, 12.3, np.nan]), np.linspace(0.0, 10.0, 41))
    assert sum(d["hist"]["counts"]) == 3 == d["n"] and d["hist"]["edges"][-1] >= 12.3
    assert _distribution(np.array([np.nan])) is None


def test_throw_in_samples_of_a_time_store(tmp_path):
    """In time, throw in samples is 2 throw / (v dt) with v the column's mean velocity: the
    ratio to throw in metres implies a rock velocity between 1.5 and 6 km/s, and the report
    says nothing about depth cells."""
    from tests.generator._helpers import generate_tiny

    store = generate_tiny(tmp_path, '[sweep]\nn_runs = 1\n[output]\ndomain = "time"\n'
                          'dt_s = 0.004\n', "t")
    r = realism_report(store)
    m = r["store"]["measures"]
    assert r["store"]["domain"] == "time" and not r["notes"]
    v = 2 * m["throw_m"]["median"] / (m["throw_samples"]["median"] * 0.004)
    assert 1500 < v < 6000, v


def test_report_takes_an_open_store(tiny_store):
    import demseis

    r = realism_report(demseis.open(tiny_store), max_samples=2)
    assert r["store"]["path"] == str(tiny_store)
