"""demseis.learning.train: the shared U-Net training loop (fixed steps), prediction, errors;
and benchmarks/learnability.py end to end on a tiny store."""

from __future__ import annotations

import json
import runpy
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("torch")

from demseis.errors import InputError  # noqa: E402
from demseis.learning.train import build_unet, predict_sections, train_unet  # noqa: E402
from tests.evaluation._helpers import toy_store  # noqa: E402

BENCH = Path(__file__).resolve().parents[2] / "benchmarks" / "learnability.py"


def test_train_unet_fixed_steps_is_repeatable(tmp_path):
    store = tmp_path / "tiny.zarr"
    toy_store(store)
    kw = dict(steps=3, crop=16, batch=4, base=4, threads=1, device="cpu", log=None)
    m1, info = train_unet(store, **kw)
    m2, _ = train_unet(store, **kw)
    assert info["steps"] == 3 and info["device"] == "cpu" and info["n_runs"] >= 1
    x = np.random.default_rng(0).normal(size=(2, 30, 30)).astype(np.float32)
    p1, p2 = predict_sections(m1, x), predict_sections(m2, x)
    assert p1.shape == (2, 30, 30) and 0 <= p1.min() and p1.max() <= 1
    np.testing.assert_array_equal(p1, p2)  # same seed, same threads: same weights
    with pytest.raises(InputError, match="exactly one of steps or minutes"):
        train_unet(store, crop=16, log=None)
    with pytest.raises(InputError, match="crop"):
        train_unet(store, steps=1, crop=18, log=None)
    with pytest.raises(InputError, match="sections must be"):
        predict_sections(build_unet(4), x[0])


def test_pos_weight_is_the_loss_weight_and_keeps_the_crops(tmp_path):
    """A given pos_weight replaces the measured ratio in the loss and nothing else: the measured
    ratio given explicitly trains the same weights, another value other weights."""
    store = tmp_path / "tiny.zarr"
    toy_store(store)
    kw = dict(steps=3, crop=16, batch=4, base=4, threads=1, device="cpu", log=None)
    m_auto, info = train_unet(store, **kw)
    ratio = info["pos_weight"]
    assert ratio > 1  # faults are rare in the toy store
    m_same, info_same = train_unet(store, pos_weight=float(ratio), **kw)
    m_one, info_one = train_unet(store, pos_weight=1.0, **kw)
    assert info_one["pos_weight"] == 1.0 and info_same["pos_weight"] == ratio

    def params(m):
        return np.concatenate([p.detach().numpy().ravel() for p in m.parameters()])

    # the ratio is recorded rounded to 2 decimals: the same loss and weights to that precision
    assert info_same["final_loss"] == pytest.approx(info["final_loss"], rel=1e-3)
    same = np.abs(params(m_same) - params(m_auto)).max()
    other = np.abs(params(m_one) - params(m_auto)).max()
    assert same < 1e-4 < other
    # the weighted cross-entropy of rare faults is larger than the unweighted one
    assert info_one["final_loss"] < info["final_loss"]
    for bad in (0.0, -1.0, float("nan")):
        with pytest.raises(InputError, match="pos_weight"):
            train_unet(store, pos_weight=bad, **kw)


def test_learnability_benchmark_prints_one_json_line(tmp_path, capsys):
    store = tmp_path / "tiny.zarr"
    toy_store(store)
    bench_main = runpy.run_path(str(BENCH))["main"]
    assert bench_main([str(store), "--steps", "2", "--crop", "16", "--batch", "4", "--base", "4",
                     "--threads", "1", "--test-fraction", "0.4", "--device", "cpu"]) == 0
    captured = capsys.readouterr()
    line = captured.out.strip().splitlines()
    assert len(line) == 1
    assert "2/2" in captured.err and "step" in captured.err  # the training bar, on stderr
    out = json.loads(line[0])
    assert out["steps"] == 2 and out["device"] == "cpu"
    for split in ("train", "test"):
        for k in ("precision", "recall", "f1", "ap"):
            for tol in (2, 4):
                assert 0.0 <= out[f"{split}_{k}_tol{tol}"] <= 1.0  # NaN fails
    assert out["test_runs"] >= 1 and out["train_runs"] >= 1
    # the threshold chosen on the train runs: one of the 99 sweep thresholds; the best F1 over
    # the sweep bounds both the F1 at 0.5 (itself a sweep threshold) and any other threshold's
    for tol in (2, 4):
        t = out[f"train_ods_threshold_tol{tol}"]
        assert 0 < t < 1 and abs(t * 100 - round(t * 100)) < 1e-6
        assert out[f"train_ods_f1_tol{tol}"] >= out[f"train_f1_tol{tol}"] - 1e-4
        assert out[f"test_ods_f1_tol{tol}"] >= out[f"test_f1_at_train_threshold_tol{tol}"] - 1e-4
        assert out[f"test_ods_f1_tol{tol}"] >= out[f"test_f1_tol{tol}"] - 1e-4
    assert "test_recall_by_slip_tol2" not in out  # this store has no slip_m array
    assert out["ods_f1_gap_tol2"] == pytest.approx(
        out["train_ods_f1_tol2"] - out["test_f1_at_train_threshold_tol2"], abs=2e-4)


def test_learnability_benchmark_test_f1_at_train_threshold_is_read_off_the_test_curve(
        tmp_path, capsys, monkeypatch):
    """The held-out F1 at the train runs' best threshold equals a fresh score of the held-out
    predictions at that threshold (the benchmark reads it off the test F1 curve)."""
    from demseis.evaluation import score
    from demseis.learning import train as train_mod

    store = tmp_path / "tiny.zarr"
    toy_store(store)
    seen = []
    real_predict = train_mod.predict_sections

    def spy(model, sections, **kw):
        p = real_predict(model, sections, **kw)
        seen.append(p)
        return p

    monkeypatch.setattr(train_mod, "predict_sections", spy)
    bench_main = runpy.run_path(str(BENCH))["main"]
    assert bench_main([str(store), "--steps", "2", "--crop", "16", "--batch", "4", "--base", "4",
                       "--threads", "1", "--test-fraction", "0.4", "--device", "cpu"]) == 0
    out = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    from demseis.datasets import FaultSegDataset

    ds = FaultSegDataset(store, inputs=("seismic",), targets=("fault",), split="test",
                         split_fractions=(0.6, 0.0, 0.4))
    truth = np.stack([ds[i][1].numpy() > 0 for i in range(len(ds))])
    assert len(seen) == 2 and seen[1].shape == truth.shape
    for tol in (2, 4):
        t = out[f"train_ods_threshold_tol{tol}"]
        direct = score(seen[1], truth, threshold=t, tolerance_px=tol).f1
        assert out[f"test_f1_at_train_threshold_tol{tol}"] == pytest.approx(direct, abs=1e-4)


def test_learnability_benchmark_train_runs_subset_keeps_the_held_out_runs(tmp_path, capsys):
    """--train-runs N trains and scores the first N train runs; the held-out runs stay the same."""
    store = tmp_path / "tiny.zarr"
    toy_store(store)
    bench_main = runpy.run_path(str(BENCH))["main"]
    common = [str(store), "--steps", "1", "--crop", "16", "--batch", "4", "--base", "4",
              "--threads", "1", "--test-fraction", "0.4", "--device", "cpu"]
    assert bench_main(common) == 0
    full = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    assert full["train_runs"] >= 2, "the tiny store needs two train runs for this test"
    assert bench_main(common + ["--train-runs", "1", "--no-progress"]) == 0
    captured = capsys.readouterr()
    assert "step" not in captured.err  # --no-progress: no bar
    sub = json.loads(captured.out.strip().splitlines()[-1])
    assert sub["train_runs_used"] == 1 and sub["train_runs"] == 1
    assert sub["test_runs"] == full["test_runs"] and sub["test_samples"] == full["test_samples"]
    with pytest.raises(SystemExit, match="train runs"):
        bench_main(common + ["--train-runs", str(full["train_runs"] + 1)])


def test_learnability_save_pred_and_figure(tmp_path, capsys):
    """--save-pred keeps held-out sections with faults and their predictions; the figure script
    draws two label sets side by side and refuses files of different sections."""
    store = tmp_path / "tiny.zarr"
    toy_store(store)
    bench_main = runpy.run_path(str(BENCH))["main"]
    pred = tmp_path / "p.npz"
    assert bench_main([str(store), "--steps", "1", "--crop", "16", "--batch", "4", "--base", "4",
                       "--threads", "1", "--test-fraction", "0.4", "--device", "cpu",
                       "--save-pred", str(pred), "--save-n", "2"]) == 0
    out = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    with np.load(pred) as z:
        d = {k: z[k] for k in z.files}
    n = d["seismic"].shape[0]
    assert 1 <= n <= 2 and d["truth"].shape == d["prob"].shape == d["seismic"].shape
    assert all(d["truth"][i].any() for i in range(n))  # only sections with a fault
    assert float(d["threshold_tol2"]) == out["train_ods_threshold_tol2"]
    from demseis.datasets import FaultSegDataset

    ds = FaultSegDataset(store, inputs=("seismic",), targets=("fault",), split="test",
                         split_fractions=(0.6, 0.0, 0.4))
    for i, s in enumerate(d["sample"]):
        np.testing.assert_array_equal(d["seismic"][i], ds[int(s)][0][0].numpy())

    fig_main = runpy.run_path(str(BENCH.with_name("learnability_figure.py")))["main"]
    png = tmp_path / "f.png"
    assert fig_main([f"a={pred}", f"b={pred}", "--out", str(png)]) == 0
    assert png.stat().st_size > 1000
    other = tmp_path / "q.npz"
    np.savez(other, **{**d, "seismic": d["seismic"] + 1})
    with pytest.raises(SystemExit, match="not the same held-out sections"):
        fig_main([f"a={pred}", f"b={other}", "--out", str(png)])
    with pytest.raises(SystemExit, match="NAME=PRED.npz"):
        fig_main([str(pred), "--out", str(png)])


def test_learnability_reference_scores_against_the_other_stores_labels(tmp_path, capsys):
    """--reference REF: trained on STORE, scored against REF's labels of the same seismic; REF =
    STORE gives the figures of a plain run; another seismic is refused."""
    from scipy import ndimage

    store, thick, other = tmp_path / "a.zarr", tmp_path / "b.zarr", tmp_path / "c.zarr"
    toy_store(store)
    toy_store(thick, fault_fn=lambda f: ndimage.binary_dilation(
        f, structure=np.ones((1, 3, 3), bool)).astype(f.dtype))
    toy_store(other, seismic_fn=lambda s: s + 1.0)
    bench_main = runpy.run_path(str(BENCH))["main"]
    common = [str(store), "--steps", "1", "--crop", "16", "--batch", "4", "--base", "4",
              "--threads", "1", "--test-fraction", "0.4", "--device", "cpu", "--no-progress"]
    assert bench_main(common) == 0
    plain = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    assert bench_main(common + ["--reference", str(store)]) == 0
    same = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    pred = tmp_path / "p.npz"
    assert bench_main(common + ["--reference", str(thick), "--save-pred", str(pred)]) == 0
    ref = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    keys = [k for k in plain if k.startswith(("train_", "test_")) and k != "train_seconds"]
    assert {k: same[k] for k in keys} == {k: plain[k] for k in keys}
    assert same["reference"] == str(store) and ref["reference"] == str(thick)
    assert ref["final_loss"] == plain["final_loss"]  # the same training
    from demseis.datasets import FaultSegDataset

    ds = FaultSegDataset(thick, inputs=("seismic",), targets=("fault",), split="test",
                         split_fractions=(0.6, 0.0, 0.4))
    with np.load(pred) as z:
        for i, s in enumerate(z["sample"]):  # the saved truth is the reference's labels
            np.testing.assert_array_equal(z["truth"][i], ds[int(s)][1].numpy() > 0)
    assert ref["test_recall_tol2"] != plain["test_recall_tol2"] or \
        ref["test_precision_tol2"] != plain["test_precision_tol2"]
    with pytest.raises(SystemExit, match="seismic of sample"):
        bench_main(common + ["--reference", str(other)])


def test_recall_by_slip_pools_to_the_scorers_recall():
    """The per-band recalls, weighted by their pixel counts, give the scorer's recall (every
    labelled pixel has a slip here), and a hand-made case gives the expected bands."""
    recall_by_slip = runpy.run_path(str(BENCH))["recall_by_slip"]
    from demseis.evaluation import score

    rng = np.random.default_rng(3)
    truth = np.zeros((3, 40, 50), bool)
    truth[:, 5:35, 20] = True
    truth[:, 10, 5:45] = True
    slip = np.where(truth, rng.uniform(10, 200, truth.shape), 0.0)
    prob = rng.uniform(size=truth.shape).astype(np.float32) * 0.6
    prob[:, 5:20, 21] = 0.9  # a part of the vertical trace, 1 px off
    res = recall_by_slip(prob >= 0.5, truth, slip, 2)
    n = sum(v[1] for v in res.values())
    assert n == truth.sum() and res["below"] == [None, 0]
    pooled = sum(v[0] * v[1] for v in res.values() if v[1]) / n
    assert pooled == pytest.approx(score(prob, truth, threshold=0.5, tolerance_px=2).recall,
                                   abs=1e-4)
    # a single labelled pixel of 30 m slip next to a prediction: recall 1 in the 20-40 band
    t = np.zeros((1, 9, 9), bool)
    t[0, 4, 4] = True
    p = np.zeros((1, 9, 9), bool)
    p[0, 4, 6] = True
    r = recall_by_slip(p, t, np.where(t, 30.0, 0.0), 2)
    assert r["20-40"] == [1.0, 1] and r["10-20"] == [None, 0]
    assert recall_by_slip(p, t, np.where(t, 30.0, 0.0), 1)["20-40"] == [0.0, 1]
