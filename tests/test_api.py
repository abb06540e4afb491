"""The public front door: demseis.generate / open / score and the Store."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest

import demseis
from demseis.errors import ConfigError, InputError, StoreError


@pytest.fixture(scope="module")
def tiny(tiny_store):
    """The session's tiny store (made by demseis.generate), opened again."""
    return demseis.open(tiny_store)


def test_generate_returns_a_store(tiny):
    assert isinstance(tiny, demseis.Store) and tiny.run_summary is None  # opened, not generated
    assert len(tiny) == 18 and tiny.done.all()
    text = repr(tiny)
    assert "18 samples (18 done)" in text and "seismic" in text and "10.0 m cells" in text
    assert "parameters (over done samples):" in tiny.summary()


def test_generate_on_a_complete_store_resumes_nothing(tiny_store):
    again = demseis.generate("tiny", out=tiny_store, workers=0)
    assert isinstance(again, demseis.Store) and again.path == tiny_store
    assert not again.run_summary.failed and again.done.all()
    assert again.run_summary.completed == [] and again.run_summary.done_before == 3  # runs
    assert again.run_summary.done_before == 3


def test_params_table_and_sample(tiny):
    p = tiny.params
    assert all(v.shape == (len(tiny),) for v in p.values())
    assert set(p["noise_kind"]) <= {"white", "band"}  # categorical: strings, not codes
    assert set(p["snr_db"]) == {10.0, np.inf} and set(p["dip_deg"]) == {45.0, 60.0}
    s = tiny.sample(3)
    h, w = tiny.layout.shape
    assert s["seismic"].shape == (h, w) and s["fault"].dtype == np.uint8
    assert s["freq_hz"] == p["freq_hz"][3] and isinstance(s["noise_kind"], str)
    np.testing.assert_array_equal(s["layer"], tiny.sample(3 - 18)["layer"])  # negative index
    with pytest.raises(InputError, match="out of range"):
        tiny.sample(len(tiny))


def test_open_and_views(tiny):
    same = demseis.open(tiny.path)
    np.testing.assert_array_equal(same.params["dip_deg"], tiny.params["dip_deg"])
    ds = same.torch_dataset(inputs=("seismic",), targets=("fault",))
    assert len(ds) == len(same)
    with pytest.raises(StoreError):
        demseis.open(tiny.path.parent / "missing.zarr")


def test_to_xarray(tiny):
    from demseis import datasets

    if not hasattr(datasets, "to_xarray"):
        pytest.skip("demseis.datasets.to_xarray arrives with the store branch (schema 2)")
    pytest.importorskip("xarray")
    ds = tiny.to_xarray()
    assert ds["seismic"].shape == (len(tiny), *tiny.layout.shape)


def test_score_the_labels_themselves(tiny):
    truth = np.stack([tiny.sample(i)["fault"] for i in range(len(tiny))]).astype(np.float32)
    res = demseis.score(truth, tiny, by=("snr_db",))
    assert res.overall.n_samples == len(tiny)
    if res.overall.tp + res.overall.fn:  # any fault pixels at all
        assert res.overall.f1 == pytest.approx(1.0)
    assert [r["group"] for r in res.rows] == ["all", "10", "inf"]
    with pytest.raises(InputError, match="per-sample parameters"):
        demseis.score(truth, tiny, by=("nope",))


def test_generate_takes_dicts_and_refuses_bad_configs(tiny, tmp_path):
    from demseis.generator.config.settings import load_config

    raw = load_config(preset="tiny").to_dict()
    raw["sweep"]["dip_deg"] = 85.0
    with pytest.raises(ConfigError, match=r"\[10, 80\]"):
        demseis.generate(raw, out=tmp_path / "x.zarr", workers=0)
    with pytest.raises(InputError, match="preset name"):
        demseis.generate(42, out=tmp_path / "y.zarr")
    assert not (tmp_path / "x.zarr").exists()


def test_front_door_is_lazy():
    code = ("import sys, demseis; assert 'demseis.api' not in sys.modules; demseis.open; "
            "print(sorted(m for m in ('torch', 'dask', 'matplotlib', 'xarray') if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"


def test_a_sample_keeps_its_label_arrays_and_every_parameter(tiny):
    s = tiny.sample(4)
    assert s["dip_deg"].shape == s["fault"].shape                # the label, not the parameter
    assert s["params"]["dip_deg"] == float(tiny.params["dip_deg"][4])
    assert s["snr_db"] == s["params"]["snr_db"]
