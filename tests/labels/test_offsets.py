"""Reflector offsets from the reference elevation (demseis.labels.offsets)."""

from __future__ import annotations

import numpy as np
import pytest

from demseis.labels.offsets import pair_offsets, pixel_offsets


def _slow_pair_offsets(y0, per_m, width, trend_pairs):
    """Plain loops over rows and pairs: the definition in the module docstring."""
    rows, ntr = y0.shape
    per_m = np.broadcast_to(np.asarray(per_m, float), y0.shape)
    d = [[y0[i, j + 1] - y0[i, j] for j in range(ntr - 1)] for i in range(rows)]
    out = np.full((rows, ntr - 1), np.nan)
    h = width // 2
    for i in range(rows):
        for j in range(ntr - 1):
            lo, hi = max(0, j - h), min(ntr - 1, j + h + 1)
            jump = sum(d[i][lo:hi])
            side = [v for v in d[i][max(0, lo - trend_pairs):lo] + d[i][hi:hi + trend_pairs]
                    if np.isfinite(v)]
            trend = float(np.median(side)) if side else 0.0
            out[i, j] = abs(jump - trend * (hi - lo)) * 0.5 * (per_m[i, j] + per_m[i, j + 1])
    return out


def test_a_step_on_a_dipping_bed_reads_its_throw():
    # beds dipping 2 m per trace; a 12 m step between traces 20 and 21; 4 m per sample
    x = np.arange(40, dtype=float)
    y0 = np.tile(2.0 * x, (5, 1)) + np.where(x > 20, 12.0, 0.0)
    off = pair_offsets(y0, 0.25, width=3)
    assert off[:, 20] == pytest.approx(3.0)            # 12 m / 4 m per sample
    # away from the step the trend is removed exactly
    assert np.abs(off[:, :17]).max() == pytest.approx(0.0, abs=1e-12)
    assert np.abs(off[:, 24:]).max() == pytest.approx(0.0, abs=1e-12)
    # the pixels on either side of the step carry it, and one trace further too
    pix = pixel_offsets(y0, 0.25, width=3)
    assert pix.shape == y0.shape
    assert (pix[:, 19:23] >= 3.0 - 1e-9).all()


def test_a_fault_zone_spread_over_three_pairs_reads_whole_in_a_three_pair_window():
    x = np.arange(30, dtype=float)
    ramp = np.clip(x - 13, 0, 3) * 4.0                 # 12 m over pairs 13, 14, 15
    y0 = np.tile(ramp, (3, 1))
    assert pair_offsets(y0, 1.0, width=3)[:, 14] == pytest.approx(12.0)
    assert pair_offsets(y0, 1.0, width=1)[:, 14] == pytest.approx(4.0)


def test_against_a_slow_reference_with_holes_and_varying_scale():
    rng = np.random.default_rng(3)
    y0 = np.cumsum(rng.normal(1.0, 3.0, (6, 25)), axis=1)
    y0[2, 5:8] = np.nan
    y0[4, :] = np.nan
    per_m = rng.uniform(0.2, 0.5, y0.shape)
    for width in (1, 3, 5):
        got = pair_offsets(y0, per_m, width=width, trend_pairs=4)
        want = _slow_pair_offsets(y0, per_m, width, 4)
        np.testing.assert_allclose(got, want, equal_nan=True)


def test_no_rock_reads_no_offset_and_bad_shapes_are_refused():
    y0 = np.full((3, 10), np.nan)
    assert (pixel_offsets(y0, 1.0) == 0).all()
    with pytest.raises(ValueError, match="odd"):
        pair_offsets(np.zeros((2, 5)), 1.0, width=2)
    with pytest.raises(ValueError, match="traces"):
        pair_offsets(np.zeros((2, 1)), 1.0)
