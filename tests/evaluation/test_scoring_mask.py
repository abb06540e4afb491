"""Scoring a prediction against a hand-picked mask (``demseis score PRED MASK``,
``demseis.score(pred, "mask.png")``): the same protocol and report as against a store, checked
against scikit-learn at tolerance 0 and a hand-worked example at tolerance 2; resizing; errors."""

from __future__ import annotations

import json

import numpy as np
import pytest
import segyio
from PIL import Image
from sklearn.metrics import (average_precision_score, f1_score, jaccard_score, precision_score,
                             recall_score)

import demseis
from demseis.cli import main
from demseis.errors import InputError
from demseis.evaluation.store_scoring import score_mask
from tests.evaluation._helpers import make_store


def _png(path, mask):
    """Black picks on white, as an interpreter's export."""
    Image.fromarray(np.where(mask, 0, 255).astype(np.uint8)).save(path)
    return path


def _picks():
    """A vertical fault (column 10, 20 px) and a short horizontal pick (row 5, cols 3..8)."""
    m = np.zeros((20, 30), bool)
    m[:, 10] = True
    m[5, 3:9] = True
    return m


def test_tolerance_2_hand_worked(tmp_path):
    """The prediction is the vertical fault one column off (20 px at 0.9). At 2 px every
    predicted pixel is matched (precision 20/20); the 20 vertical picks are found, the
    horizontal pick's pixels lie 3..8 columns from the prediction and are not: recall 20/26,
    F1 = 2 * 1 * (20/26) / (1 + 20/26) = 40/46."""
    pred = np.zeros((20, 30), np.float32)
    pred[:, 11] = 0.9
    r = demseis.score(pred, _png(tmp_path / "m.png", _picks()), tolerance_px=2)
    o = r.overall
    assert (o.tp, o.fp, o.tp_truth, o.fn) == (20, 0, 20, 6)
    assert o.precision == 1.0 and o.recall == pytest.approx(20 / 26)
    assert o.f1 == pytest.approx(40 / 46) and o.iou == pytest.approx(20 / 26)
    # a column 2 further off: the vertical picks lie 3 away, nothing matches
    far = np.roll(pred, 2, axis=1)
    assert demseis.score(far, _picks(), tolerance_px=2).overall.f1 == 0.0
    assert demseis.score(pred, _picks(), tolerance_px=0).overall.f1 == 0.0


@pytest.mark.parametrize("kind", ["png", "npy", "sgy"])
def test_tolerance_0_equals_sklearn(tmp_path, kind):
    rng = np.random.default_rng(7)
    truth = rng.random((3, 24, 32)) < 0.08
    # scores on the sweep's grid (k / 100), so that AP equals scikit-learn's exactly
    pred = (rng.integers(1, 100, truth.shape) / 100.0 * np.where(truth, 1.0, 0.7)).round(2)
    pred = pred.astype(np.float64)
    if kind == "npy":  # the stack in one file
        np.save(tmp_path / "m.npy", truth.astype(np.uint8))
        cases = [(tmp_path / "m.npy", pred, truth)]
    else:  # one section per file
        cases = []
        for i in range(3):
            if kind == "png":
                path = _png(tmp_path / f"m{i}.png", truth[i])
            else:
                path = tmp_path / f"m{i}.sgy"
                segyio.tools.from_array2D(str(path), np.ascontiguousarray(truth[i].T, np.float32),
                                          format=5)
            cases.append((path, pred[i], truth[i]))
    for m, p, t in cases:
        o = demseis.score(p, m, threshold=0.5, tolerance_px=0).overall
        y, yp = t.ravel(), np.ravel(p) >= 0.5
        assert o.precision == pytest.approx(precision_score(y, yp))
        assert o.recall == pytest.approx(recall_score(y, yp))
        assert o.f1 == pytest.approx(f1_score(y, yp))
        assert o.iou == pytest.approx(jaccard_score(y, yp))
        assert o.ap == pytest.approx(average_precision_score(y, np.ravel(p)), abs=1e-9)


def test_mask_report_has_the_store_reports_fields(tmp_path, capsys):
    fault = make_store(tmp_path / "s.zarr")
    pred = np.clip(fault * 0.7 + 0.1, 0, 1).astype(np.float32)
    np.save(tmp_path / "p.npy", pred)
    np.save(tmp_path / "m.npy", fault)
    assert main(["score", str(tmp_path / "p.npy"), str(tmp_path / "s.zarr"), "--tolerance", "1",
                 "--out-prefix", str(tmp_path / "store")]) == 0
    assert main(["score", str(tmp_path / "p.npy"), str(tmp_path / "m.npy"), "--tolerance", "1",
                 "--out-prefix", str(tmp_path / "mask")]) == 0
    out = capsys.readouterr().out
    assert "mask " + str(tmp_path / "m.npy") in out and "ODS F1" in out
    a = json.loads((tmp_path / "store.json").read_text())
    b = json.loads((tmp_path / "mask.json").read_text())
    assert set(a) <= set(b) and b["store"] is None and b["mask"] == str(tmp_path / "m.npy")
    assert a["overall"] == b["overall"]  # the same labels: the same scores
    assert [set(r) for r in b["groups"]] == [set(a["groups"][0])]
    assert (tmp_path / "mask.csv").read_text().splitlines()[0] == \
        (tmp_path / "store.csv").read_text().splitlines()[0]


def test_segy_prediction_against_png_mask_cli(tmp_path, capsys):
    m = _picks()
    pred = np.where(m, 0.8, 0.1).astype(np.float32)
    segyio.tools.from_array2D(str(tmp_path / "p.sgy"), np.ascontiguousarray(pred.T), format=5)
    assert main(["score", str(tmp_path / "p.sgy"), str(_png(tmp_path / "m.png", m)),
                 "--tolerance", "2"]) == 0
    capsys.readouterr()
    rep = json.loads((tmp_path / "p.score.json").read_text())
    assert rep["overall"]["f1"] == 1.0 and rep["overall"]["tolerance_px"] == 2


def test_resize_puts_the_prediction_on_the_mask_grid(tmp_path, capsys):
    m = np.zeros((40, 60), bool)
    m[:, 20] = True
    coarse = np.zeros((20, 30), np.float32)
    coarse[:, 10] = 1.0  # the same fault at half the sampling
    np.save(tmp_path / "p.npy", coarse)
    np.save(tmp_path / "m.npy", m)
    assert main(["score", str(tmp_path / "p.npy"), str(tmp_path / "m.npy")]) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and "(20, 30)" in err and "(40, 60)" in err and "--resize" in err
    assert main(["score", str(tmp_path / "p.npy"), str(tmp_path / "m.npy"), "--resize",
                 "--tolerance", "1"]) == 0
    capsys.readouterr()
    assert json.loads((tmp_path / "p.score.json").read_text())["overall"]["f1"] == 1.0
    r = score_mask(coarse, m, resize=True, threshold=0.5)
    assert r.counts.n_pixels[0] == 40 * 60


def test_bad_input_exits_2_with_one_line(tmp_path, capsys):
    m = _picks()
    _png(tmp_path / "m.png", m)
    np.save(tmp_path / "p.npy", np.zeros((20, 30), np.float32))
    np.save(tmp_path / "p3.npy", np.zeros((2, 20, 30), np.float32))
    np.save(tmp_path / "logit.npy", np.full((20, 30), 3.0, np.float32))
    Image.fromarray(np.full((20, 30), 255, np.uint8)).save(tmp_path / "blank.png")
    (tmp_path / "notes.txt").write_text("x")
    make_store(tmp_path / "s.zarr")
    p, mask = str(tmp_path / "p.npy"), str(tmp_path / "m.png")
    cases = [([p, str(tmp_path / "none.png")], "does not exist"),
             ([str(tmp_path / "none.npy"), mask], "do not exist"),
             ([p, str(tmp_path / "blank.png")], "no fault pixels"),
             ([str(tmp_path / "p3.npy"), mask], "(2, 20, 30)"),
             ([str(tmp_path / "logit.npy"), mask], "[0, 1]"),
             ([p, str(tmp_path / "notes.txt")], "neither a store"),
             ([p, mask, "--by", "freq_hz"], "--by goes with a store"),
             ([p, mask, "--indices", "0"], "--indices goes with a store"),
             ([p, str(tmp_path / "s.zarr"), "--resize"], "--resize goes with a mask")]
    for args, message in cases:
        assert main(["score", *args]) == 2, args
        err = capsys.readouterr().err.strip()
        assert err.count("\n") == 0 and message in err, (args, err)
    assert not list(tmp_path.glob("*.score.*"))  # nothing written
    with pytest.raises(InputError, match="by: a mask"):
        demseis.score(np.zeros((20, 30)), mask, by=("freq_hz",))
