"""The index of the parameter table: readers take what it holds for the chunks it copied and
nothing else, it is rebuilt when damaged, and the sweep's driver keeps it up to date."""

from __future__ import annotations

import numpy as np
import pytest

import demseis.datasets.index as index
import demseis.datasets.table as table
from demseis.datasets import read_done_params, read_params, validate_store, write_shard
from demseis.datasets._shardio import write_block
from demseis.datasets.index import update_index
from demseis.datasets.layout import array_metas
from tests.datasets._helpers import PARAMS, make_store, shard_data, zarr_params

S, SHAPE = 6, (24, 32)


def _no_chunk_reads(monkeypatch):
    """Make every read of a shard's own table chunk fail: what still reads came from the index."""
    def fail(*a, **k):
        raise AssertionError("a table chunk was read")
    monkeypatch.setattr(table, "read_shard_records", fail)


def test_readers_take_the_indexed_records_and_only_those(tmp_path, monkeypatch):
    path = make_store(tmp_path / "s.zarr", write=[0, 1, 3])
    want = zarr_params(path)
    assert update_index(path) == 3
    assert update_index(path) == 0  # up to date: nothing rewritten
    with monkeypatch.context() as m:
        _no_chunk_reads(m)
        got = read_done_params(path)
        assert got.shards.tolist() == [0, 1, 3]
        for name in PARAMS:
            np.testing.assert_array_equal(got.values[name], want[name][got.samples])
    # a shard rewritten with other parameters: its chunk is no longer the one indexed
    d, p, parts = shard_data(1, S, SHAPE)
    p["freq_hz"] = np.full(S, 33.0)
    write_shard(path, 1, d, p, parts)
    np.testing.assert_array_equal(read_params(path)["freq_hz"][S:2 * S], 33.0)
    # a shard written since the update is read from its own chunk
    write_shard(path, 2, *shard_data(2, S, SHAPE))
    assert read_done_params(path).shards.tolist() == [0, 1, 2, 3]
    assert update_index(path) == 2  # shard 1 again, shard 2 new
    with monkeypatch.context() as m:
        _no_chunk_reads(m)
        np.testing.assert_array_equal(read_params(path)["freq_hz"], zarr_params(path)["freq_hz"])


def test_a_shard_no_longer_done_leaves_the_index(tmp_path):
    path = make_store(tmp_path / "s.zarr")
    update_index(path)
    (path / "shard_done" / "c" / "2").unlink()  # as a rewrite of the shard begins
    assert read_done_params(path).shards.tolist() == [0, 1, 3]
    assert update_index(path) == 1
    rows = index.read_block(path, array_metas(path), 0)
    assert not rows.files[2].any() and rows.files[[0, 1, 3]].all()


def test_a_damaged_index_block_is_ignored_named_and_rebuilt(tmp_path):
    path = make_store(tmp_path / "s.zarr")
    update_index(path)
    f = path / "params_index" / "c.0.0"
    data = bytearray(f.read_bytes())
    data[5] ^= 0x01
    f.write_bytes(bytes(data))
    np.testing.assert_array_equal(read_params(path)["run_id"], zarr_params(path)["run_id"])
    problems = validate_store(path).problems
    assert any("index block 0: params_index is damaged" in line for line in problems), problems
    assert update_index(path) == 4
    assert validate_store(path).ok


def test_an_index_from_another_store_serves_nothing(tmp_path):
    path = make_store(tmp_path / "s.zarr")
    update_index(path)
    other = make_store(tmp_path / "o.zarr", seed=1)
    update_index(other)
    for name in ("params_index", "params_index_files"):
        (path / name / "c.0.0").write_bytes((other / name / "c.0.0").read_bytes())
    np.testing.assert_array_equal(read_params(path)["freq_hz"], zarr_params(path)["freq_hz"])
    assert validate_store(path).ok  # nothing it holds matches a chunk: nothing is served


def test_validate_names_index_rows_that_differ_from_their_chunk(tmp_path):
    """Rows rewritten behind the identities (not an accident the checksums let through)."""
    path = make_store(tmp_path / "s.zarr")
    update_index(path)
    metas = array_metas(path)
    blk = index.read_block(path, metas, 0)
    blk.records[S + 2] ^= 0xFF  # a row of shard 1
    write_block(path, metas["params_index"], 0, blk.records, write_empty=True)
    problems = validate_store(path).problems
    assert problems == ["the index holds other parameters than the table for shards 1; "
                        f"`demseis migrate {path}` rebuilds the index"], problems


def test_update_of_some_shards_touches_only_their_blocks(tmp_path):
    path = make_store(tmp_path / "s.zarr", n_shards=300, s=1, shape=(2, 2),
                      write=[0, 5, 260, 299])
    assert update_index(path, shards=[5]) == 2  # block 0: shards 0 and 5
    assert sorted(f.name for f in (path / "params_index_files").glob("c.*")) == ["c.0.0"]
    assert update_index(path, shards=[260]) == 2
    assert sorted(f.name for f in (path / "params_index_files").glob("c.*")) == ["c.0.0", "c.1.0"]
    assert read_done_params(path).shards.tolist() == [0, 5, 260, 299]


def test_the_sweep_updates_the_index_as_runs_finish(tmp_path, monkeypatch):
    """With the update interval at 0 the driver updates after every run; finalize_store's
    update is switched off, so the index the store ends with is the sweep's."""
    import demseis.datasets.status as status
    import demseis.generator.sweep.driver as sweep
    from demseis.generator.config.settings import load_config, parse_config

    calls = []
    real = sweep.update_index
    monkeypatch.setattr(sweep, "INDEX_EVERY_S", 0.0)
    monkeypatch.setattr(sweep, "update_index", lambda p, **k: calls.append(k) or real(p, **k))
    monkeypatch.setattr(status, "update_index", lambda *a, **k: 0)
    raw = load_config(preset="tiny").to_dict()
    raw["model"]["engine"] = "kinematic"
    raw["sweep"]["n_runs"] = 3
    cfg = parse_config(raw)
    out = tmp_path / "g.zarr"
    sweep.run_sweep(cfg, out, workers=0, progress=False)
    n = cfg.sweep.n_runs
    assert len(calls) == n and [c["shards"] for c in calls] == [[k] for k in range(n)]
    with monkeypatch.context() as m:
        _no_chunk_reads(m)
        assert read_done_params(out).shards.tolist() == list(range(n))


@pytest.mark.parametrize("n_shards", [1, 256, 257])
def test_block_edges(tmp_path, n_shards):
    path = make_store(tmp_path / "s.zarr", n_shards=n_shards, s=1, shape=(2, 2),
                      write=[0, n_shards - 1])
    update_index(path)
    assert read_done_params(path).shards.tolist() == sorted({0, n_shards - 1})
    assert validate_store(path).ok
