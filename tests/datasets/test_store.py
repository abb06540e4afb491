"""Store creation, shard writing, round trips, resume semantics, errors, determinism."""

from __future__ import annotations

import hashlib
import json
from pathlib import Path

import numpy as np
import pytest
import zarr
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import demseis.datasets.write as write
from demseis.datasets import (
    SCHEMA_VERSION,
    create_store,
    finalize_store,
    open_store,
    read_layout,
    read_params,
    read_particles,
    read_store_attrs,
    record_failures,
    shard_status,
    stored_config,
    to_xarray,
    validate_store,
    write_shard,
)
from demseis.datasets._shardio import RawShardReader, raw_shard_layout
from demseis.datasets.records import fill_value_for
from demseis.errors import InputError, StoreError
from tests.datasets._helpers import ARRAYS, PARAMS, grid_attrs, make_store, shard_data, zarr_params


def _tree_digest(path: Path) -> dict[str, str]:
    return {
        str(f.relative_to(path)): hashlib.sha256(f.read_bytes()).hexdigest()
        for f in sorted(path.rglob("*")) if f.is_file()
    }


@settings(max_examples=12, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(
    h=st.integers(1, 17), w=st.integers(1, 23), s=st.integers(1, 4), n_shards=st.integers(1, 3),
    with_impedance=st.booleans(), data_seed=st.integers(0, 2**16), order_seed=st.integers(0, 99),
)
def test_round_trip_random_shapes(tmp_path_factory, h, w, s, n_shards, with_impedance, data_seed,
                                  order_seed):
    path = tmp_path_factory.mktemp("rt") / "s.zarr"
    arrays = ARRAYS + (("impedance",) if with_impedance else ())
    create_store(path, n_shards=n_shards, samples_per_shard=s, shape=(h, w), arrays=list(arrays),
                 params=PARAMS, attrs={"config": {"k": [1, 2]}, "grid": grid_attrs((h, w))})
    expected = {}
    for k in np.random.default_rng(order_seed).permutation(n_shards).tolist():
        expected[k] = shard_data(k, s, (h, w), arrays, seed=data_seed)
        write_shard(path, k, *expected[k])
    finalize_store(path)
    group = open_store(path)
    assert shard_status(path).tolist() == [1] * n_shards
    for k, (data, params, parts) in expected.items():
        sl = slice(k * s, (k + 1) * s)
        for name, arr in data.items():
            got = group[name][sl]
            assert got.dtype == arr.dtype
            np.testing.assert_array_equal(got, arr)
        stored = zarr_params(path)
        assert all(np.array_equal(read_params(path)[n][sl], stored[n][sl]) for n in params)
        for name, v in params.items():
            got = stored[name][sl]
            np.testing.assert_array_equal(got, np.asarray(v).astype(PARAMS[name]))
        back = read_particles(path, k)
        assert len(back) == len(parts)
        for a, b in zip(parts, back):
            assert (a.index, a.step, a.throw_m) == (b.index, b.step, b.throw_m)
            for f in ("ids", "xy", "radius", "layer", "deposited"):
                np.testing.assert_array_equal(getattr(a, f), getattr(b, f))
                assert getattr(a, f).dtype == getattr(b, f).dtype
    # the fast shard reader sees exactly what zarr sees
    for name in arrays:
        raw = raw_shard_layout(group[name])
        assert raw is not None
        reader = RawShardReader(path / name, *raw[:3], fill_value_for(group[name].dtype), raw[3])
        for k, (data, _, _) in expected.items():
            for i in range(s):
                np.testing.assert_array_equal(
                    reader.window(k * s + i, slice(0, h), slice(1 % w, w)), data[name][i, :, 1 % w:]
                )


def test_layout_and_attrs(tmp_path):
    path = make_store(tmp_path / "s.zarr", n_shards=3, s=5, shape=(8, 9))
    lay = read_layout(path)
    assert (lay.n_shards, lay.samples_per_shard, lay.shape, lay.n_samples) == (3, 5, (8, 9), 15)
    assert list(lay.arrays) == list(ARRAYS)
    assert {k: str(v) for k, v in lay.params.items()} == dict(sorted(PARAMS.items()))
    attrs = read_store_attrs(path)
    assert attrs["demseis"]["schema_version"] == SCHEMA_VERSION
    assert "package_version" in attrs["demseis"]
    assert stored_config(path) == {"seed": 0}
    g = open_store(path)
    assert g["seismic"].chunks == (1, 8, 9) and g["seismic"].shards == (5, 8, 9)
    assert g["shard_done"].chunks == (1,)
    assert g["params"].chunks == (5, g["params"].shape[1])  # one chunk of records per shard
    assert lay.table and set(lay.columns) == set(PARAMS)


def test_same_inputs_same_bytes_whatever_the_write_order(tmp_path):
    a = make_store(tmp_path / "a.zarr", write=[0, 1, 2, 3])
    b = make_store(tmp_path / "b.zarr", write=[3, 1, 0, 2])
    write_shard(b, 1, *shard_data(1, 6, (24, 32)))  # a retry rewrites identical bytes
    for p in (a, b):
        record_failures(p, {})
        finalize_store(p)
    da, db = _tree_digest(a), _tree_digest(b)
    assert da == db
    assert "zarr.json" in da and len(da) > 30


def test_resume_keeps_done_shards_and_checks_layout(tmp_path):
    path = make_store(tmp_path / "s.zarr", write=[0, 2])
    kw = dict(n_shards=4, samples_per_shard=6, shape=(24, 32), arrays=list(ARRAYS), params=PARAMS)
    create_store(path, **kw, attrs={"config": {"other": 1}})  # resume: nothing is replaced
    assert shard_status(path).tolist() == [1, 0, 1, 0]
    assert stored_config(path) == {"seed": 0}
    with pytest.raises(StoreError, match="samples_per_shard"):
        create_store(path, **{**kw, "samples_per_shard": 7})
    with pytest.raises(StoreError, match="params"):
        create_store(path, **{**kw, "params": {"run_id": "int64"}})
    create_store(path, **kw, overwrite=True)
    assert shard_status(path).tolist() == [0, 0, 0, 0]


def test_refuses_to_touch_foreign_directories(tmp_path):
    foreign = tmp_path / "mine"
    foreign.mkdir()
    (foreign / "thesis.tex").write_text("precious")
    kw = dict(n_shards=1, samples_per_shard=1, shape=(2, 2))
    for overwrite in (False, True):
        with pytest.raises(StoreError, match="not a demseis store"):
            create_store(foreign, **kw, overwrite=overwrite)
    assert (foreign / "thesis.tex").read_text() == "precious"
    zarr.create_group(tmp_path / "other.zarr", attributes={"x": 1})
    with pytest.raises(StoreError, match="not a demseis store"):
        create_store(tmp_path / "other.zarr", **kw, overwrite=True)
    (tmp_path / "file").write_text("x")
    with pytest.raises(StoreError, match="file"):
        create_store(tmp_path / "file", **kw)
    empty = tmp_path / "empty"
    empty.mkdir()
    create_store(empty, **kw)  # an empty directory is fine
    assert shard_status(empty).tolist() == [0]


@pytest.mark.parametrize(
    "setup, message",
    [
        (lambda p: None, "does not exist"),
        (lambda p: p.mkdir(), "not a Zarr store"),
        (lambda p: zarr.create_group(p, attributes={"a": 1}), "not written by demseis"),
        (lambda p: zarr.create_group(p, zarr_format=2), "not a Zarr store|Zarr v3"),
    ],
)
def test_open_store_errors(tmp_path, setup, message):
    path = tmp_path / "x.zarr"
    setup(path)
    with pytest.raises(StoreError, match=message):
        open_store(path)


@pytest.mark.parametrize("version, message", [
    (99, r"schema version 99 but this demseis .* reads schema version 3$"),
    (2, r"schema version 2 but this demseis .* reads schema version 3; convert it with `demseis "
        r"migrate "),
    (1, r"schema version 1 but this demseis .* reads schema version 3; it was written by an "
        r"older demseis: regenerate it"),
])
def test_open_store_other_schema_version(tmp_path, version, message):
    path = make_store(tmp_path / "s.zarr", n_shards=1, s=1, shape=(2, 3))
    meta = json.loads((path / "zarr.json").read_text())
    meta["attributes"]["demseis"]["schema_version"] = version
    (path / "zarr.json").write_text(json.dumps(meta))
    for read in (open_store, to_xarray):
        with pytest.raises(StoreError, match=message):
            read(path)


def test_write_shard_rejects_bad_input(tmp_path):
    path = make_store(tmp_path / "s.zarr", write=[])
    d, p, parts = shard_data(0, 6, (24, 32))

    def bad(**changes):
        arrays = {**d, **changes.pop("arrays", {})}
        params = {**p, **changes.pop("params", {})}
        return arrays, params

    cases = [
        (bad(arrays={"seismic": d["seismic"][:, :5]}), "shape"),
        (bad(arrays={"fault": d["fault"] * 2}), "fault.*allowed \\[0, 1\\]"),
        (bad(arrays={"damage": d["damage"] + 1}), "damage.*allowed \\[0, 2\\]"),
        (bad(arrays={"strain": np.where(d["fault"] > 0, np.nan, d["strain"])}), "NaN"),
        (bad(params={"run_id": np.arange(6)}), "constant"),
        (bad(params={"freq_hz": np.full(6, np.nan)}), "NaN"),
        (bad(params={"snapshot": np.full(6, 0.5)}), "fit"),
    ]
    for (arrays, params), msg in cases:
        with pytest.raises(InputError, match=msg):
            write_shard(path, 0, arrays, params)
    with pytest.raises(InputError, match="exactly"):
        write_shard(path, 0, {k: v for k, v in d.items() if k != "layer"}, p)
    with pytest.raises(InputError, match="exactly"):
        write_shard(path, 0, d, {**p, "dip_deg": np.zeros(6)})
    with pytest.raises(InputError, match="shard_index"):
        write_shard(path, 4, d, p)
    assert shard_status(path).tolist() == [0, 0, 0, 0]  # nothing was marked done


def test_rewrite_clears_done_flag_first(tmp_path, monkeypatch):
    path = make_store(tmp_path / "s.zarr", write=[1])
    seen = []
    real = write._write_array

    def spy(root, arr, sel, data):
        # a flag set to the fill value (0) has no chunk file: no file means "not done"
        seen.append(int((path / "shard_done" / "c" / "1").exists()))
        real(root, arr, sel, data)

    monkeypatch.setattr(write, "_write_array", spy)
    write_shard(path, 1, *shard_data(1, 6, (24, 32)))
    assert seen and set(seen) == {0}  # never done while its data is being replaced
    assert shard_status(path)[1] == 1


def test_record_failures_and_finalize(tmp_path):
    path = make_store(tmp_path / "s.zarr", write=[0])
    assert record_failures(path, {2: "SimulationError: NaN in velocities", 3: "boom"}) == {
        "2": "SimulationError: NaN in velocities", "3": "boom"}
    write_shard(path, 3, *shard_data(3, 6, (24, 32)))  # a resumed run fixes shard 3
    assert record_failures(path, {1: "later"}) == {"1": "later", "2": "SimulationError: NaN in velocities"}
    with pytest.raises(InputError, match="outside"):
        record_failures(path, {9: "x"})
    finalize_store(path)
    meta = json.loads((path / "zarr.json").read_text())
    assert "consolidated_metadata" in meta
    assert "seismic" in meta["consolidated_metadata"]["metadata"]
    assert open_store(path).attrs["failures"]["1"] == "later"


def test_read_particles_missing_run(tmp_path):
    path = make_store(tmp_path / "s.zarr", write=[0])
    with pytest.raises(StoreError, match="no particle snapshots for run 1"):
        read_particles(path, 1)


def test_a_particle_group_is_replaced_whole_and_scratch_of_a_killed_writer_is_harmless(tmp_path):
    """Shard 1's writer was killed while it replaced its run's particles (between the two
    renames), shard 2's just after it made a directory of its new group: no group for run 1, its
    new group under one hidden name and the old under another, run 2's half begun. The store
    validates and opens, readers see run 1 absent (not half written), and the resumed shards
    clear the scratch."""
    import shutil

    from demseis.datasets import validate_store
    from demseis.datasets.xarray_io import to_xarray

    path = make_store(tmp_path / "s.zarr", n_shards=3, write=[0])
    write.write_particles(path, 1, shard_data(1, 6, (24, 32))[2])  # an earlier attempt
    final = path / "particles" / "run_00001"
    shutil.copytree(final, final.with_name(".run_00001.partial"))
    final.rename(final.with_name(".run_00001.old"))
    (path / "particles" / ".run_00002.partial" / "ids").mkdir(parents=True)
    assert shard_status(path).tolist() == [1, 0, 0]
    with pytest.raises(StoreError, match="no particle snapshots for run 1"):
        read_particles(path, 1)
    report = validate_store(path)
    assert report.ok and report.n_done == 1, report.problems
    to_xarray(path)
    expected = {k: shard_data(k, 6, (24, 32)) for k in (1, 2)}
    for k, data in expected.items():
        write_shard(path, k, *data)
    assert sorted(p.name for p in (path / "particles").iterdir()) == [
        "run_00000", "run_00001", "run_00002", "zarr.json"]
    for k, data in expected.items():
        np.testing.assert_array_equal(read_particles(path, k)[-1].xy, data[2][-1].xy)
    report = validate_store(path)
    assert report.ok and report.n_done == 3, report.problems


def test_layer_minus_one_means_no_rock_and_is_valid(tmp_path):
    path = make_store(tmp_path / "s.zarr", n_shards=1, write=[])
    d, p, parts = shard_data(0, 6, (24, 32))
    d["layer"][:, :3] = -1  # rows above the free surface
    write_shard(path, 0, d, p, parts)
    assert validate_store(path).ok
    np.testing.assert_array_equal(open_store(path)["layer"][:, :3], -1)
    d["layer"][0, 5, 5] = -2
    with pytest.raises(InputError, match="layer.*allowed \\[-1, 32767\\]"):
        write_shard(path, 0, d, p, parts)


def test_a_store_written_before_a_parameter_existed_resumes_with_it(tmp_path):
    """create_store with one more parameter: the table is declared anew and the done shards
    become pending (their records lack it), so the sweep computes them again; the samples
    stay until then."""
    old = {k: v for k, v in PARAMS.items() if k != "snr_db"}
    path = make_store(tmp_path / "s.zarr", params=old)
    seismic = (path / "seismic" / "c" / "1" / "0" / "0").read_bytes()
    create_store(path, n_shards=4, samples_per_shard=6, shape=(24, 32), arrays=list(ARRAYS),
                 params=PARAMS)
    assert shard_status(path).tolist() == [0, 0, 0, 0]
    assert set(read_layout(path).params) == set(PARAMS)
    assert (path / "seismic" / "c" / "1" / "0" / "0").read_bytes() == seismic
    for k in range(4):
        write_shard(path, k, *shard_data(k, 6, (24, 32)))
    assert validate_store(path).ok
    np.testing.assert_array_equal(read_params(path)["snr_db"], zarr_params(path)["snr_db"])
    with pytest.raises(StoreError, match="another layout"):  # fewer parameters: refused
        create_store(path, n_shards=4, samples_per_shard=6, shape=(24, 32), arrays=list(ARRAYS),
                     params=old)
