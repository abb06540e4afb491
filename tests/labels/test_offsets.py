"""Reflector offsets from the reference elevation (demseis.labels.offsets)."""

from __future__ import annotations

import numpy as np
import pytest

from demseis.labels.offsets import (LABEL_NOT_SHOWN, OFFSET_NOT_LABELLED, offset_disagreement,
                                    pair_offsets, pixel_offsets)


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


def _slow_disagreement(fault, pair, min_samples, near_px):
    """Pixel by pixel: a pixel's offset is the largest of the pairs (j-2, j-1) to (j+1, j+2),
    a step's centre a pair at least ``min_samples`` and no smaller than its neighbours, and the
    Chebyshev distance to the nearest shown or labelled pixel decides."""
    h, w = fault.shape
    p = np.nan_to_num(pair)
    pad = np.zeros((h, w + 1))
    pad[:, 1:w] = p                           # pad[:, k] is the pair (k - 1, k)
    shown = np.zeros((h, w), bool)
    step = np.zeros((h, w), bool)
    for r in range(h):
        for c in range(w):
            pairs = [p[r, k] for k in range(c - 2, c + 2) if 0 <= k < w - 1]
            shown[r, c] = max(pairs) >= min_samples
            here = pad[r, c + 1]              # the pair (c, c + 1); 0 at the last column
            step[r, c] = here >= min_samples and here >= pad[r, c] and \
                here >= (pad[r, c + 2] if c + 2 <= w else 0.0)
    lab = fault > 0
    out = np.zeros((h, w), np.uint8)
    for r in range(h):
        for c in range(w):
            win = (slice(max(r - near_px, 0), r + near_px + 1),
                   slice(max(c - near_px, 0), c + near_px + 1))
            if lab[r, c] and not shown[win].any():
                out[r, c] = 1
            elif step[r, c] and not lab[win].any():
                out[r, c] = 2
    return out


def test_disagreement_of_a_half_shown_fault_and_an_unlabelled_step():
    """A labelled fault at column 20 whose upper half offsets the reflectors by 3 samples
    (spread over three pairs, as a three-pair window reads one step), a step of 2 samples
    with no label, and a 0.5-sample offset (below the threshold)."""
    fault = np.zeros((40, 40), np.uint8)
    pair = np.zeros((40, 39))
    fault[5:36, 20] = 1
    pair[5:21, 19:22] = 3.0     # the pairs (19, 20) to (21, 22)
    pair[10:31, 5] = 2.0        # an offset no label explains, between traces 5 and 6
    pair[:, 30] = 0.5           # too small to be seen
    got = offset_disagreement(fault, pair, min_samples=1.0, near_px=2)
    assert not got[5:23, 20].any()                # shown, or within 2 px of a shown pixel
    assert (got[23:36, 20] == LABEL_NOT_SHOWN).all()
    assert (got[10:31, 5] == OFFSET_NOT_LABELLED).all()
    # the labelled step's fringe (pixels 17 to 23 read it through the window) is not a step
    assert int((got > 0).sum()) == 13 + 21
    exact = offset_disagreement(fault, pair, min_samples=1.0, near_px=0)
    assert (exact[21:36, 20] == LABEL_NOT_SHOWN).all()
    assert (exact[5:21, 19] == OFFSET_NOT_LABELLED).all()   # a step beside the label
    np.testing.assert_array_equal(offset_disagreement(fault, pair, min_samples=4.0)
                                  [fault > 0], LABEL_NOT_SHOWN)


@pytest.mark.parametrize("near_px", [0, 1, 2, 3])
def test_disagreement_against_a_slow_reference(near_px):
    rng = np.random.default_rng(near_px)
    fault = (rng.random((30, 35)) < 0.08).astype(np.uint8)
    pair = rng.exponential(0.25, (30, 34))
    pair[rng.random((30, 34)) < 0.05] = np.nan  # no rock
    got = offset_disagreement(fault, pair, min_samples=1.0, near_px=near_px)
    np.testing.assert_array_equal(got, _slow_disagreement(fault, pair, 1.0, near_px))
    assert {1, 2} <= set(np.unique(got).tolist())
    with pytest.raises(ValueError, match="shape"):
        offset_disagreement(fault, pair[:, :-1], min_samples=1.0)
