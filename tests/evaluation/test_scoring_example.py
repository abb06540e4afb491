"""examples/train_unet.py end to end on a tiny store written with demseis.datasets."""

from __future__ import annotations

import importlib.util
import json
from pathlib import Path

import numpy as np
import pytest

datasets = pytest.importorskip("demseis.datasets")
if not hasattr(datasets, "FaultSegDataset"):
    pytest.skip("demseis.datasets.FaultSegDataset is not available", allow_module_level=True)
pytest.importorskip("torch")

from tests.evaluation._helpers import toy_store  # noqa: E402

EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "train_unet.py"


def test_train_unet_example_runs_and_scores(tmp_path, capsys):
    store = tmp_path / "tiny.zarr"
    toy_store(store)
    spec = importlib.util.spec_from_file_location("train_unet", EXAMPLE)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    out = tmp_path / "run"
    rc = mod.main([str(store), "--out-dir", str(out), "--minutes", "0.03", "--crop", "16",
                   "--batch", "4", "--threads", "1", "--by", "freq_hz,snr_db",
                   "--val-every", "2"])
    assert rc == 0
    text = capsys.readouterr().out
    assert text.count("scores of") == 2 and "freq_hz" in text
    assert "best val F1@2" in text and (out / "unet.pt").is_file()
    idx = np.load(out / "test_indices.npy")
    pred = np.load(out / "unet_test.npy")
    assert pred.shape == (idx.size, 32, 32) and 0 <= pred.min() and pred.max() <= 1
    for name in ("unet_test", "baseline_test"):
        rep = json.loads((out / f"{name}.score.json").read_text())
        assert rep["overall"]["n_samples"] == idx.size
        assert {g["by"] for g in rep["groups"]} == {"all", "freq_hz", "snr_db"}
