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

from demseis.diagnostics.toys import faulted_section  # noqa: E402

EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "train_unet.py"


def _tiny_store(path, n_shards=5, per_shard=4, h=32, w=32, fault_fn=None, seismic_fn=None):
    """Faulted sections written with demseis.datasets; ``fault_fn`` / ``seismic_fn`` (arrays of
    one shard in, out) make a store with other labels or other seismic of the same samples."""
    datasets.create_store(path, n_shards=n_shards, samples_per_shard=per_shard, shape=(h, w),
                          arrays=["seismic", "fault"],
                          params={"run_id": "int32", "freq_hz": "float32",
                                  "snr_db": "float32", "dip_deg": "float32"},
                          attrs={"config": {}, "grid": {"x0_m": 0.0, "top_m": 0.0,
                                                        "cell_m": 10.0, "nz": h, "nx": w}})
    for k in range(n_shards):
        dip = 55.0 + 5 * k
        secs, labs = zip(*(faulted_section(nz=h, nx=w, dip_deg=dip, seed=10 * k + j,
                                           noise=0.3 * (j % 2)) for j in range(per_shard)))
        secs, labs = np.stack(secs), np.stack(labs)
        if fault_fn is not None:
            labs = fault_fn(labs)
        if seismic_fn is not None:
            secs = seismic_fn(secs)
        datasets.write_shard(path, k, {"seismic": secs, "fault": labs},
                             {"run_id": k, "freq_hz": np.array([20.0, 20.0, 40.0, 40.0]),
                              "snr_db": np.array([np.inf, 10.0, np.inf, 10.0]),
                              "dip_deg": dip})


def test_train_unet_example_runs_and_scores(tmp_path, capsys):
    store = tmp_path / "tiny.zarr"
    _tiny_store(store)
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
