"""Scoring against a tiny demseis store: grouping by parameters, the CLI, store errors."""

from __future__ import annotations

import csv
import json

import numpy as np
import pytest
import zarr

from demseis.errors import InputError, StoreError
from demseis.cli import main
from demseis.datasets.read import open_truth
from demseis.evaluation.grouping import group_rows, score_store_counts
from demseis.evaluation.scoring import score
from tests.evaluation._helpers import make_store


def test_store_counts_and_grouping(tmp_path):
    fault = make_store(tmp_path / "s.zarr")
    store = open_truth(str(tmp_path / "s.zarr"))
    rng = np.random.default_rng(3)
    pred = np.clip(fault * 0.6 + rng.random(fault.shape) * 0.5, 0, 1).astype(np.float32)
    counts, sample = score_store_counts(pred, store, tolerance_px=1, block=5)
    assert np.array_equal(sample, np.arange(12))
    direct = score(pred, fault, tolerance_px=1)
    params = {k: v[sample] for k, v in store.params.items()}
    rows = group_rows(counts, params, ["freq_hz", "snr_db", "dip_deg"], bins=3)
    assert rows[0]["by"] == "all" and rows[0]["f1"] == pytest.approx(direct.f1)
    freq = [r for r in rows if r["by"] == "freq_hz"]
    assert [r["group"] for r in freq] == ["20", "40", "60"]
    assert sum(r["n_samples"] for r in freq) == 12
    for r in freq:  # each group equals scoring its samples directly
        m = params["freq_hz"] == r["lo"]
        d = score(pred[m], fault[m], tolerance_px=1)
        assert (r["precision"], r["recall"], r["iou"]) == pytest.approx(
            (d.precision, d.recall, d.iou))
    snr = [r["group"] for r in rows if r["by"] == "snr_db"]
    assert snr == ["10", "inf"]
    dip = [r for r in rows if r["by"] == "dip_deg"]
    assert len(dip) == 3 and sum(r["n_samples"] for r in dip) == 12
    assert dip[0]["group"].startswith("[50") and dip[-1]["group"].endswith("80]")


def test_incomplete_shards_are_skipped_and_indices(tmp_path):
    fault = make_store(tmp_path / "s.zarr", done=[1, 0, 1])
    store = open_truth(str(tmp_path / "s.zarr"))
    pred = fault.astype(np.float32)
    counts, sample = score_store_counts(pred, store)
    assert list(sample) == [0, 1, 2, 3, 8, 9, 10, 11]
    idx = np.array([9, 2, 0])
    c2, s2 = score_store_counts(pred[idx], store, indices=idx)
    assert list(s2) == [0, 2, 9] and c2.n_truth.sum() == fault[[0, 2, 9]].sum()
    with pytest.raises(StoreError, match="not complete"):
        score_store_counts(pred[[4]], store, indices=np.array([4]))
    with pytest.raises(InputError, match="12"):
        score_store_counts(pred[:5], store)


def test_store_errors(tmp_path):
    make_store(tmp_path / "empty.zarr", done=[0, 0, 0])
    with pytest.raises(StoreError, match="empty"):
        open_truth(str(tmp_path / "empty.zarr"))
    make_store(tmp_path / "nolab.zarr", with_fault=False)
    with pytest.raises(StoreError, match="'fault'"):
        open_truth(str(tmp_path / "nolab.zarr"))
    zarr.open_group(str(tmp_path / "foreign.zarr"), mode="w")
    with pytest.raises(StoreError, match="not a demseis store|not written by demseis"):
        open_truth(str(tmp_path / "foreign.zarr"))
    with pytest.raises(StoreError, match="does not exist"):
        open_truth(str(tmp_path / "missing.zarr"))


def test_cli_score_writes_table_csv_json(tmp_path, capsys):
    fault = make_store(tmp_path / "s.zarr")
    pred = np.roll(fault, 1, axis=2).astype(np.float32)  # every line one pixel off
    np.save(tmp_path / "pred.npy", pred)
    rc = main(["score", str(tmp_path / "pred.npy"), str(tmp_path / "s.zarr"), "--tolerance",
               "1", "--by", "freq_hz,snr_db,dip_deg", "--per-sample"])
    out = capsys.readouterr().out
    assert rc == 0
    assert "freq_hz" in out and "snr_db" in out and "ODS" in out
    rep = json.loads((tmp_path / "pred.score.json").read_text())
    assert rep["overall"]["f1"] == 1.0 and rep["overall"]["tolerance_px"] == 1.0
    assert len(rep["per_sample"]) == 12 and rep["per_sample"][1]["snr_db"] == 10.0
    assert rep["per_sample"][0]["snr_db"] == "inf"
    with open(tmp_path / "pred.score.csv") as fh:
        rows = list(csv.DictReader(fh))
    assert rows[0]["by"] == "all" and {r["by"] for r in rows} == {"all", "freq_hz", "snr_db",
                                                                   "dip_deg"}
    assert (tmp_path / "pred.score.samples.csv").exists()
    # exact overlap gives 0 for the shifted lines
    rc = main(["score", str(tmp_path / "pred.npy"), str(tmp_path / "s.zarr"), "--out-prefix",
               str(tmp_path / "exact")])
    assert rc == 0
    assert json.loads((tmp_path / "exact.json").read_text())["overall"]["f1"] == 0.0


def test_cli_score_zarr_predictions(tmp_path):
    fault = make_store(tmp_path / "s.zarr")
    zarr.create_array(str(tmp_path / "p.zarr"), data=fault.astype(np.float32), chunks=(1, 24, 20))
    rc = main(["score", str(tmp_path / "p.zarr"), str(tmp_path / "s.zarr")])
    assert rc == 0
    assert json.loads((tmp_path / "p.score.json").read_text())["overall"]["iou"] == 1.0


@pytest.mark.parametrize("case", ["shape", "nan", "empty", "nolabels", "by", "range"])
def test_cli_errors_exit_2(tmp_path, capsys, case):
    fault = make_store(tmp_path / "s.zarr", done=[0, 0, 0] if case == "empty" else None,
                       with_fault=case != "nolabels")
    pred = fault.astype(np.float32)
    if case == "shape":
        pred = pred[:, :, :-1]
    if case == "nan":
        pred[5, 3, 3] = np.nan
    if case == "range":
        pred *= 255
    np.save(tmp_path / "pred.npy", pred)
    extra = ["--by", "colour"] if case == "by" else []
    rc = main(["score", str(tmp_path / "pred.npy"), str(tmp_path / "s.zarr"), *extra])
    err = capsys.readouterr().err
    assert rc == 2
    assert err.startswith("demseis: error:") and len(err.strip().splitlines()) == 1
    expect = {"shape": "pixels", "nan": "NaN", "empty": "empty", "nolabels": "'fault'",
              "by": "colour", "range": "[0, 1]"}[case]
    assert expect in err
    assert not (tmp_path / "pred.score.json").exists()


def test_grouping_rule_swept_values_vs_drawn_values():
    from demseis.evaluation.scoring import SampleCounts

    n = 6
    z = np.zeros(n, np.int64)
    counts = SampleCounts(n_pred=z + 1, n_truth=z + 1, tp=z + 1, tp_truth=z + 1,
                          n_near_truth=z + 1, n_pixels=z + 4, curve_n_pred=np.ones((n, 1), int),
                          curve_tp=np.ones((n, 1), int), curve_tp_truth=np.ones((n, 1), int),
                          thresholds=np.array([0.5]), threshold=0.5, tolerance_px=0.0)
    params = {"dip_deg": np.repeat(np.float32([42.1659, 45.0286, 56.9102]), 2),
              "swept": np.float32([45, 45, 60, 60, 0.1, 0.1])}
    rows = group_rows(counts, params, ["dip_deg", "swept"], bins=2)
    assert [r["group"] for r in rows if r["by"] == "dip_deg"] == ["[42.2, 49.5)", "[49.5, 56.9]"]
    assert [r["group"] for r in rows if r["by"] == "swept"] == ["0.1", "45", "60"]
