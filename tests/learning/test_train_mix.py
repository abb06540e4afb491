"""Training on several stores at once: the mix follows the weights, bad weights are refused
in one line, and ``demseis train A B --weights`` records the stores, weights and per-store
metrics and resumes."""

from __future__ import annotations

import json

import numpy as np
import pytest

torch = pytest.importorskip("torch")

import demseis  # noqa: E402
from demseis.cli import main  # noqa: E402
from demseis.errors import InputError  # noqa: E402
from demseis.learning.train import check_weights, mix_sampler, train_unet  # noqa: E402
from tests.evaluation._helpers import toy_store  # noqa: E402

FAST = ["--base", "4", "--batch", "4", "--threads", "1", "--device", "cpu", "--quiet"]


@pytest.fixture(scope="module")
def two_stores(tmp_path_factory):
    d = tmp_path_factory.mktemp("mix")
    toy_store(d / "a.zarr")
    toy_store(d / "b.zarr", n_shards=4)
    return d / "a.zarr", d / "b.zarr"


def test_mix_sampler_follows_the_weights():
    """Draws of a seeded sampler fall in each dataset in proportion to its weight, whatever the
    datasets' sizes, and uniformly inside it; the same seed gives the same draws."""
    sizes, shares = [10, 40], check_weights([2, 1], 2)
    draws = []
    for _ in range(2):
        sampler = mix_sampler(sizes, shares, torch.Generator().manual_seed(3))
        draws.append(np.concatenate([list(sampler) for _ in range(600)]))  # 30,000 draws
    assert np.array_equal(draws[0], draws[1])
    idx = draws[0]
    n = idx.size
    first = float(np.mean(idx < 10))
    assert abs(first - 2 / 3) < 4 * np.sqrt(2 / 9 / n)  # within 4 binomial sigmas
    per = np.bincount(idx, minlength=50)
    assert per[:10].min() > 0.8 * per[:10].mean() and per[10:].min() > 0.7 * per[10:].mean()
    # equal weights: equal shares, not shares by size
    idx = np.concatenate([list(mix_sampler(sizes, check_weights(None, 2),
                                           torch.Generator().manual_seed(0))) for _ in range(300)])
    assert abs(float(np.mean(idx < 10)) - 0.5) < 4 * np.sqrt(0.25 / idx.size)


def test_check_weights_refuses_bad_weights():
    assert check_weights([2, 1], 2) == pytest.approx([2 / 3, 1 / 3])
    assert check_weights(None, 3) == pytest.approx([1 / 3] * 3)
    for weights, message in (([1], "1 weight"), ([1, 2, 3], "3 weight"), ([1, 0], "weight 2"),
                             ([-1, 1], "weight 1"), ([1, float("nan")], "weight 2"),
                             ([float("inf"), 1], "weight 1"), ([True, 1], "weight 1"),
                             (["2", 1], "weight 1")):
        with pytest.raises(InputError, match=message) as err:
            check_weights(weights, 2)
        assert "\n" not in str(err.value)


def test_train_unet_draws_batches_in_proportion(two_stores):
    a, b = two_stores
    _, info = train_unet([a, b], weights=[3, 1], steps=40, crop=16, batch=8, base=4,
                         threads=1, device="cpu", log=None)
    drawn = info["drawn_per_store"]
    # every sample of every step (an epoch of n_samples draws ends in a smaller batch), none
    # of the batches looked at for the loss's positive weight
    n = info["n_samples"]
    epoch = [8] * (n // 8) + ([n % 8] if n % 8 else [])
    assert sum(drawn) == sum((epoch * 40)[:40])
    assert abs(drawn[0] / sum(drawn) - 0.75) < 4 * np.sqrt(0.75 * 0.25 / sum(drawn))
    _, one = train_unet(a, steps=3, crop=16, batch=4, base=4, threads=1, device="cpu", log=None)
    assert one["drawn_per_store"] == [12]


def test_cli_trains_on_two_stores_and_resumes(two_stores, tmp_path, capsys):
    a, b = two_stores
    model = tmp_path / "m.pt"
    args = ["train", str(a), str(b), "--weights", "2,1", "--out", str(model), "--save-every",
            "2", *FAST]
    assert main([*args, "--steps", "2"]) == 0
    assert main([*args, "--steps", "4", "--resume"]) == 0
    meta = json.loads(model.with_suffix(".json").read_text())
    assert meta["steps"] == 4 and "store" not in meta
    assert meta["stores"] == [str(a.resolve()), str(b.resolve())]
    assert meta["weights"] == [2.0, 1.0]
    per = meta["per_store"]
    assert [p["store"] for p in per] == meta["stores"]
    assert [p["share"] for p in per] == [0.6667, 0.3333]
    assert sum(p["train_samples_drawn"] for p in per) == 4 * 4  # both runs of the training
    assert meta["test_samples"] == sum(p["test_samples"] for p in per)
    assert meta["test_runs"] == sum(p["test_runs"] for p in per) >= 2
    for p in per:
        assert all(0.0 <= p[k] <= 1.0 for k in ("precision", "recall", "f1", "ap"))
    assert torch.load(model, weights_only=True)["metrics"]["stores"] == meta["stores"]
    # another mix, or a store fewer, does not resume this training
    assert main(["train", str(a), str(b), "--weights", "1,1", "--out", str(model), "--steps",
                 "6", "--resume", *FAST]) == 2
    assert "other stores, weights" in capsys.readouterr().err
    assert main(["train", str(a), "--out", str(model), "--steps", "6", "--resume", *FAST]) == 2
    assert "other stores, weights" in capsys.readouterr().err


def test_cli_weight_of_fault_pixels_per_store(two_stores, tmp_path, capsys):
    """``--pos-weight 5,1``: one weight per store, recorded in the model's JSON; the resume
    keeps it; a count or value that does not fit is one line naming --pos-weight."""
    a, b = two_stores
    model = tmp_path / "pw.pt"
    args = ["train", str(a), str(b), "--out", str(model), "--save-every", "2", *FAST]
    assert main([*args, "--steps", "2", "--pos-weight", "5,1"]) == 0
    assert json.loads(model.with_suffix(".json").read_text())["pos_weight"] == [5.0, 1.0]
    assert main([*args, "--steps", "4", "--resume", "--pos-weight", "5,2"]) == 2
    assert "--pos-weight" in capsys.readouterr().err
    assert main([*args, "--steps", "4", "--resume", "--pos-weight", "5,1"]) == 0
    capsys.readouterr()
    for bad, message in (("5,1,2", "--pos-weight 5.0,1.0,2.0: use a number > 0, or one per "
                          "store (2 here)"), ("5,0", "--pos-weight 5.0,0.0"),
                         ("5,x", "--pos-weight '5,x'")):
        assert main([*args, "--steps", "2", "--pos-weight", bad]) == 2
        err = capsys.readouterr().err.strip()
        assert err.count("\n") == 0 and message in err, err


def test_single_store_metadata_keeps_its_store_key(two_stores, tmp_path):
    a, _ = two_stores
    meta = demseis.train(a, out=tmp_path / "one.pt", steps=1, base=4, batch=4, device="cpu",
                         threads=1, progress=False, log=None)
    assert meta["store"] == str(a.resolve()) and meta["stores"] == [meta["store"]]
    assert meta["weights"] == [1.0] and len(meta["per_store"]) == 1
    assert meta["per_store"][0]["f1"] == meta["f1"]


def test_bad_weights_and_stores_are_one_line(two_stores, tmp_path, capsys):
    a, b = two_stores
    out = ["--out", str(tmp_path / "m.pt"), *FAST]
    for extra, message in ((["--weights", "1"], "1 weight(s) for 2 store(s)"),
                           (["--weights", "1,0"], "weight 2 is 0.0"),
                           (["--weights", "1,-2"], "weight 2 is -2.0"),
                           (["--weights", "2,x"], "'2,x'"),
                           (["--weights", "1,2,3"], "3 weight(s)")):
        assert main(["train", str(a), str(b), *extra, *out]) == 2
        err = capsys.readouterr().err.strip()
        assert err.count("\n") == 0 and message in err, err
    assert main(["train", str(a), str(a), *out]) == 2
    assert "given twice" in capsys.readouterr().err
    assert main(["train", str(a), str(tmp_path / "none.zarr"), *out]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "none.zarr" in err
    with pytest.raises(InputError, match="weight 1"):
        demseis.train([a, b], out=tmp_path / "m.pt", weights=[0, 1])
    assert not (tmp_path / "m.pt").exists()


def test_a_weight_of_fault_pixels_per_store(tmp_path):
    """pos_weight=[wa, wb] weighs each sample's fault pixels by its own store's weight: equal
    weights train what one weight trains, and the weight of a store without fault pixels
    changes nothing, while the other store's weight does."""
    a, empty = tmp_path / "a.zarr", tmp_path / "empty.zarr"
    toy_store(a)
    toy_store(empty, n_shards=4, fault_fn=np.zeros_like)
    kw = dict(steps=4, crop=16, batch=4, base=4, threads=1, device="cpu", log=None)

    def params(stores, pos_weight):
        m, info = train_unet(stores, pos_weight=pos_weight, **kw)
        return np.concatenate([p.detach().numpy().ravel() for p in m.parameters()]), info

    one, _ = params([a, empty], 7.0)
    both, info = params([a, empty], [7.0, 7.0])
    np.testing.assert_array_equal(one, both)
    assert info["pos_weight"] == [7.0, 7.0]
    # the empty store's samples have no fault pixel for its weight to weigh
    low, _ = params([a, empty], [7.0, 1.0])
    high, _ = params([a, empty], [7.0, 40.0])
    np.testing.assert_array_equal(low, both)
    np.testing.assert_array_equal(high, both)
    other, _ = params([a, empty], [1.0, 7.0])
    assert np.abs(other - both).max() > 1e-4
    # one store: a list of one is its weight
    single, _ = params(a, [7.0])
    np.testing.assert_array_equal(single, params(a, 7.0)[0])
    for bad, message in (([7.0], "1 weight"), ([7.0, 1.0, 2.0], "3 weight"), ([7.0, 0.0], "0.0"),
                         ([float("nan"), 1.0], "nan")):
        with pytest.raises(InputError, match=message) as err:
            train_unet([a, empty], pos_weight=bad, **kw)
        assert "\n" not in str(err.value)
