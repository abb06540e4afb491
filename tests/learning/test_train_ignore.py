"""Training with pixels left out of the loss (``train_unet(ignore=)``, ``demseis train
--ignore``): the masked loss against a plain reference, labels under the ignored pixels that
change nothing, stores without the array in a mix, and the errors."""

from __future__ import annotations

import json
import runpy
from pathlib import Path

import numpy as np
import pytest

torch = pytest.importorskip("torch")

from demseis import datasets  # noqa: E402
from demseis.cli import main  # noqa: E402
from demseis.errors import InputError  # noqa: E402
from demseis.evaluation import score  # noqa: E402
from demseis.learning.train import (ignored_pixels, masked_loss, parse_ignore,  # noqa: E402
                                    train_unet)
from tests.evaluation._helpers import toy_store  # noqa: E402

BENCH = Path(__file__).resolve().parents[2] / "benchmarks" / "learnability.py"
KW = dict(steps=4, crop=16, batch=4, base=4, threads=1, device="cpu", log=None, augment=True)


def _store_with_uncertain(path, labels=None, n_shards=4, per_shard=4, h=24, w=24):
    """Sections with a vertical fault at column 12 (rows 4-19), ``fault_uncertain`` 1 on its
    lower half and 2 on a band at column 4; ``labels(fault, uncertain)`` may change the
    labels before they are written."""
    datasets.create_store(path, n_shards=n_shards, samples_per_shard=per_shard, shape=(h, w),
                          arrays=["seismic", "fault", "fault_uncertain"],
                          params={"run_id": "int32"},
                          attrs={"config": {}, "grid": {"x0_m": 0.0, "top_m": 0.0,
                                                        "cell_m": 10.0, "nz": h, "nx": w}})
    rng = np.random.default_rng(0)
    for k in range(n_shards):
        seis = rng.normal(size=(per_shard, h, w)).astype(np.float32)
        fault = np.zeros((per_shard, h, w), np.uint8)
        fault[:, 4:20, 12] = 1
        unc = np.zeros_like(fault)
        unc[:, 12:20, 12] = 1
        unc[:, 2:22, 4] = 2
        if labels is not None:
            fault = labels(fault, unc)
        datasets.write_shard(path, k, {"seismic": seis, "fault": fault,
                                       "fault_uncertain": unc}, {"run_id": k})


def _slow_loss(logits, y, keep, pos_weight):
    """The masked loss written out pixel by pixel in NumPy (``pos_weight``: one number, or one
    per sample)."""
    z, t, k = (np.asarray(a, np.float64).ravel() for a in (logits, y, keep))
    w = np.repeat(np.broadcast_to(np.asarray(pos_weight, np.float64), (len(logits),)),
                  z.size // len(logits))
    p = 1 / (1 + np.exp(-z))
    bce = [-(wi * ti * np.log(pi) + (1 - ti) * np.log(1 - pi))
           for wi, ti, pi, ki in zip(w, t, p, k) if ki]
    inter = sum(pi * ti for pi, ti, ki in zip(p, t, k) if ki)
    dice = 1 - (2 * inter + 1) / (sum(p * k) + sum(t * k) + 1)
    return np.mean(bce) + dice


def test_masked_loss_against_a_slow_reference_and_the_plain_loss():
    g = torch.Generator().manual_seed(0)
    logits = torch.randn(2, 1, 6, 7, generator=g)
    y = (torch.rand(2, 1, 6, 7, generator=g) < 0.2).float()
    keep = (torch.rand(2, 1, 6, 7, generator=g) < 0.7).float()
    pw = torch.tensor(7.5)
    got = float(masked_loss(logits, y, keep, pw))
    assert got == pytest.approx(_slow_loss(logits, y, keep, 7.5), rel=1e-5)
    # every pixel kept: the loss train_unet uses without ignore
    p = torch.sigmoid(logits)
    plain = torch.nn.BCEWithLogitsLoss(pos_weight=pw)(logits, y) \
        + 1 - (2 * (p * y).sum() + 1) / (p.sum() + y.sum() + 1)
    assert float(masked_loss(logits, y, torch.ones_like(y), pw)) == pytest.approx(
        float(plain), rel=1e-6)
    # an ignored pixel's logit and label do not reach the loss or its gradient
    z = logits.clone().requires_grad_(True)
    masked_loss(z, y, keep, pw).backward()
    assert (z.grad[keep == 0] == 0).all() and (z.grad[keep == 1] != 0).all()
    y2 = torch.where(keep == 0, 1 - y, y)
    assert float(masked_loss(logits, y2, keep, pw)) == pytest.approx(got, rel=1e-6)
    # one weight per sample (a weight per store): each sample's fault pixels by its own
    each = torch.tensor([7.5, 2.0]).view(-1, 1, 1, 1)
    assert float(masked_loss(logits, y, keep, each)) == pytest.approx(
        _slow_loss(logits, y, keep, [7.5, 2.0]), rel=1e-5)


def test_labels_under_ignored_pixels_change_nothing(tmp_path):
    """Two stores that differ only in the labels of their ignored pixels train the same
    weights; without ignore they do not."""
    a, b = tmp_path / "a.zarr", tmp_path / "b.zarr"
    _store_with_uncertain(a)
    # b: the lower half of the fault unlabelled and the band at column 4 labelled instead
    _store_with_uncertain(b, labels=lambda f, u: np.where(u > 0, (u == 2).astype(np.uint8), f))
    ma, ia = train_unet(a, ignore="fault_uncertain", **KW)
    mb, ib = train_unet(b, ignore="fault_uncertain", **KW)
    for (k, va), vb in zip(ma.state_dict().items(), mb.state_dict().values()):
        assert torch.equal(va, vb), k
    assert ia["pos_weight"] == ib["pos_weight"]
    assert 0 < ia["ignored_fraction"] < 0.2
    m1, _ = train_unet(a, **KW)
    m2, _ = train_unet(b, **KW)
    assert any(not torch.equal(v1, v2) for v1, v2 in zip(m1.state_dict().values(),
                                                         m2.state_dict().values()))
    # only class 2 ignored: the lower half of the fault counts, so a and b differ again
    mc, _ = train_unet(a, ignore="fault_uncertain", ignore_values=[2], **KW)
    md, _ = train_unet(b, ignore="fault_uncertain", ignore_values=[2], **KW)
    assert any(not torch.equal(v1, v2) for v1, v2 in zip(mc.state_dict().values(),
                                                         md.state_dict().values()))


def test_a_mix_with_a_store_without_the_array_and_the_errors(tmp_path):
    a, plain = tmp_path / "a.zarr", tmp_path / "plain.zarr"
    _store_with_uncertain(a)
    toy_store(plain, h=24, w=24)
    _, info = train_unet([a, plain], ignore="fault_uncertain", **KW)
    _, alone = train_unet(a, ignore="fault_uncertain", **KW)
    assert info["steps"] == 4 and sum(info["drawn_per_store"]) == 16
    assert 0 < info["ignored_fraction"] < alone["ignored_fraction"]
    with pytest.raises(InputError, match="'fault_uncertain': no training store holds"):
        train_unet(plain, ignore="fault_uncertain", **KW)
    assert parse_ignore("fault_uncertain=1,2") == ("fault_uncertain", [1, 2])
    assert parse_ignore("fault_uncertain") == ("fault_uncertain", None)
    for bad in ("=1", "fault_uncertain=", "fault_uncertain=x"):
        with pytest.raises(InputError, match="--ignore"):
            parse_ignore(bad)


def test_a_weight_of_fault_pixels_per_store_with_pixels_left_out(tmp_path):
    """With ``ignore``, a weight per store still weighs each sample by its own store: a store
    without fault pixels trains the same whatever its weight, the other store's weight
    matters."""
    a, empty = tmp_path / "a.zarr", tmp_path / "empty.zarr"
    _store_with_uncertain(a)
    toy_store(empty, h=24, w=24, fault_fn=np.zeros_like)

    def params(pos_weight):
        m, _ = train_unet([a, empty], ignore="fault_uncertain", pos_weight=pos_weight, **KW)
        return np.concatenate([p.detach().numpy().ravel() for p in m.parameters()])

    one = params(7.0)
    np.testing.assert_array_equal(params([7.0, 7.0]), one)
    np.testing.assert_array_equal(params([7.0, 40.0]), one)
    assert np.abs(params([1.0, 7.0]) - one).max() > 1e-4


def test_cli_train_ignore_is_recorded_and_resume_checks_it(tmp_path, capsys):
    a = tmp_path / "a.zarr"
    _store_with_uncertain(a, n_shards=4)
    out = tmp_path / "m.pt"
    fast = ["--base", "4", "--batch", "4", "--threads", "1", "--device", "cpu", "--quiet",
            "--crop", "16"]
    assert main(["train", str(a), "--out", str(out), "--steps", "2", "--ignore",
                 "fault_uncertain=1", *fast]) == 0
    metrics = json.loads(out.with_suffix(".json").read_text())
    assert metrics["ignore"] == ["fault_uncertain", [1]]
    assert main(["train", str(a), "--out", str(out), "--steps", "4", "--resume", "--ignore",
                 "fault_uncertain", *fast]) == 2
    assert "--ignore" in capsys.readouterr().err
    assert main(["train", str(a), "--out", str(out), "--steps", "4", "--resume", "--ignore",
                 "fault_uncertain=1", *fast]) == 0
    assert main(["train", str(a), "--out", str(out), "--steps", "2", "--ignore", "x=y",
                 *fast]) == 2


def test_ignored_pixels_are_the_same_for_numpy_and_torch():
    u = np.array([[0, 1, 2], [2, 0, 1]], np.uint8)
    for values, want in ((None, u != 0), ([2], u == 2), ([1, 2], u > 0), ([], u < 0)):
        np.testing.assert_array_equal(ignored_pixels(u, values), want)
        np.testing.assert_array_equal(ignored_pixels(torch.from_numpy(u), values).numpy(), want)


def test_learnability_scores_without_the_left_out_pixels(tmp_path, capsys):
    """``--score-without``: the ``_kept`` scores are those of the predictions and labels with
    the left-out pixels removed, recomputed here from the saved predictions."""
    a = tmp_path / "a.zarr"
    _store_with_uncertain(a, n_shards=5)
    pred = tmp_path / "pred.npz"
    bench = runpy.run_path(str(BENCH))["main"]
    assert bench([str(a), "--steps", "2", "--crop", "16", "--batch", "4", "--base", "4",
                  "--threads", "1", "--device", "cpu", "--test-fraction", "0.4", "--no-progress",
                  "--ignore", "fault_uncertain=1", "--score-without", "fault_uncertain=2",
                  "--save-pred", str(pred), "--save-n", "99"]) == 0
    out = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    assert out["ignore"] == ["fault_uncertain", [1]]
    assert out["score_without"] == ["fault_uncertain", [2]]
    assert 0 < out["ignored_fraction"] < 0.05
    # class 2 is the band at column 4, rows 2-21: 20 of 24 x 24 pixels
    assert out["test_left_out_fraction"] == pytest.approx(20 / 576, abs=1e-4)
    saved = np.load(pred)
    prob, truth = saved["prob"], saved["truth"]
    left = np.zeros(prob.shape, bool)
    left[:, 2:22, 4] = True
    r = score(np.where(left, 0.0, prob), truth & ~left, threshold=0.5, tolerance_px=2)
    assert out["test_f1_tol2_kept"] == pytest.approx(round(float(r.f1), 4), abs=1e-4)
    assert out["test_ap_tol2_kept"] == pytest.approx(round(float(r.ap), 4), abs=1e-4)
