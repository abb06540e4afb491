"""The wavelet and processing parameters go from a config to the store: drawn per sample,
recorded with their names, applied to the seismic, and the same bytes from the same seed."""

from __future__ import annotations

import numpy as np

import demseis
from demseis.datasets import validate_store
from demseis.generator.config.settings import load_config


def _config() -> dict:
    raw = load_config(preset="tiny").to_dict()
    raw["model"]["engine"] = "kinematic"
    raw["sweep"].update({"n_runs": 2, "wavelet": ["ricker", "ormsby"], "wavelet_phase_deg": -90.0,
                         "noise_kind": "coloured", "snr_db": 10.0, "noise_slope": 1.5,
                         "trace_gain_jitter": 0.2, "quantise_bits": 8})
    return raw


def test_wavelets_and_processing_reach_the_store(tmp_path):
    store = demseis.generate(_config(), out=tmp_path / "a.zarr", workers=0, progress=False)
    assert validate_store(tmp_path / "a.zarr").ok
    samples = [store.sample(i) for i in range(len(store))]
    names = {s["wavelet"] for s in samples}
    assert names == {"ricker", "ormsby"}
    assert {s["noise_kind"] for s in samples} == {"coloured"}
    assert all(s["quantise_bits"] == 8 and s["wavelet_phase_deg"] == -90.0 for s in samples)
    for s in samples:
        sec = np.asarray(s["seismic"])
        assert np.isfinite(sec).all() and np.unique(sec).size <= 256   # an 8-bit image
    # the two wavelets of one snapshot image it differently
    by_snap: dict = {}
    for s in samples:
        by_snap.setdefault((s["run_id"], s["snapshot"]), {})[s["wavelet"]] = np.asarray(s["seismic"])
    pair = next(v for v in by_snap.values() if len(v) == 2)
    assert np.corrcoef(pair["ricker"].ravel(), pair["ormsby"].ravel())[0, 1] < 0.99
    # the same config and seed give the same bytes
    again = demseis.generate(_config(), out=tmp_path / "b.zarr", workers=0, progress=False)
    for i in range(len(store)):
        assert np.asarray(again.sample(i)["seismic"]).tobytes() == \
            np.asarray(store.sample(i)["seismic"]).tobytes()
