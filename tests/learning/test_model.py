"""demseis train / predict (and the API's train / predict): generate -> train -> predict a
SEG-Y section -> score it, on ``tiny`` (and ``quick``, slow); resume; stores too small to train
on; sections of any size."""

from __future__ import annotations

import dataclasses
import json

import numpy as np
import pytest

pytest.importorskip("torch")

import demseis  # noqa: E402
from demseis.cli import main  # noqa: E402
from demseis.errors import InputError  # noqa: E402
from demseis.learning.model import load_model, predict_array  # noqa: E402
from tests.evaluation._helpers import write_cube  # noqa: E402
from tests.generator._helpers import kinematic_cfg  # noqa: E402

FAST = ["--base", "4", "--batch", "4", "--threads", "1", "--device", "cpu", "--quiet"]


def _chain(store, tmp_path, capsys, steps: int) -> dict:
    """train -> export a test sample as SEG-Y -> predict it -> score it; the score's JSON."""
    model = tmp_path / "model.pt"
    assert main(["train", str(store), "--out", str(model), "--steps", str(steps), *FAST]) == 0
    metrics = json.loads(model.with_suffix(".json").read_text())
    assert set(metrics) >= {"precision", "recall", "f1", "ap", "test_samples", "test_runs"}
    assert metrics["steps"] == steps and metrics["test_runs"] >= 1
    # tiny and quick have one validation run: the training says what that means (issue 38)
    assert metrics["val_runs"] == 1
    assert any("chosen on 1 validation run" in w for w in metrics["warnings"])
    assert "demseis: warning: the model was chosen on 1 validation run" in capsys.readouterr().err
    assert all(0.0 <= metrics[k] <= 1.0 for k in ("precision", "recall", "f1", "ap"))
    sample = int(np.flatnonzero(demseis.open(store).done)[-1])
    sgy, pred = tmp_path / "in.sgy", tmp_path / "pred.sgy"
    assert main(["export-segy", str(store), "--sample", str(sample), "--out", str(sgy)]) == 0
    # the threshold chosen on the validation runs is saved with the model and used by --mask
    chosen = metrics["chosen_threshold"]
    assert 0 < chosen["threshold"] < 1 and chosen["split"] == "val" and chosen["runs"] == 1
    assert metrics["at_chosen_threshold"]["threshold"] == chosen["threshold"]
    assert load_model(model, "cpu").demseis_threshold == chosen["threshold"]
    mask = tmp_path / "mask.sgy"
    assert main(["predict", str(model), str(sgy), "--out", str(pred), "--device", "cpu",
                 "--png", str(tmp_path / "pred.png"), "--mask", str(mask)]) == 0
    assert f"reaches {chosen['threshold']:g}, the model's" in capsys.readouterr().out
    assert (tmp_path / "pred.png").stat().st_size > 5_000   # the section with its prediction
    import segyio

    with segyio.open(str(sgy), ignore_geometry=True) as a, \
            segyio.open(str(pred), ignore_geometry=True) as b, \
            segyio.open(str(mask), ignore_geometry=True) as m:
        assert b.tracecount == a.tracecount and len(b.samples) == len(a.samples)
        assert b.text[0] == a.text[0]
        assert all(dict(b.header[i]) == dict(a.header[i]) for i in range(a.tracecount))
        assert all(dict(m.header[i]) == dict(a.header[i]) for i in range(a.tracecount))
        prob = b.trace.raw[:]
        assert 0.0 <= prob.min() and prob.max() <= 1.0
        np.testing.assert_array_equal(m.trace.raw[:], prob >= chosen["threshold"])
    prefix = tmp_path / "pred.score"
    assert main(["score", str(pred), str(store), "--indices", str(sample), "--tolerance", "2",
                 "--out-prefix", str(prefix)]) == 0
    capsys.readouterr()
    return json.loads((tmp_path / "pred.score.json").read_text())


def test_generate_train_predict_score_on_tiny(tiny_store, tmp_path, capsys):
    result = _chain(tiny_store, tmp_path, capsys, steps=4)
    assert result["overall"]["n_samples"] == 1 and result["overall"]["tolerance_px"] == 2
    assert 0.0 <= result["overall"]["f1"] <= 1.0


def test_resume_goes_on_from_the_checkpoint(tiny_store, tmp_path, capsys):
    model = tmp_path / "m.pt"
    args = ["train", str(tiny_store), "--out", str(model), "--save-every", "2", *FAST]
    assert main([*args, "--steps", "2"]) == 0
    assert (tmp_path / "m.pt.ckpt").is_file()
    assert main([*args, "--steps", "4", "--resume"]) == 0
    assert json.loads(model.with_suffix(".json").read_text())["steps"] == 4
    assert main([*args, "--steps", "4", "--resume"]) == 2  # nothing left to do
    assert "larger --steps" in capsys.readouterr().err
    assert main(["train", str(tiny_store), "--out", str(tmp_path / "x.pt"), "--resume",
                 *FAST]) == 2
    assert "no training state" in capsys.readouterr().err
    # the loss's weight of fault pixels, measured (the background / fault ratio, at most 50)
    assert 1.0 < json.loads(model.with_suffix(".json").read_text())["pos_weight"] <= 50.0


def test_pos_weight_is_recorded_and_resume_keeps_it(tiny_store, tmp_path, capsys):
    """--pos-weight reaches the loss (train_unet's info), the model's JSON records it, and a
    checkpoint trained with it resumes only with the same weight."""
    model = tmp_path / "w.pt"
    args = ["train", str(tiny_store), "--out", str(model), "--save-every", "2", *FAST]
    assert main([*args, "--steps", "2", "--pos-weight", "3"]) == 0
    saved = json.loads(model.with_suffix(".json").read_text())
    assert saved["pos_weight"] == 3.0
    assert main([*args, "--steps", "4", "--resume"]) == 2
    assert "--pos-weight" in capsys.readouterr().err
    assert main([*args, "--steps", "4", "--resume", "--pos-weight", "3"]) == 0
    assert main([*args, "--steps", "2", "--pos-weight", "0", "--out", str(tmp_path / "z.pt")]) == 2
    assert "--pos-weight 0.0: use a number > 0" in capsys.readouterr().err


def test_api_train_and_predict(tiny_store, tmp_path):
    metrics = demseis.train(tiny_store, out=tmp_path / "a.pt", steps=2, base=4, batch=4,
                            device="cpu", threads=1, progress=False, log=None)
    assert 0.0 <= metrics["f1"] <= 1.0
    section = demseis.open(tiny_store).sample(0)["seismic"]
    prob = demseis.predict(tmp_path / "a.pt", section, device="cpu")
    assert prob.shape == section.shape and prob.dtype == np.float32
    out = demseis.predict(tmp_path / "a.pt", section[None], device="cpu")
    assert out.shape == (1, *section.shape)


@pytest.mark.parametrize("shape", [(1, 1), (3, 7), (37, 41), (130, 70)])
def test_predict_any_section_size(tiny_store, tmp_path, shape):
    demseis.train(tiny_store, out=tmp_path / "s.pt", steps=1, base=4, batch=2, device="cpu",
                  progress=False, log=None)
    model = load_model(tmp_path / "s.pt", "cpu")
    x = np.random.default_rng(1).normal(size=shape).astype(np.float32)
    whole = predict_array(model, x)
    tiled = predict_array(model, x, tile=32, overlap=8)  # several tiles where larger than 32
    assert whole.shape == tiled.shape == shape
    assert np.isfinite(tiled).all() and 0 <= tiled.min() and tiled.max() <= 1


def test_stores_too_small_say_why(tmp_path, capsys):
    small = tmp_path / "two.zarr"
    cfg = kinematic_cfg("tiny")
    cfg = dataclasses.replace(cfg, sweep=dataclasses.replace(cfg.sweep, n_runs=2))
    demseis.generate(cfg, out=small, workers=0)
    assert main(["train", str(small), "--out", str(tmp_path / "m.pt"), *FAST]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "2 run(s)" in err and "at least 3" in err


def test_crop_larger_than_the_sections_names_the_flag(tiny_store, tmp_path, capsys):
    assert main(["train", str(tiny_store), "--out", str(tmp_path / "m.pt"), "--crop", "64",
                 *FAST]) == 2
    err = capsys.readouterr().err
    assert "--crop 64" in err and "40" in err


def test_predict_errors(tmp_path, capsys):
    assert main(["predict", str(tmp_path / "none.pt"), str(tmp_path / "x.sgy"), "--out",
                 str(tmp_path / "y.npy")]) == 2
    assert "does not exist" in capsys.readouterr().err
    np.save(tmp_path / "x.npy", np.zeros((4, 4), np.float32))
    assert main(["predict", str(tmp_path / "none.pt"), str(tmp_path / "x.npy"), "--out",
                 str(tmp_path / "y.sgy")]) == 2
    assert "SEG-Y output needs SEG-Y input" in capsys.readouterr().err
    with pytest.raises(InputError, match="sections must be"):
        predict_array(None, np.zeros(5))


def test_training_warnings_name_what_the_training_lacked():
    from demseis.learning.model import training_warnings

    good = {"val_runs": 3, "test_runs": 3, "best_step": 800, "steps": 1000}
    assert training_warnings(good) == []
    early = training_warnings({**good, "best_step": 100})
    assert len(early) == 1 and "step 100 of 1000" in early[0]
    thin = training_warnings({**good, "val_runs": 1, "test_runs": 1})
    assert len(thin) == 2 and "1 validation run" in thin[0] and "from 1 run" in thin[1]


def test_a_file_that_is_not_a_model_says_so(tmp_path):
    """issue 38: every kind of file that is not a model (text, an empty file, a pickle of
    something else, a torch file of other tensors, one with the format key but no weights)
    gives the same one line, not the name of the exception torch raised inside."""
    import pickle

    import torch

    files = {"text.pt": b"not a model at all", "empty.pt": b"",
             "pickle.pt": pickle.dumps({"a": 1})}
    for name, data in files.items():
        (tmp_path / name).write_bytes(data)
    torch.save({"w": torch.zeros(3)}, tmp_path / "tensors.pt")
    torch.save({"format": "demseis-unet-1", "base": 4}, tmp_path / "noweights.pt")
    from demseis.learning.model import FORMAT

    torch.save({"format": FORMAT, "base": 4, "state_dict": {"w": torch.zeros(3)}},
               tmp_path / "wrongweights.pt")
    for f in sorted(tmp_path.iterdir()):
        with pytest.raises(InputError) as err:
            load_model(f, "cpu")
        assert str(err.value) == f"model {str(f)!r} is not a demseis model (made by demseis train)"


@pytest.mark.slow
def test_generate_train_predict_score_on_quick(tmp_path, capsys):
    store = tmp_path / "quick.zarr"
    demseis.generate("quick", out=store)
    result = _chain(store, tmp_path, capsys, steps=6)
    assert result["overall"]["n_samples"] == 1


@pytest.mark.parametrize("sorting_inline, block_bytes", [(True, 64 * 2**20), (False, 64 * 2**20),
                                                        (True, 5 * 24 * 4 * 2)])
def test_predict_a_3d_cube_along_inlines_and_crosslines(tmp_path, monkeypatch, sorting_inline,
                                                        block_bytes):
    """issue 38: a 3-D SEG-Y cube is predicted along every inline and every crossline and the
    two averaged (checked against the same model applied to the cube in memory); the output
    cube has the input's geometry and trace headers, whatever its trace order."""
    import segyio
    import torch

    from demseis.learning.model import predict_file
    from demseis.learning.train import build_unet

    import demseis.learning.model as model_module

    monkeypatch.setattr(model_module, "CUBE_BLOCK_BYTES", block_bytes)  # 2 crosslines a block
    torch.manual_seed(0)
    net = build_unet(4).eval()
    rng = np.random.default_rng(0)
    cube = rng.normal(size=(5, 7, 24)).astype(np.float32)
    ilines, xlines = [101, 102, 103, 104, 105], [11, 13, 15, 17, 19, 21, 23]
    inp, out = tmp_path / "cube.sgy", tmp_path / "prob.sgy"
    write_cube(inp, cube, ilines, xlines, sorting_inline=sorting_inline)
    # what segyio reads back (IBM floats are not exactly float32)
    def as_il_xl(f):  # segyio.tools.cube is (slow, fast, samples): crossline-major if so sorted
        c = segyio.tools.cube(f)
        return c if f.sorting == segyio.TraceSortingFormat.INLINE_SORTING else c.transpose(1, 0, 2)

    with segyio.open(str(inp)) as f:
        stored = as_il_xl(f).astype(np.float32)
    np.testing.assert_allclose(stored, cube, rtol=1e-6)
    assert predict_file(net, inp, out) == out
    along_il = np.stack([predict_array(net, stored[i].T).T for i in range(5)])
    along_xl = np.stack([predict_array(net, stored[:, j].T).T for j in range(7)], axis=1)
    with segyio.open(str(inp)) as a, segyio.open(str(out)) as b:
        assert list(b.ilines) == ilines and list(b.xlines) == xlines
        assert b.sorting == a.sorting and len(b.samples) == 24
        assert b.bin[segyio.BinField.Format] == 5               # IEEE float32 probabilities
        for k in range(a.tracecount):
            assert dict(b.header[k]) == dict(a.header[k])
        np.testing.assert_allclose(as_il_xl(b), 0.5 * (along_il + along_xl), atol=1e-5)
    npy = predict_file(net, inp, tmp_path / "prob.npy", mask=tmp_path / "mask.npy",
                       threshold=0.5)
    prob = np.load(npy)
    np.testing.assert_allclose(prob, 0.5 * (along_il + along_xl), atol=1e-5)
    mask = np.load(tmp_path / "mask.npy")  # 0/1 at the threshold, inline by inline
    assert mask.dtype == np.uint8 and mask.shape == prob.shape
    np.testing.assert_array_equal(mask, prob >= 0.5)
    t = float(np.median(prob))  # a threshold that splits this untrained model's output
    predict_file(net, inp, tmp_path / "p2.sgy", mask=tmp_path / "mask.sgy", threshold=t)
    with segyio.open(str(tmp_path / "p2.sgy")) as b, segyio.open(str(tmp_path / "mask.sgy")) as m:
        assert list(m.ilines) == ilines and list(m.xlines) == xlines
        assert all(dict(m.header[k]) == dict(b.header[k]) for k in range(b.tracecount))
        got = as_il_xl(m)
        np.testing.assert_array_equal(got, as_il_xl(b) >= t)
        assert 0 < got.mean() < 1
    assert sorted(p.name for p in tmp_path.iterdir()) == [
        "cube.sgy", "mask.npy", "mask.sgy", "p2.sgy", "prob.npy", "prob.sgy"]


def test_the_shipped_model_predicts_when_no_model_is_named(tmp_path, capsys):
    """issue 38: `demseis predict SECTION --out X` uses the model shipped in the package (at
    most 10 MB, a demseis model); `predict MODEL IN` keeps working; both at once is refused."""
    from demseis.learning.model import pretrained_path

    shipped = pretrained_path()
    assert shipped.stat().st_size < 10 * 2**20
    net = load_model(shipped, "cpu")
    assert net.demseis_metrics["steps"] == 1200
    # its threshold, chosen on its validation runs, in the file and in the JSON beside it
    assert 0 < net.demseis_threshold < 1
    assert net.demseis_threshold == net.demseis_metrics["chosen_threshold"]["threshold"]
    assert json.loads(shipped.with_suffix(".json").read_text()) == net.demseis_metrics
    sec = np.random.default_rng(0).normal(size=(40, 56)).astype(np.float32)
    np.save(tmp_path / "s.npy", sec)
    assert main(["predict", str(tmp_path / "s.npy"), "--out", str(tmp_path / "a.npy"),
                 "--device", "cpu"]) == 0
    assert main(["predict", str(shipped), str(tmp_path / "s.npy"), "--out",
                 str(tmp_path / "b.npy"), "--device", "cpu"]) == 0
    a, b = np.load(tmp_path / "a.npy"), np.load(tmp_path / "b.npy")
    np.testing.assert_array_equal(a, b)
    np.testing.assert_allclose(a, predict_array(net, sec), atol=1e-6)
    capsys.readouterr()
    assert main(["predict", str(shipped), str(tmp_path / "s.npy"), "--model", str(shipped),
                 "--out", str(tmp_path / "c.npy")]) == 2
    assert "give the model once" in capsys.readouterr().err
