"""benchmarks/cross_domain.py end to end on tiny DEM and kinematic stores on the CPU, with a
SEG-Y + mask field set; and the mixed / augmented / AMP options of the shared training loop."""

from __future__ import annotations

import json
import runpy
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("torch")

from demseis.errors import InputError  # noqa: E402
from tests.generator._helpers import kinematic_cfg  # noqa: E402

BENCH = Path(__file__).resolve().parents[2] / "benchmarks" / "cross_domain.py"


@pytest.fixture(scope="module")
def bench():
    return runpy.run_path(str(BENCH), run_name="cross_domain")


@pytest.fixture(scope="module")
def stores(tmp_path_factory, tiny_store):
    import demseis
    from demseis.seismic.segy import write_segy

    root = tmp_path_factory.mktemp("xd")
    kin = root / "kin.zarr"
    demseis.generate(kinematic_cfg(), out=kin, workers=0)
    s = demseis.open(kin).sample(5)
    assert s["fault"].any()
    write_segy(s["seismic"] * 1000.0, root / "field.sgy", x0_m=0.0, cell_m=10.0, top_m=0.0)
    np.save(root / "field_mask.npy", s["fault"])
    return tiny_store, kin, root


def test_whole_benchmark_on_tiny_stores(bench, stores, tmp_path, capsys):
    dem, kin, root = stores
    results, fig = tmp_path / "xd.json", tmp_path / "xd.png"
    argv = ["--dem", str(dem), "--kin", str(kin), "--field",
            f"{root / 'field.sgy'}:{root / 'field_mask.npy'}", "--seeds", "0", "1", "2",
            "--steps", "2", "--base", "4", "--crop", "32", "--batch", "2", "--threads", "1",
            "--device", "cpu", "--test-fraction", "0.5", "--max-eval", "4",
            "--results", str(results), "--figure", str(fig)]
    assert bench["main"](argv) == 0
    line = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    m = line["matrix"]
    assert set(m) == {f"{a}->{b}" for a in ("dem", "kinematic", "mix")
                      for b in ("dem", "kinematic", "field")}
    for cell in m.values():
        assert cell["seeds"] == [0, 1, 2]
        for k in ("precision", "recall", "f1", "ap"):
            for t in (2, 4):
                v = cell[f"{k}_tol{t}"]
                assert v["n"] == 3 and 0.0 <= v["mean"] <= 1.0 and v["std"] >= 0.0
    assert fig.stat().st_size > 0
    saved = json.loads(results.read_text())
    assert len(saved["cells"]) == 27
    # a second visit with one more seed trains only that seed, and the matrix grows to 4
    argv[argv.index("--seeds") + 1: argv.index("--seeds") + 4] = ["3"]
    assert bench["main"](argv) == 0
    line = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    assert len(json.loads(results.read_text())["cells"]) == 36
    assert line["matrix"]["mix->field"]["seeds"] == [0, 1, 2, 3]


def test_field_input_errors(bench, stores, tmp_path):
    _, _, root = stores
    np.save(tmp_path / "bad.npy", np.ones((3, 3)))  # a mask, of another shape
    with pytest.raises(InputError, match="shape"):
        bench["read_field"]([f"{root / 'field.sgy'}:{tmp_path / 'bad.npy'}"])
    with pytest.raises(InputError, match="not a file"):
        bench["read_field"]([f"{tmp_path / 'none.sgy'}:{tmp_path / 'bad.npy'}"])
    (tmp_path / "junk.sgy").write_bytes(b"x" * 100)
    with pytest.raises(InputError, match="SEG-Y"):
        bench["read_field"]([f"{tmp_path / 'junk.sgy'}:{tmp_path / 'bad.npy'}"])


def test_field_reader_reads_back_the_section(bench, stores):
    import demseis

    _, kin, root = stores
    (sec, mask), = bench["read_field"]([f"{root / 'field.sgy'}:{root / 'field_mask.npy'}"])
    s = demseis.open(kin).sample(5)
    np.testing.assert_allclose(sec, s["seismic"] * 1000.0, rtol=1e-6)
    np.testing.assert_array_equal(mask, s["fault"] > 0)


def test_mixed_training_draws_from_both_stores(stores):
    from demseis.learning.train import train_unet

    dem, kin, _ = stores
    kw = dict(steps=2, crop=32, batch=2, base=4, threads=1, device="cpu", log=None,
              augment=True, amp=True, split_fractions=(0.5, 0.0, 0.5))
    _, info = train_unet([dem, kin], **kw)
    _, one = train_unet(dem, **kw)
    assert info["n_samples"] == one["n_samples"] + train_unet(kin, **kw)[1]["n_samples"]
    assert info["n_runs"] == 2 * one["n_runs"]
    assert info["amp"] is False  # AMP is CUDA only
    assert info["augment"] is True


def test_validation_keeps_the_best_model_and_stops_early(stores, tmp_path):
    import torch

    from demseis.learning.train import build_unet, train_unet

    _, kin, _ = stores
    ckpt = tmp_path / "best.pt"
    model, info = train_unet(kin, steps=12, crop=32, batch=2, base=4, threads=1, device="cpu",
                             log=None, split_fractions=(0.5, 0.5, 0.0), val_every=2,
                             patience=2, checkpoint=str(ckpt), progress=True)
    hist = info["val_history"]
    assert [s for s, _ in hist] == list(range(2, info["steps"] + 1, 2))
    assert info["best_val_f1"] == max(f for _, f in hist)
    assert info["best_step"] in [s for s, f in hist if f == info["best_val_f1"]]
    assert info["stopped_early"] == (info["steps"] < 12)
    if info["stopped_early"]:  # two evaluations in a row without improvement
        assert all(f <= info["best_val_f1"] for _, f in hist[-2:]) and hist[-1][0] - 4 >= 0
    saved = build_unet(4)
    saved.load_state_dict(torch.load(ckpt))
    for k, v in model.state_dict().items():  # the returned model is the best (checkpointed) one
        assert torch.equal(v, saved.state_dict()[k]), k
    with pytest.raises(InputError, match="val split is empty"):
        train_unet(kin, steps=1, crop=32, batch=2, base=4, device="cpu", log=None,
                   split_fractions=(1.0, 0.0, 0.0), val_every=1)
