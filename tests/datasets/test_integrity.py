"""Checksums on every chunk: a bit flip in each kind of array is named by validate, refused by
the readers (FaultSegDataset, read_sample), and a resume rewrites the damaged shard to the bytes
of an undamaged store."""

from __future__ import annotations

import json
import os
import shutil
import time
from pathlib import Path

import numpy as np
import pytest

import demseis
import demseis.datasets._shardio as shardio
import demseis.datasets.dataset as dataset
from demseis.cli import main
from demseis.datasets import (FaultSegDataset, ParamSpec, damaged_shards, read_layout, read_sample,
                              shard_status, validate_store, write_shard)
from demseis.datasets.index import update_index
from demseis.errors import StoreError
from tests.datasets._helpers import PARAMS, digest, make_store, mini_config, shard_data

S, SHAPE, N_SHARDS = 6, (24, 32), 4
CAT_PARAMS = {**PARAMS, "noise_kind": ParamSpec("int8", categories=("white", "band"))}


def _make(path: Path) -> Path:
    return make_store(path, n_shards=N_SHARDS, s=S, shape=SHAPE, params=CAT_PARAMS)


@pytest.fixture(scope="module")
def pristine(tmp_path_factory):
    return _make(tmp_path_factory.mktemp("pristine") / "s.zarr")


def _copy(src: Path, dst: Path) -> Path:
    shutil.copytree(src, dst)
    return dst




def _flip(file: Path, offset: int) -> None:
    data = bytearray(file.read_bytes())
    data[offset] ^= 0x10
    file.write_bytes(bytes(data))


def _chunk_range(shard_file: Path, local: int, n_chunks: int = S) -> tuple[int, int]:
    """(offset, nbytes) of inner chunk ``local`` from the shard index at the file's end."""
    data = shard_file.read_bytes()
    index = np.frombuffer(data[-(n_chunks * 16 + 4):-4], dtype="<u8").reshape(n_chunks, 2)
    return int(index[local, 0]), int(index[local, 1])


def _resume(path: Path) -> None:
    """What a resumed sweep does: rewrite every shard that is not done or is damaged."""
    for k in np.flatnonzero(shard_status(path, verify=True) == 0).tolist():
        d, p, parts = shard_data(k, S, SHAPE, params=CAT_PARAMS)
        write_shard(path, k, d, p, parts)


# sample 2 * S + 3 (shard 2, local chunk 3)
def _flip_seismic(path):
    f = path / "seismic" / "c" / "2" / "0" / "0"
    off, n = _chunk_range(f, 3)
    _flip(f, off + n // 2)  # in the raw float values, not the checksum


def _flip_fault(path):
    f = path / "fault" / "c" / "2" / "0" / "0"
    off, n = _chunk_range(f, 3)
    _flip(f, off + n // 2)  # inside the Blosc-compressed bytes


def _flip_seismic_index(path):
    f = path / "seismic" / "c" / "2" / "0" / "0"
    _flip(f, f.stat().st_size - 20)


def _flip_param(path):
    _flip(path / "params" / "c.2.0", 3)


def _flip_particles(path):
    f = path / "particles" / "run_00002" / "x_m" / "c" / "0"
    _flip(f, f.stat().st_size // 2)


def _flip_done(path):
    _flip(path / "shard_done" / "c" / "2", 0)


CASES = {
    "seismic-raw": (_flip_seismic, "shard 2: seismic is damaged in samples 15 (crc32c mismatch)"),
    "fault-blosc": (_flip_fault, "shard 2: fault is damaged in samples 15 (crc32c mismatch)"),
    "seismic-index": (_flip_seismic_index,
                      "shard 2: seismic is damaged in samples 12..17 (index crc32c mismatch"),
    "params": (_flip_param, "shard 2: parameters are damaged in samples 12..17"),
    "particles": (_flip_particles, "shard 2: particles of run 2 are damaged: x_m (crc32c mismatch)"),
    "done-flag": (_flip_done, "shard 2: done flag is damaged (crc32c mismatch)"),
}


@pytest.mark.parametrize("case", list(CASES))
def test_bit_flip_is_named_by_validate_and_resume_restores_the_bytes(tmp_path, pristine, case):
    flip, message = CASES[case]
    path = _copy(pristine, tmp_path / "s.zarr")
    flip(path)
    report = validate_store(path)
    assert not report.ok
    assert any(message in line for line in report.problems), report.problems
    assert list(damaged_shards(path)) == [2]
    assert shard_status(path, verify=True).tolist() == [1, 1, 0, 1]
    _resume(path)
    assert validate_store(path).ok
    assert digest(path) == digest(pristine)


@pytest.mark.parametrize("case", ["seismic-raw", "fault-blosc", "seismic-index"])
def test_dataset_names_the_damaged_sample(tmp_path, pristine, case):
    path = _copy(pristine, tmp_path / "s.zarr")
    CASES[case][0](path)
    ds = FaultSegDataset(path, ("seismic",), ("fault",))
    ds.__getitems__(list(range(0, 12)))  # shards 0, 1 are intact
    with pytest.raises(StoreError, match=r"sample.* 1[25]\b.*array '(seismic|fault)'"):
        ds.__getitems__([15])
    with pytest.raises(StoreError, match=r"sample.* 1[25]\b"):
        ds[15]


def _replace_with_flipped(file: Path, offset: int) -> None:
    """Damage ``file`` the way zarr writes: a new file renamed over it (new inode)."""
    data = bytearray(file.read_bytes())
    data[offset] ^= 0x10
    tmp = file.with_name(file.name + ".tmp")
    tmp.write_bytes(bytes(data))
    os.replace(tmp, file)


@pytest.mark.parametrize("how", ["written-in-place", "replaced"])
def test_dataset_checks_a_chunk_once_and_again_after_its_file_changes(tmp_path, pristine,
                                                                       monkeypatch, how):
    """docs/store.md: a chunk's crc32c is checked on its first read by a reader, not again while
    its shard file stays the same, and again once the file is written or replaced."""
    calls = []
    real = shardio.crc_ok
    monkeypatch.setattr(shardio, "crc_ok", lambda b: calls.append(b.shape[0]) or real(b))
    path = _copy(pristine, tmp_path / "s.zarr")
    ds = FaultSegDataset(path, ("seismic",), ("fault",))
    calls.clear()  # the done flags and parameters the dataset read when it was made
    first = ds.__getitems__([15])[0][0].clone()
    assert len(calls) == 4  # seismic and fault: shard index, then chunk
    calls.clear()
    again = ds.__getitems__([15, 14])[0][0]
    assert (again == first).all()
    assert len(calls) == 2  # sample 14's seismic and fault chunks only; 15 was checked
    calls.clear()
    ds.__getitems__([14])
    assert calls == []  # both checked already, both files unchanged
    f = path / "seismic" / "c" / "2" / "0" / "0"
    off, n = _chunk_range(f, 3)
    if how == "written-in-place":
        time.sleep(0.05)  # past the file system's timestamp resolution since the copy
        _flip(f, off + n // 2)
    else:
        _replace_with_flipped(f, off + n // 2)
    with pytest.raises(StoreError, match=r"sample 15 of array 'seismic' is damaged"):
        ds.__getitems__([15])
    assert ds.__getitems__([14])  # its neighbours in the same file are checked afresh, intact
    assert validate_store(path).problems == [
        "shard 2: seismic is damaged in samples 15 (crc32c mismatch)"]


def test_dataset_keeps_its_checks_when_a_shard_map_is_dropped(tmp_path, pristine, monkeypatch):
    """A store of more shards than the reader keeps mapped is not checked again every epoch."""
    calls = []
    real = shardio.crc_ok
    monkeypatch.setattr(shardio, "crc_ok", lambda b: calls.append(b.shape[0]) or real(b))
    monkeypatch.setattr(shardio, "MAX_OPEN_SHARDS", 1)
    path = _copy(pristine, tmp_path / "s.zarr")
    ds = FaultSegDataset(path, ("seismic",), ("fault",))
    ds.__getitems__([0])
    ds.__getitems__([S])  # shard 1: shard 0's maps are dropped
    assert all(len(r._open) == 1 for r in ds._raw.values())
    calls.clear()
    ds.__getitems__([0])  # shard 0 mapped again: its index is read (and checked) again ...
    assert len(calls) == 2  # ... but not its already checked chunks
    calls.clear()
    ds.__getitems__([S + 1])  # shard 1 mapped again (its index) and a new chunk of it
    assert len(calls) == 4


def test_dataset_zarr_path_names_the_damaged_samples(tmp_path, pristine, monkeypatch):
    """Arrays read through zarr (no raw fast path) also raise StoreError, not garbage."""
    monkeypatch.setattr(dataset, "raw_shard_layout", lambda array: None)
    path = _copy(pristine, tmp_path / "s.zarr")
    _flip_fault(path)
    ds = FaultSegDataset(path, ("seismic",), ("fault",))
    with pytest.raises(StoreError, match=r"samples 15\.\.15 of array 'fault'"):
        ds.__getitems__([15])


@pytest.mark.parametrize("case", ["seismic-raw", "fault-blosc", "params"])
def test_read_sample_of_a_damaged_sample_fails_clearly(tmp_path, pristine, case):
    path = _copy(pristine, tmp_path / "s.zarr")
    CASES[case][0](path)
    neighbour = 11 if case == "params" else 14  # a parameter chunk holds the whole shard
    assert read_sample(path, neighbour).arrays["seismic"].shape == SHAPE
    with pytest.raises(StoreError, match=r"sample 15 .*damaged"):
        read_sample(path, 15)


def test_read_sample_of_a_pending_shard_fails_clearly(tmp_path):
    path = make_store(tmp_path / "s.zarr", n_shards=2, s=S, shape=SHAPE, write=[0],
                      params=CAT_PARAMS)
    with pytest.raises(StoreError, match=r"sample 7 .* shard 1, which is not done"):
        read_sample(path, 7)


def test_read_sample_values_and_category_names(pristine):
    got = read_sample(pristine, 13)
    d, p, _ = shard_data(2, S, SHAPE, params=CAT_PARAMS)
    for name, arr in d.items():
        np.testing.assert_array_equal(got.arrays[name], arr[1])
    assert got.params["noise_kind"] == ("white", "band")[int(p["noise_kind"][1])]
    assert got.params["run_id"] == 2


def test_every_chunk_has_a_crc32c(pristine):
    """Each array's codec chain ends with crc32c (inside the shards for sample arrays)."""
    metas = list(pristine.rglob("zarr.json"))
    arrays = [json.loads(m.read_text()) for m in metas]
    arrays = [m for m in arrays if m["node_type"] == "array"]
    assert len(arrays) > 20
    for meta in arrays:
        codecs = meta["codecs"]
        if codecs[0]["name"] == "sharding_indexed":
            codecs = codecs[0]["configuration"]["codecs"]
        assert codecs[-1]["name"] == "crc32c", meta


def test_plot_of_a_damaged_or_pending_sample_fails_clearly(tmp_path, capsys):
    from demseis.generator.sweep.driver import run_sweep  # the generator loads numba: only here

    out = tmp_path / "g.zarr"
    run_sweep(mini_config(), out, workers=0, progress=False)
    assert main(["plot", str(out), "--sample", "1", "--out", str(tmp_path / "ok.png")]) == 0
    f = out / "seismic" / "c" / "0" / "0" / "0"
    off, n = _chunk_range(f, 1, n_chunks=read_layout(out).samples_per_shard)
    _flip(f, off + n // 2)
    assert main(["plot", str(out), "--sample", "1", "--out", str(tmp_path / "bad.png")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "sample 1 of array 'seismic'" in err[0] and "damaged" in err[0]
    assert not (tmp_path / "bad.png").exists()
    (out / "shard_done" / "c" / "0").unlink()  # the shard is pending again
    assert main(["plot", str(out), "--sample", "0", "--out", str(tmp_path / "p.png")]) == 2
    assert "which is not done" in capsys.readouterr().err


def test_info_of_a_store_with_a_damaged_parameter_is_one_line(tmp_path, pristine, capsys):
    path = _copy(pristine, tmp_path / "s.zarr")
    assert main(["info", str(path)]) == 0
    assert update_index(path) == 4  # every done shard indexed (sweeps do it as they end)
    _flip_param(path)
    # the index holds a checksummed copy of the shard's records: readers still get them
    assert main(["info", str(path)]) == 0
    for f in (path / "params_index_files").glob("c.*"):  # without the index
        f.unlink()
    capsys.readouterr()
    assert main(["info", str(path)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "parameters of samples 12..17" in err[0]
    assert "damaged (crc32c mismatch" in err[0], err[0]


def test_store_sample_of_a_damaged_sample_fails_clearly(tmp_path, pristine):
    path = _copy(pristine, tmp_path / "s.zarr")
    _flip_seismic(path)
    store = demseis.open(path)
    assert store.sample(14)["seismic"].shape == SHAPE
    with pytest.raises(StoreError, match=r"sample 15 of array 'seismic' .* is damaged"):
        store.sample(15)
