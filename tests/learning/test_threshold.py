"""The model's threshold: chosen on the validation runs (checked against a threshold-by-threshold
search with the scorer), saved by ``demseis train`` and ``demseis threshold``, and used by
``demseis predict --mask``."""

from __future__ import annotations

import json

import numpy as np
import pytest

pytest.importorskip("torch")

import demseis.learning.model as mm  # noqa: E402
from demseis.cli import main  # noqa: E402
from demseis.datasets import FaultSegDataset  # noqa: E402
from demseis.errors import InputError  # noqa: E402
from demseis.evaluation import score  # noqa: E402
from demseis.evaluation.scoring import default_thresholds  # noqa: E402
from demseis.evaluation.store_scoring import score_store  # noqa: E402
from demseis.learning.train import predict_sections  # noqa: E402

FAST = ["--base", "4", "--batch", "4", "--threads", "1", "--device", "cpu", "--quiet"]


def _split(store, split):
    ds = FaultSegDataset(store, inputs=("seismic",), targets=("fault",), split=split)
    secs = np.stack([ds[j][0][0].numpy() for j in range(len(ds))])
    truth = np.stack([ds[j][1].numpy() > 0 for j in range(len(ds))])
    return ds, secs, truth


def test_choose_threshold_is_the_best_f1_of_a_search_threshold_by_threshold(tiny_store,
                                                                         monkeypatch):
    """Probabilities that follow the labels loosely (labels 0.45 higher, plus noise): the
    threshold chosen is the one of the 99 whose F1 at 2 px, scored one threshold at a time, is
    the highest, and its F1 is that F1."""
    ds, secs, truth = _split(tiny_store, "val")
    assert truth.any()
    rng = np.random.default_rng(3)
    prob = np.clip(0.45 * truth + 0.55 * rng.random(truth.shape), 0, 1).astype(np.float32)
    table = {secs.tobytes(): prob}
    monkeypatch.setattr(mm, "predict_sections", lambda model, x: table[np.asarray(x).tobytes()])
    got = mm.choose_threshold(object(), tiny_store)
    thresholds = default_thresholds()
    f1 = np.array([score(prob, truth, threshold=float(t), tolerance_px=2).f1
                   for t in thresholds])
    best = int(np.argmax(f1))   # the first of equal F1s, as the sweep takes
    assert got["threshold"] == pytest.approx(thresholds[best], abs=1e-4)
    assert got["f1"] == pytest.approx(f1[best], abs=1e-4)
    assert 0.3 < got["threshold"] < 0.99 and f1[best] > f1[49] + 0.05  # not 0.5, and it matters
    assert got["samples"] == len(ds) and got["runs"] == 1 and got["split"] == "val"
    # no threshold finds a fault: the default threshold
    monkeypatch.setattr(mm, "predict_sections", lambda model, x: np.zeros(x.shape, np.float32))
    assert mm.choose_threshold(object(), tiny_store)["threshold"] == mm.DEFAULT_THRESHOLD


def test_threshold_command_and_a_model_without_one(tiny_store, tmp_path, capsys):
    """A model file without a threshold draws its mask at 0.5 and says so; ``demseis threshold``
    chooses one on the validation runs, saves it in the file and its JSON with the test runs
    scored at it, and predict then uses it."""
    import torch

    model = tmp_path / "m.pt"
    assert main(["train", str(tiny_store), "--out", str(model), "--steps", "3", *FAST]) == 0
    blob = torch.load(model, map_location="cpu", weights_only=True)
    trained = blob.pop("threshold")
    for key in ("chosen_threshold", "at_chosen_threshold"):
        blob["metrics"].pop(key)
    torch.save(blob, model)  # as a model made before models carried a threshold
    net = mm.load_model(model, "cpu")
    assert net.demseis_threshold is None
    assert mm.model_threshold(net)[0] == mm.DEFAULT_THRESHOLD
    _, secs, _ = _split(tiny_store, "test")
    np.save(tmp_path / "s.npy", secs)
    capsys.readouterr()
    assert main(["predict", str(model), str(tmp_path / "s.npy"), "--out", str(tmp_path / "p.npy"),
                 "--mask", str(tmp_path / "m0.npy"), "--device", "cpu"]) == 0
    assert "reaches 0.5, default; the model carries no threshold" in capsys.readouterr().out
    prob = np.load(tmp_path / "p.npy")
    np.testing.assert_array_equal(np.load(tmp_path / "m0.npy"), prob >= 0.5)

    assert main(["threshold", str(model), str(tiny_store), "--device", "cpu"]) == 0
    assert "validation run(s); saved in" in capsys.readouterr().out
    ref = mm.choose_threshold(net, tiny_store)
    t = ref["threshold"]
    assert t == trained      # the same choice as demseis train made
    assert mm.load_model(model, "cpu").demseis_threshold == t
    metrics = json.loads(model.with_suffix(".json").read_text())
    assert metrics["chosen_threshold"] == ref
    assert mm.load_model(model, "cpu").demseis_metrics["chosen_threshold"] == ref
    test = FaultSegDataset(tiny_store, inputs=("seismic",), targets=("fault",), split="test")
    direct = score_store(predict_sections(net, secs), tiny_store, indices=test.indices,
                         threshold=t, tolerance_px=2).overall
    at = metrics["at_chosen_threshold"]
    assert at["threshold"] == t and at["f1"] == pytest.approx(direct.f1, abs=1e-4)
    assert at["precision"] == pytest.approx(direct.precision, abs=1e-4)
    assert main(["predict", str(model), str(tmp_path / "s.npy"), "--out", str(tmp_path / "q.npy"),
                 "--mask", str(tmp_path / "m1.npy"), "--device", "cpu"]) == 0
    assert f"reaches {t:g}, the model's" in capsys.readouterr().out
    np.testing.assert_array_equal(np.load(tmp_path / "m1.npy"), prob >= t)
    assert main(["predict", str(model), str(tmp_path / "s.npy"), "--out", str(tmp_path / "r.npy"),
                 "--mask", str(tmp_path / "m2.npy"), "--threshold", "0.2",
                 "--device", "cpu"]) == 0
    np.testing.assert_array_equal(np.load(tmp_path / "m2.npy"), prob >= 0.2)


def test_mask_and_threshold_errors(tmp_path, capsys):
    sec = tmp_path / "s.npy"
    np.save(sec, np.zeros((8, 8), np.float32))
    (tmp_path / "old.npy").write_bytes(b"x")
    for extra, message in (
            (["--mask", str(tmp_path / "p.npy")], "is --out as well"),
            (["--mask", str(tmp_path / "old.npy")], "exists; pass --overwrite"),
            (["--mask", str(tmp_path / "m.png")], "name a .sgy, .segy or .npy file"),
            (["--mask", str(tmp_path / "m.sgy")], "SEG-Y output needs SEG-Y input"),
            (["--threshold", "1.5"], "--threshold 1.5: expected a probability in (0, 1)")):
        assert main(["predict", str(sec), "--out", str(tmp_path / "p.npy"), *extra]) == 2
        assert message in capsys.readouterr().err
    assert not (tmp_path / "p.npy").exists()
    with pytest.raises(InputError, match="mask: give out as well"):
        import demseis

        demseis.predict(None, np.zeros((8, 8), np.float32), mask=tmp_path / "m.npy")


def test_a_model_file_with_a_threshold_out_of_range_is_no_model(tmp_path):
    import torch

    from demseis.learning.train import build_unet

    blob = {"format": mm.FORMAT, "version": mm.VERSION, "base": 4, "target": "fault",
            "state_dict": build_unet(4).state_dict()}
    for value, ok in ((0.37, True), (1.5, False), ("0.5", False), (0.0, False)):
        torch.save({**blob, "threshold": value}, tmp_path / "m.pt")
        if ok:
            assert mm.load_model(tmp_path / "m.pt", "cpu").demseis_threshold == value
        else:
            with pytest.raises(InputError, match="is not a demseis model"):
                mm.load_model(tmp_path / "m.pt", "cpu")


def test_training_keeps_the_step_best_at_its_own_threshold(tiny_store, tmp_path, capsys):
    """select="ods_f1" (the default of demseis train): the kept model's validation score is its
    F1 at its best threshold, recomputed here from the saved model; "f1" keeps the score at
    0.5; a checkpoint trained with one is not resumed with the other."""
    kw = dict(steps=4, val_every=1, base=4, batch=4, threads=1, device="cpu", progress=False,
              log=None, save_every=2)
    m = mm.train_model(tiny_store, tmp_path / "a.pt", **kw)
    assert m["select"] == "ods_f1"
    net = mm.load_model(tmp_path / "a.pt", "cpu")
    assert m["best_val_f1"] == pytest.approx(mm.choose_threshold(net, tiny_store)["f1"], abs=1e-4)
    assert m["chosen_threshold"]["f1"] == pytest.approx(m["best_val_f1"], abs=1e-4)
    m = mm.train_model(tiny_store, tmp_path / "b.pt", select="f1", **kw)
    net = mm.load_model(tmp_path / "b.pt", "cpu")
    val, secs, _ = _split(tiny_store, "val")
    at_half = score_store(predict_sections(net, secs), tiny_store, indices=val.indices,
                          threshold=0.5, tolerance_px=2).overall.f1
    assert m["select"] == "f1" and m["best_val_f1"] == pytest.approx(at_half, abs=1e-4)
    with pytest.raises(InputError, match="--select"):
        mm.train_model(tiny_store, tmp_path / "b.pt", resume=True, **{**kw, "steps": 6})
    with pytest.raises(InputError, match="select 'iou'"):
        mm.train_model(tiny_store, tmp_path / "c.pt", select="iou", **kw)
