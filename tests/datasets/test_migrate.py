"""`demseis migrate`: a store of schema version 2 (an array per parameter) becomes a store of
this version with the same sample bytes, the same parameters, and the table bytes a store
written by this version has."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import numpy as np
import pytest
import zarr

import demseis.datasets.migrate as migrate
from demseis.cli import main
from demseis.datasets import (
    FaultSegDataset,
    finalize_store,
    migrate_store,
    read_params,
    read_sample,
    shard_status,
    validate_store,
    write_shard,
)
from demseis.datasets._nodes import small_compressors
from demseis.datasets.records import fill_value_for
from demseis.errors import StoreError
from tests.datasets._helpers import PARAMS, digest, make_store, shard_data, zarr_params

S, SHAPE = 6, (24, 32)


def downgrade_to_v2(path: Path) -> None:
    """The store at ``path`` as schema version 2 wrote it: one zarr array per parameter
    (``params/<name>``, chunks of one shard, zstd + crc32c, the fill value where a shard is
    not done), no table, no index. Written with zarr, from the values zarr reads."""
    values = zarr_params(path)
    table = zarr.open_group(path, mode="r", use_consolidated=False)["params"]
    columns = table.attrs["demseis"]["columns"]
    done = np.repeat(shard_status(path) == 1, S)
    for name in ("params", "params_index", "params_index_files"):
        shutil.rmtree(path / name)
    root = zarr.open_group(path, mode="r+", use_consolidated=False)
    group = root.create_group("params")
    for col in columns:
        dtype = np.dtype(col["dtype"]).newbyteorder("=")
        attrs = {k: v for k, v in col.items() if k not in ("name", "dtype")}
        arr = group.create_array(col["name"], shape=values[col["name"]].shape, dtype=dtype,
                                 chunks=(S,), fill_value=fill_value_for(dtype),
                                 compressors=small_compressors(), dimension_names=("sample",),
                                 attributes=attrs)
        v = np.where(done, values[col["name"]], fill_value_for(dtype)).astype(dtype)
        arr[:] = v
    meta = json.loads((path / "zarr.json").read_text())
    meta["attributes"]["demseis"]["schema_version"] = 2
    meta.pop("consolidated_metadata", None)
    (path / "zarr.json").write_text(json.dumps(meta))


def _store(tmp_path: Path, name: str, write=(0, 2, 3)) -> Path:
    path = make_store(tmp_path / name, n_shards=4, s=S, shape=SHAPE, write=list(write))
    finalize_store(path)
    return path


def _data_files(d: dict[str, str]) -> dict[str, str]:
    """Digests of the sample arrays, done flags and particles (what migrate must not touch)."""
    return {k: v for k, v in d.items() if not k.startswith(("params", ".migrate", "zarr.json"))}


def test_a_v2_store_is_refused_with_the_migrate_command(tmp_path):
    path = _store(tmp_path, "s.zarr")
    downgrade_to_v2(path)
    with pytest.raises(StoreError, match="schema version 2 .* `demseis migrate "):
        read_params(path)


def test_migrate_keeps_every_byte_of_the_samples_and_gives_this_versions_table(tmp_path, capsys):
    ref = _store(tmp_path, "ref.zarr")
    path = _store(tmp_path, "old.zarr")
    downgrade_to_v2(path)
    before = digest(path)
    n_before = sum(1 for f in path.rglob("*") if f.is_file())
    assert main(["migrate", str(path)]) == 0
    out = capsys.readouterr().out
    assert "schema version 2 -> 3; parameters of 3 done run(s) moved" in out
    after = digest(path)
    assert _data_files(after) == _data_files(before)             # samples, flags, particles
    ref_d = digest(ref)
    table = {k: v for k, v in after.items() if k.startswith("params")}
    assert table == {k: v for k, v in ref_d.items() if k.startswith("params")}  # same table
    assert validate_store(path).ok
    assert shard_status(path).tolist() == [1, 0, 1, 1]
    got, want = read_params(path), read_params(ref)
    for name in PARAMS:
        np.testing.assert_array_equal(got[name], want[name])
    np.testing.assert_array_equal(read_sample(path, 13).arrays["seismic"],
                                  shard_data(2, S, SHAPE)[0]["seismic"][1])
    assert len(FaultSegDataset(path, where={"freq_hz": 40})) == 6
    assert sum(1 for f in path.rglob("*") if f.is_file()) < n_before
    write_shard(path, 1, *shard_data(1, S, SHAPE))                 # it resumes as a v3 store
    assert validate_store(path).ok
    # again on the current version: the index is rebuilt, nothing else changes
    assert main(["migrate", str(path)]) == 0
    assert "already schema version 3; index rebuilt" in capsys.readouterr().out


@pytest.mark.parametrize("stop", ["after-staging", "between-renames", "before-root"])
def test_an_interrupted_migrate_is_finished_by_running_it_again(tmp_path, monkeypatch, stop):
    ref = _store(tmp_path, "ref.zarr")
    path = _store(tmp_path, "old.zarr")
    downgrade_to_v2(path)
    before = digest(path)
    real_rename, real_put = Path.rename, migrate.put_file
    calls = []

    def rename(self, target):
        calls.append(Path(target).name)
        if stop == "between-renames" and len(calls) == 2:
            raise KeyboardInterrupt
        return real_rename(self, target)

    def put_file(f, data):
        if stop == "before-root" and Path(f).name == "zarr.json" and Path(f).parent == path:
            raise KeyboardInterrupt
        return real_put(f, data)

    def staging_done(*a, **k):
        raise KeyboardInterrupt

    monkeypatch.setattr(Path, "rename", rename)
    monkeypatch.setattr(migrate, "put_file", put_file)
    if stop == "after-staging":
        monkeypatch.setattr(migrate, "read_done_flags", staging_done)
    with pytest.raises(KeyboardInterrupt):
        migrate_store(path)
    monkeypatch.undo()
    with pytest.raises(StoreError, match="schema version 2"):  # still a v2 store
        read_params(path)
    assert _data_files(digest(path)) == _data_files(before)
    migrate_store(path)
    assert validate_store(path).ok
    d, r = digest(path), digest(ref)
    assert {k: v for k, v in d.items() if k.startswith("params")} == {
        k: v for k, v in r.items() if k.startswith("params")}
    assert not (path / ".migrate-params").exists() and not (path / ".migrate-params-v2").exists()


def test_a_v2_shard_with_a_damaged_parameter_becomes_pending(tmp_path):
    path = _store(tmp_path, "old.zarr")
    downgrade_to_v2(path)
    f = path / "params" / "freq_hz" / "c" / "2"
    data = bytearray(f.read_bytes())
    data[3] ^= 0x10
    f.write_bytes(bytes(data))
    report = migrate_store(path)
    assert report.pending == [2] and report.shards_moved == 2
    assert shard_status(path).tolist() == [1, 0, 0, 1]
    assert validate_store(path).ok


def test_migrate_refuses_what_it_cannot_convert(tmp_path):
    with pytest.raises(StoreError, match="does not exist"):
        migrate_store(tmp_path / "nope.zarr")
    path = _store(tmp_path, "s.zarr")
    meta = json.loads((path / "zarr.json").read_text())
    meta["attributes"]["demseis"]["schema_version"] = 1
    (path / "zarr.json").write_text(json.dumps(meta))
    with pytest.raises(StoreError, match="converts versions \\[2\\] to 3"):
        migrate_store(path)
