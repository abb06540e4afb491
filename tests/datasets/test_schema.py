"""The store follows demseis.schema: a label array registered there at run time is created,
checked on write, validated, summarised and read by the Dataset, with no change to
demseis.datasets; the attributes of every array are its declaration's."""

from __future__ import annotations

import numpy as np
import pytest

from demseis.datasets import (
    FaultSegDataset,
    create_store,
    open_store,
    read_layout,
    read_sample,
    validate_store,
    write_shard,
)
from demseis.datasets.read import store_summary
from demseis.errors import InputError, StoreError
from demseis.schema import SAMPLE_ARRAYS, SampleArray, register_array, stored_arrays
from tests.datasets._helpers import ARRAYS, PARAMS, grid_attrs, make_store, shard_data

S, SHAPE = 3, (8, 10)


@pytest.fixture
def wide_fault():
    """A label array the package does not know, registered for the test only."""
    spec = register_array(SampleArray(
        "fault_wide", "uint8", "label", "1", "fault mask grown by 1 cell", fill=0,
        valid_range=(0, 1), producer=lambda state: state.labels["fault"]))
    try:
        yield spec
    finally:
        SAMPLE_ARRAYS.unregister(spec.name)


def _with_wide(k: int) -> tuple[dict, dict, list]:
    data, params, parts = shard_data(k, S, SHAPE)
    data["fault_wide"] = np.maximum(data["fault"], np.roll(data["fault"], 1, axis=2))
    return data, params, parts


def test_a_registered_label_is_stored_checked_and_read(tmp_path, wide_fault):
    path = tmp_path / "s.zarr"
    create_store(path, n_shards=2, samples_per_shard=S, shape=SHAPE,
                 arrays=[*ARRAYS, "fault_wide"], params=PARAMS,
                 attrs={"config": {}, "grid": grid_attrs(SHAPE)})
    assert list(read_layout(path).arrays) == [*ARRAYS, "fault_wide"]
    data, params, parts = _with_wide(0)
    with pytest.raises(InputError, match=r"fault_wide.*allowed \[0, 1\]"):
        write_shard(path, 0, {**data, "fault_wide": data["fault_wide"] * 2}, params, parts)
    write_shard(path, 0, data, params, parts)
    write_shard(path, 1, *_with_wide(1))

    g = open_store(path)
    arr = g["fault_wide"]
    assert arr.dtype == np.uint8 and arr.fill_value == 255
    assert dict(arr.attrs) == {"units": "1", "long_name": "fault mask grown by 1 cell",
                               "demseis": {"role": "label", "fill": 0, "valid_range": [0, 1],
                                           "raw": False}}
    codecs = arr.metadata.to_dict()["codecs"][0]["configuration"]["codecs"]
    assert [c["name"] for c in codecs] == ["bytes", "blosc", "crc32c"]  # compressed: a label
    np.testing.assert_array_equal(arr[:S], data["fault_wide"])
    assert validate_store(path).ok

    np.testing.assert_array_equal(read_sample(path, 1, ["fault_wide"]).arrays["fault_wide"],
                                  data["fault_wide"][1])
    ds = FaultSegDataset(path, ("seismic",), ("fault_wide",))
    x, y = ds[1]
    assert y.dtype.is_floating_point is False and y.numpy().dtype == np.uint8
    np.testing.assert_array_equal(y.numpy(), data["fault_wide"][1])
    summary = "\n".join(store_summary(path))
    assert "fault_wide" in summary and "label, 1: fault mask grown by 1 cell" in summary

    open_store(path, "r+")["fault_wide"][1] = np.full(SHAPE, 3, np.uint8)  # past its range
    assert validate_store(path).problems == [
        "shard 0: fault_wide has values 3 outside [0, 1] in samples 1"]


def test_default_arrays_are_the_schemas_stored_arrays(tmp_path, wide_fault):
    create_store(tmp_path / "s.zarr", n_shards=1, samples_per_shard=1, shape=(2, 3))
    arrays = list(read_layout(tmp_path / "s.zarr").arrays)
    assert arrays == list(stored_arrays()) and arrays[-1] == "fault_wide"
    assert "impedance" not in arrays  # opt-in


def test_every_array_has_its_declared_attributes(tmp_path):
    names = list(SAMPLE_ARRAYS.names())
    path = make_store(tmp_path / "s.zarr", n_shards=1, s=1, shape=(2, 3), arrays=names, write=[])
    g = open_store(path)
    for name, spec in SAMPLE_ARRAYS.items():
        arr = g[name]
        assert arr.dtype == spec.np_dtype, name
        attrs = dict(arr.attrs)
        assert (attrs["units"], attrs["long_name"]) == (spec.units, spec.description), name
        attrs = attrs["demseis"]
        assert attrs["role"] == spec.role and attrs["fill"] == spec.fill and attrs["raw"] == (not spec.compressed), name
        assert attrs["valid_range"] == (None if spec.valid_range is None
                                        else list(spec.valid_range)), name
        codecs = [c["name"] for c in
                  arr.metadata.to_dict()["codecs"][0]["configuration"]["codecs"]]
        assert ("blosc" in codecs) == spec.compressed, (name, codecs)
    assert list(read_layout(path).arrays) == names  # store order is the schema's order


def test_a_plugin_array_survives_reopening_without_its_plugin(tmp_path):
    """The store describes its arrays (role, fill, valid range in their attributes): once the
    plug-in that declared ``fault_wide`` is gone, the store still lists it, validates it
    against its stored range, summarises it and serves it to the Dataset."""
    path = tmp_path / "s.zarr"
    spec = SampleArray("fault_wide", "uint8", "label", "1", "fault mask grown by 1 cell",
                       fill=0, valid_range=(0, 1), producer=lambda state: state.labels["fault"])
    with SAMPLE_ARRAYS.registered(spec.name, spec):
        create_store(path, n_shards=2, samples_per_shard=S, shape=SHAPE,
                     arrays=[*ARRAYS, "fault_wide"], params=PARAMS,
                     attrs={"config": {}, "grid": grid_attrs(SHAPE)})
        data, params, parts = _with_wide(0)
        write_shard(path, 0, data, params, parts)
    assert "fault_wide" not in SAMPLE_ARRAYS
    write_shard(path, 1, *_with_wide(1))          # a resumed run without the plug-in
    with pytest.raises(InputError, match=r"fault_wide.*allowed \[0, 1\]"):
        write_shard(path, 1, {**data, "fault_wide": data["fault_wide"] * 2}, params, parts)
    write_shard(path, 1, *_with_wide(1))
    layout = read_layout(path)
    assert list(layout.arrays) == [*ARRAYS, "fault_wide"]
    stored = layout.specs["fault_wide"]
    assert (stored.role, stored.valid_range, stored.fill, stored.description) == (
        "label", (0, 1), 0, "fault mask grown by 1 cell")
    assert validate_store(path).ok
    ds = FaultSegDataset(path, ("seismic",), ("fault_wide",))
    np.testing.assert_array_equal(ds[1][1].numpy(), data["fault_wide"][1])
    assert "label, 1: fault mask grown by 1 cell" in "\n".join(store_summary(path))
    open_store(path, "r+")["fault_wide"][1] = np.full(SHAPE, 3, np.uint8)  # past its range
    assert validate_store(path).problems == [
        "shard 0: fault_wide has values 3 outside [0, 1] in samples 1"]


def test_a_store_whose_arrays_do_not_describe_themselves_reads_as_before(tmp_path):
    """Stores written before the arrays carried their role keep the registered declarations;
    attributes that name a role but are not a declaration are a StoreError naming the array."""
    import json

    path = make_store(tmp_path / "s.zarr", n_shards=1, s=S, shape=SHAPE)
    for name in ARRAYS:
        meta_file = path / name / "zarr.json"
        meta = json.loads(meta_file.read_text())
        spec = SAMPLE_ARRAYS.get(name)
        meta["attributes"] = {"units": spec.units, "long_name": spec.description}
        meta_file.write_text(json.dumps(meta))
    layout = read_layout(path)
    assert list(layout.arrays) == list(ARRAYS)
    assert all(layout.specs[n] is SAMPLE_ARRAYS.get(n) for n in ARRAYS)
    assert validate_store(path).ok
    bad = json.loads((path / "fault" / "zarr.json").read_text())
    bad["attributes"] = {"demseis": {"role": "label", "valid_range": "0-1"}}
    (path / "fault" / "zarr.json").write_text(json.dumps(bad))
    with pytest.raises(StoreError, match="fault.*not a valid declaration"):
        read_layout(path)
