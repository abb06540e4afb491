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


def _count_identity_reads(monkeypatch) -> list:
    calls = []
    real = index.chunk_identity
    monkeypatch.setattr(index, "chunk_identity", lambda f: calls.append(f) or real(f))
    return calls


def test_a_current_index_is_read_with_one_chunk_read_per_block(tmp_path, monkeypatch):
    """After a full update nothing in the table's directory changed: each block's entries are
    served after one of them matches its chunk, not one read per shard."""
    done = [*range(0, 256, 13), 259]  # 20 shards in block 0, one in block 1
    path = make_store(tmp_path / "s.zarr", n_shards=260, s=1, shape=(2, 2), write=done)
    assert not index.index_current(path)  # chunks written since the store was made
    update_index(path, shards=[0])
    assert not index.index_current(path)  # an update of some blocks is not a full one
    update_index(path)
    assert index.index_current(path)
    want = zarr_params(path)
    calls = _count_identity_reads(monkeypatch)
    with monkeypatch.context() as m:
        _no_chunk_reads(m)
        got = read_done_params(path)
    assert got.shards.tolist() == done
    for name in PARAMS:
        np.testing.assert_array_equal(got.values[name], want[name][got.samples])
    assert len(calls) == 2  # blocks 0 (shards 0..255) and 1 (256..259)
    # a chunk written since: the index is not current and every entry is checked again
    d, p, parts = shard_data(13, 1, (2, 2))
    p["freq_hz"] = np.full(1, 33.0)
    write_shard(path, 13, d, p, parts)
    assert not index.index_current(path)
    calls.clear()
    got = read_done_params(path)
    np.testing.assert_array_equal(got.values["freq_hz"], zarr_params(path)["freq_hz"][done])
    assert got.values["freq_hz"][1] == 33.0
    assert len(calls) == len(done)
    update_index(path)  # current again (the end of the next sweep, or `demseis migrate`)
    assert index.index_current(path)
    assert read_done_params(path).values["freq_hz"][1] == 33.0


def test_an_index_from_another_store_serves_nothing(tmp_path):
    path = make_store(tmp_path / "s.zarr")
    update_index(path)
    other = make_store(tmp_path / "o.zarr", seed=1)
    update_index(other)
    for name in ("params_index", "params_index_files"):
        (path / name / "c.0.0").write_bytes((other / name / "c.0.0").read_bytes())
    assert index.index_current(path)  # the table did not change: the spot check catches it
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


def _tiny_kinematic_sweep(n_runs: int):
    """(the sweep driver module, the ``tiny`` preset's config with the kinematic engine)."""
    import demseis.generator.sweep.driver as sweep
    from demseis.generator.config.settings import load_config, parse_config

    raw = load_config(preset="tiny").to_dict()
    raw["model"]["engine"] = "kinematic"
    raw["sweep"]["n_runs"] = n_runs
    return sweep, parse_config(raw)


def test_the_sweep_updates_the_index_as_runs_finish(tmp_path, monkeypatch):
    """With the update interval at 0 the driver updates after every run; finalize_store's
    update is switched off, so the index the store ends with is the sweep's."""
    import demseis.datasets.status as status

    sweep, cfg = _tiny_kinematic_sweep(3)
    calls = []
    real = sweep.update_index
    monkeypatch.setattr(sweep, "INDEX_EVERY_S", 0.0)
    monkeypatch.setattr(sweep, "update_index", lambda p, **k: calls.append(k) or real(p, **k))
    monkeypatch.setattr(status, "update_index", lambda *a, **k: 0)
    out = tmp_path / "g.zarr"
    sweep.run_sweep(cfg, out, workers=0, progress=False)
    n = cfg.sweep.n_runs
    assert len(calls) == n and [c["shards"] for c in calls] == [[k] for k in range(n)]
    with monkeypatch.context() as m:
        _no_chunk_reads(m)
        assert read_done_params(out).shards.tolist() == list(range(n))


def test_a_sweep_drops_the_entries_of_the_runs_it_writes_again_first(tmp_path, monkeypatch):
    """A run whose done flag is gone is written again; before it is, the index no longer names
    its chunk (so no reader takes the old records while the new chunk is written), and the
    sweep's end leaves the index current."""
    sweep, cfg = _tiny_kinematic_sweep(3)
    out = tmp_path / "g.zarr"
    sweep.run_sweep(cfg, out, workers=0, progress=False)
    assert index.index_current(out)
    metas = array_metas(out)
    assert index.read_block(out, metas, 0).files[1].all()
    (out / "shard_done" / "c" / "1").unlink()
    seen = []
    real = sweep.shard_task

    def task(store, cfg_dict, shard):
        seen.append((shard, index.read_block(out, metas, 0).files[shard].tolist()))
        return real(store, cfg_dict, shard)

    monkeypatch.setattr(sweep, "shard_task", task)
    sweep.run_sweep(cfg, out, workers=0, progress=False)
    assert seen == [(1, [0, 0])]
    assert index.read_block(out, metas, 0).files.all()
    assert index.index_current(out)
    assert validate_store(out).ok


@pytest.mark.parametrize("n_shards", [1, 256, 257])
def test_block_edges(tmp_path, n_shards):
    path = make_store(tmp_path / "s.zarr", n_shards=n_shards, s=1, shape=(2, 2),
                      write=[0, n_shards - 1])
    update_index(path)
    assert read_done_params(path).shards.tolist() == sorted({0, n_shards - 1})
    assert validate_store(path).ok
