"""Scores against scikit-learn, hand-built tolerance cases, a brute-force reference, errors."""

from __future__ import annotations

import numpy as np
import pytest
from sklearn.metrics import (
    average_precision_score,
    f1_score,
    jaccard_score,
    precision_score,
    recall_score,
)

from demseis.errors import InputError
from demseis.evaluation.scoring import count_samples, default_thresholds, score


def _sk(truth, pred_bin, zd=0.0):
    t, p = truth.ravel().astype(int), pred_bin.ravel().astype(int)
    return (precision_score(t, p, zero_division=zd), recall_score(t, p, zero_division=zd),
            f1_score(t, p, zero_division=zd), jaccard_score(t, p, zero_division=zd))


@pytest.mark.parametrize("seed", range(6))
@pytest.mark.parametrize("binary", [True, False])
def test_tolerance0_equals_sklearn_on_random_masks(seed, binary):
    rng = np.random.default_rng(seed)
    shape = (int(rng.integers(1, 5)), int(rng.integers(5, 40)), int(rng.integers(5, 40)))
    truth = rng.random(shape) < rng.uniform(0.02, 0.5)
    pred = rng.random(shape)
    if binary:
        pred = (pred < rng.uniform(0.05, 0.6)).astype(np.uint8)
    res = score(pred, truth, threshold=0.5)
    p, r, f, j = _sk(truth, pred >= 0.5)
    assert res.precision == pytest.approx(p, abs=1e-12)
    assert res.recall == pytest.approx(r, abs=1e-12)
    assert res.f1 == pytest.approx(f, abs=1e-12)
    assert res.iou == pytest.approx(j, abs=1e-12)
    assert res.tp == res.tp_truth
    assert res.tp + res.fp == int((pred >= 0.5).sum()) and res.tp + res.fn == int(truth.sum())
    for i in range(shape[0]):  # per-sample values are sklearn on each sample
        p, r, f, j = _sk(truth[i], pred[i] >= 0.5)
        ps = res.per_sample
        assert (ps["precision"][i], ps["recall"][i], ps["f1"][i], ps["iou"][i]) == \
            pytest.approx((p, r, f, j), abs=1e-12)


@pytest.mark.parametrize("zd", [0.0, 1.0])
@pytest.mark.parametrize("case", ["no_pred", "no_truth", "neither"])
def test_zero_division_matches_sklearn(zd, case):
    rng = np.random.default_rng(1)
    truth = rng.random((9, 9)) < 0.3
    pred = (rng.random((9, 9)) < 0.3).astype(float)
    if case in ("no_pred", "neither"):
        pred[:] = 0
    if case in ("no_truth", "neither"):
        truth[:] = False
    res = score(pred, truth, zero_division=zd)
    assert (res.precision, res.recall, res.f1, res.iou) == pytest.approx(_sk(truth, pred >= .5, zd))


def test_threshold_is_inclusive_and_float_dtypes_agree():
    truth = np.array([[1, 0, 1, 0]])
    pred32 = np.array([[0.3, 0.3, 0.29, 0.9]], np.float32)
    r = score(pred32, truth, threshold=0.3)
    assert (r.tp, r.fp, r.fn) == (1, 2, 1)
    assert score(pred32.astype(np.float64), truth, threshold=0.3).tp == 1


def test_average_precision_matches_sklearn():
    rng = np.random.default_rng(5)
    truth = rng.random((4, 30, 30)) < 0.15
    raw = np.clip(rng.random(truth.shape) * 0.7 + 0.3 * truth, 0, 1)
    # every distinct value on the threshold grid: exact agreement
    q = np.clip(np.round(raw * 100) / 100, 0.01, 0.99)
    assert score(q, truth).ap == pytest.approx(average_precision_score(truth.ravel(), q.ravel()),
                                               abs=1e-12)
    # continuous scores: differs only by the threshold discretisation (stated bound 0.01)
    assert abs(score(raw, truth).ap - average_precision_score(truth.ravel(), raw.ravel())) < 0.01


def test_ods_ois_against_brute_force():
    rng = np.random.default_rng(7)
    truth = rng.random((3, 16, 16)) < 0.2
    pred = np.clip(rng.random(truth.shape) * 0.8 + 0.25 * truth, 0, 1)
    thr = default_thresholds(19)
    res = score(pred, truth, tolerance_px=1.0, thresholds=thr)
    f_dataset = [score(pred, truth, threshold=t, tolerance_px=1.0).f1 for t in thr]
    assert res.ods_f1 == pytest.approx(max(f_dataset), abs=1e-12)
    assert res.ods_threshold == pytest.approx(thr[int(np.argmax(f_dataset))])
    per = [max(score(pred[i], truth[i], threshold=t, tolerance_px=1.0).f1 for t in thr)
           for i in range(3)]
    assert res.ois_f1 == pytest.approx(np.mean(per), abs=1e-12)
    assert np.allclose(res.f1_curve, f_dataset)


# ---- tolerance -------------------------------------------------------------------------------

def _vline(col, h=10, w=12):
    a = np.zeros((h, w), np.uint8)
    a[:, col] = 1
    return a


def test_tolerance_shifted_line():
    truth = _vline(5)
    pred = _vline(6).astype(float)
    assert score(pred, truth).f1 == 0.0
    r = score(pred, truth, tolerance_px=1)
    assert (r.precision, r.recall, r.f1, r.iou) == (1.0, 1.0, 1.0, 1.0)
    assert score(_vline(7), truth, tolerance_px=1).f1 == 0.0
    assert score(_vline(7), truth, tolerance_px=2).f1 == 1.0


def test_tolerance_is_euclidean():
    truth = np.zeros((7, 7), np.uint8)
    truth[3, 3] = 1
    pred = np.zeros((7, 7))
    pred[4, 4] = 1.0  # diagonal neighbour: distance sqrt(2)
    assert score(pred, truth, tolerance_px=1.0).f1 == 0.0
    assert score(pred, truth, tolerance_px=1.42).f1 == 1.0


def test_tolerance_asymmetric_hand_counts():
    truth = _vline(5)  # 10 labelled pixels
    pred = np.zeros_like(truth, dtype=float)
    pred[:, 3:8] = 0.9  # a 5-wide band: columns 3..7
    r = score(pred, truth, tolerance_px=1)
    # predicted pixels within 1 px of column 5: columns 4, 5, 6 -> 30 of 50
    assert (r.tp, r.fp) == (30, 20)
    assert r.recall == 1.0 and r.fn == 0
    assert r.precision == pytest.approx(0.6)
    assert r.f1 == pytest.approx(2 * 0.6 / 1.6)
    assert r.iou == pytest.approx(r.f1 / (2 - r.f1))
    # half the line predicted (top 5 rows) with tol 1 finds 6 labelled pixels (row 5 is 1 away)
    pred2 = np.zeros_like(pred)
    pred2[:5, 5] = 1
    r2 = score(pred2, truth, tolerance_px=1)
    assert (r2.tp_truth, r2.fn, r2.precision) == (6, 4, 1.0)


def test_tolerance_does_not_cross_samples():
    truth = np.zeros((2, 6, 6), np.uint8)
    truth[0, :, 2] = 1
    pred = np.zeros((2, 6, 6))
    pred[1, :, 2] = 1  # same place, other sample
    r = score(pred, truth, tolerance_px=3)
    assert r.tp == 0 and r.tp_truth == 0


def _brute_counts(pred, truth, thr, tol):
    """Obvious O(n^2) reference of the tolerance matching on one sample."""
    pos = np.argwhere(pred >= thr)
    lab = np.argwhere(truth)

    def near(a, b):
        if len(a) == 0 or len(b) == 0:
            return np.zeros(len(a), bool)
        d = np.sqrt(((a[:, None, :] - b[None, :, :]) ** 2).sum(-1))
        return (d <= tol).any(1)

    return len(pos), len(lab), int(near(pos, lab).sum()), int(near(lab, pos).sum())


@pytest.mark.parametrize("tol", [0.0, 1.0, 1.5, 2.3])
def test_tolerance_matches_brute_force_and_sweep(tol):
    rng = np.random.default_rng(int(tol * 10))
    truth = rng.random((3, 14, 17)) < 0.08
    pred = np.round(rng.random(truth.shape), 2)
    thr = default_thresholds(9)
    c = count_samples(pred, truth, threshold=0.3, tolerance_px=tol, thresholds=thr)
    for i in range(3):
        assert (c.n_pred[i], c.n_truth[i], c.tp[i], c.tp_truth[i]) == \
            _brute_counts(pred[i], truth[i], 0.3, tol)
        for k, t in enumerate(thr):  # sweep (histogram + max filter) == distance transforms
            n_pred, _, tp, tp_truth = _brute_counts(pred[i], truth[i], t, tol)
            assert (c.curve_n_pred[i, k], c.curve_tp[i, k], c.curve_tp_truth[i, k]) == \
                (n_pred, tp, tp_truth)


def test_2d_input_and_empty_truth_sample():
    truth = np.zeros((2, 5, 5), np.uint8)
    truth[0, 2, :] = 1
    pred = truth.astype(float)
    r = score(pred, truth)
    assert r.f1 == 1.0 and r.n_samples == 2
    assert np.isclose(r.ois_f1, 1.0)  # mean over the labelled sample only
    assert score(pred[0], truth[0]).f1 == 1.0


# ---- errors ----------------------------------------------------------------------------------

def test_errors_name_the_problem():
    t = np.zeros((2, 4, 4), np.uint8)
    with pytest.raises(InputError, match="shape"):
        score(np.zeros((2, 4, 5)), t)
    bad = np.zeros((2, 4, 4))
    bad[1, 2, 2] = np.nan
    with pytest.raises(InputError, match="NaN.*sample 1"):
        score(bad, t)
    with pytest.raises(InputError, match=r"\[0, 1\]"):
        score(np.full((2, 4, 4), 3.0), t)
    with pytest.raises(InputError, match="binary"):
        score(np.zeros((2, 4, 4)), t + 2)
    with pytest.raises(InputError, match="empty"):
        score(np.zeros((0, 4, 4)), np.zeros((0, 4, 4)))
    with pytest.raises(InputError, match="threshold"):
        score(np.zeros((2, 4, 4)), t, threshold=0)
    with pytest.raises(InputError, match="tolerance_px"):
        score(np.zeros((2, 4, 4)), t, tolerance_px=-1)
    with pytest.raises(InputError, match=r"\(N, H, W\)"):
        score(np.zeros(4), np.zeros(4))


from hypothesis import given, settings  # noqa: E402
from hypothesis import strategies as st  # noqa: E402
from hypothesis.extra.numpy import arrays  # noqa: E402


@settings(max_examples=60, deadline=None)
@given(data=st.data(), zd=st.sampled_from([0.0, 1.0]))
def test_property_tolerance0_equals_sklearn(data, zd):
    shape = data.draw(st.tuples(st.integers(1, 3), st.integers(1, 6), st.integers(1, 6)))
    truth = data.draw(arrays(np.bool_, shape))
    pred = data.draw(arrays(np.uint8, shape, elements=st.integers(0, 1)))
    r = score(pred, truth, zero_division=zd)
    assert (r.precision, r.recall, r.f1, r.iou) == pytest.approx(_sk(truth, pred == 1, zd))


def test_chance_ap_is_what_random_scores_get():
    rng = np.random.default_rng(11)
    truth = np.zeros((20, 40, 40), np.uint8)
    truth[:, :, 13] = 1
    truth[:, 25, :] = 1
    pred = rng.random(truth.shape)
    for tol in (0, 2):
        r = score(pred, truth, tolerance_px=tol)
        from scipy import ndimage

        near = np.mean([(ndimage.distance_transform_edt(1 - t) <= tol).mean() for t in truth])
        assert r.chance_ap == pytest.approx(near)
        assert r.ap == pytest.approx(r.chance_ap, rel=0.05)
