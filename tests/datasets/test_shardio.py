"""The direct writer of chunk and shard files (demseis.datasets._shardio) against zarr itself.

Every file written by the direct path is compared byte for byte with the file zarr writes for
the same data (zarr's own ``setitem``, the reference), over every array
of a store, over every dtype and codec chain demseis uses and the fill-value edge cases; and
zarr reads back what the direct path wrote.
"""

from __future__ import annotations

import errno
import os
import re
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest
import zarr
from zarr.codecs import BloscCodec, BytesCodec, Crc32cCodec, ZstdCodec

import demseis.datasets._shardio as shardio
from demseis.datasets import (
    create_store,
    read_layout,
    read_particles,
    remove_partial_writes,
    shard_status,
    write_shard,
)
from demseis.datasets._nodes import small_compressors
from demseis.datasets._shardio import array_meta, is_fill, temporary_name, write_block
from demseis.datasets.records import fill_value_for, record_dtype
from demseis.datasets.particles import PARTICLE_FIELDS, particle_group_name
from demseis.types import Snapshot
from tests.datasets._helpers import (
    EVERY_PARAM_DTYPES,
    EVERY_S,
    EVERY_SHAPE,
    digest,
    every_array_dtypes,
    every_array_shard,
    grid_attrs,
    zarr_params,
)

ROOT = Path(__file__).resolve().parents[2]
SHAPE = EVERY_SHAPE
S = EVERY_S
PARAM_DTYPES = EVERY_PARAM_DTYPES


def _zarr_write_shard(path: Path, k: int, arrays: dict, params: dict,
                      particles: list[Snapshot] | None, run_id: int) -> None:
    """The reference write path: every chunk through zarr's setitem (flag cleared first and
    set last, particles through zarr), in the order of write_shard."""
    g = zarr.open_group(path, mode="r+", use_consolidated=False)
    g["shard_done"][k] = 0
    sel = slice(k * S, (k + 1) * S)
    for name, value in arrays.items():
        (path / name / "c" / str(k) / "0" / "0").unlink(missing_ok=True)
        g[name][sel] = value
    layout = read_layout(path)
    rec = np.zeros(S, dtype=record_dtype(list(layout.columns.values())))
    for name, value in params.items():
        rec[name] = np.asarray(value).astype(PARAM_DTYPES[name])
    g["params"][sel] = rec.view(np.uint8).reshape(S, -1)
    if particles is not None:
        counts = np.array([sn.ids.shape[0] for sn in particles], dtype=np.int64)
        data = {
            "ids": np.concatenate([sn.ids for sn in particles]),
            "x_m": np.concatenate([sn.xy[:, 0] for sn in particles]),
            "y_m": np.concatenate([sn.xy[:, 1] for sn in particles]),
            "radius_m": np.concatenate([sn.radius for sn in particles]),
            "layer": np.concatenate([sn.layer for sn in particles]),
            "deposited": np.concatenate([sn.deposited for sn in particles]),
            "offsets": np.concatenate([[0], np.cumsum(counts)]),
            "index": np.array([sn.index for sn in particles]),
            "step": np.array([sn.step for sn in particles]),
            "throw_m": np.array([sn.throw_m for sn in particles]),
        }
        group = g.create_group(particle_group_name(run_id), overwrite=True,
                               attributes={"run_id": run_id, "n_snapshots": len(particles)})
        for name, (dtype, dim, units, long_name) in PARTICLE_FIELDS.items():
            values = data[name].astype(dtype, copy=False)
            group.create_array(
                name, shape=values.shape, dtype=dtype, chunks=(max(1, values.shape[0]),),
                fill_value=0, compressors=small_compressors(), dimension_names=(dim,),
                attributes={"units": units, "long_name": long_name},
                config={"write_empty_chunks": True},
            )[...] = values
    g["shard_done"][k] = 1


def _every_array_store(path: Path) -> Path:
    create_store(path, n_shards=3, samples_per_shard=S, shape=SHAPE, arrays=list(every_array_dtypes()),
                 params=PARAM_DTYPES, attrs={"config": {}, "grid": grid_attrs(SHAPE)})
    return path


def test_write_shard_gives_zarrs_bytes_for_every_array(tmp_path):
    via_zarr = _every_array_store(tmp_path / "zarr.zarr")
    direct = _every_array_store(tmp_path / "direct.zarr")
    assert digest(via_zarr) == digest(direct)
    for k, variant in ((0, 0), (2, 0), (0, 1)):  # (0, 1): a rewrite with other data
        arrays, params, snaps = every_array_shard(k, variant)
        _zarr_write_shard(via_zarr, k, arrays, params, snaps, run_id=k)
        write_shard(direct, k, arrays, params, snaps, run_id=k)
        a, b = digest(via_zarr), digest(direct)
        assert a == b, sorted(f for f in set(a) | set(b) if a.get(f) != b.get(f))
    assert len(a) > 80  # every array of both stores was compared
    # zarr reads back what the direct path wrote (an independent check of the bytes)
    g = zarr.open_group(direct, mode="r")
    arrays, params, snaps = every_array_shard(0, 1)
    for name, value in arrays.items():
        np.testing.assert_array_equal(g[name][:S], value)
        assert np.signbit(g[name][:S]).tolist() == np.signbit(value).tolist()
    stored = zarr_params(direct)
    for name, value in params.items():
        np.testing.assert_array_equal(stored[name][:S], value)
    assert np.isnan(g["seismic"][S:2 * S]).all()  # shard 1 never written: the fill value
    got = read_particles(direct, 0)
    for sn, want in zip(got, snaps, strict=True):
        np.testing.assert_array_equal(sn.xy, want.xy)
        np.testing.assert_array_equal(sn.deposited, want.deposited)
    assert shard_status(direct).tolist() == [1, 0, 1]


CODECS = {
    "sharded raw": dict(serializer=BytesCodec(), compressors=(Crc32cCodec(),), sharded=True),
    "sharded lz4": dict(serializer=BytesCodec(),
                        compressors=(BloscCodec(cname="lz4", clevel=5, shuffle="shuffle"),
                                     Crc32cCodec()), sharded=True),
    "sharded lz4 noshuffle": dict(serializer=BytesCodec(), compressors=(
        BloscCodec(cname="lz4", clevel=5, shuffle="noshuffle"), Crc32cCodec()), sharded=True),
    "sharded zstd bitshuffle big-endian": dict(
        serializer=BytesCodec(endian="big"),
        compressors=(BloscCodec(cname="zstd", clevel=3, shuffle="bitshuffle"), Crc32cCodec()),
        sharded=True),
    "chunk zstd": dict(serializer=BytesCodec(),
                       compressors=(ZstdCodec(level=0, checksum=False), Crc32cCodec()),
                       sharded=False),
    "chunk zstd checksum big-endian": dict(serializer=BytesCodec(endian="big"),
                                           compressors=(ZstdCodec(level=3, checksum=True),),
                                           sharded=False),
    "chunk crc only": dict(serializer=BytesCodec(), compressors=(Crc32cCodec(),), sharded=False),
}
DTYPES = ["bool", "int8", "uint8", "int16", "uint16", "int32", "int64", "float32", "float64"]


def _patterns(dtype: np.dtype, fill, shape: tuple[int, ...]) -> dict[str, np.ndarray]:
    """Blocks to write one after the other, each compared with zarr's file."""
    rng = np.random.default_rng(7)
    if dtype.kind == "b":
        rand = rng.integers(0, 2, shape).astype(bool)
    elif dtype.kind == "f":
        rand = rng.normal(size=shape).astype(dtype)
    else:
        info = np.iinfo(dtype)
        rand = rng.integers(info.min, info.max, shape, endpoint=True, dtype=dtype)
    some_fill = rand.copy()
    some_fill[: max(1, shape[0] // 2)] = fill  # the first inner chunk(s) / values are fill
    out = {"random": rand, "some fill": some_fill,
           "all fill": np.full(shape, fill, dtype=dtype), "random again": rand[::-1].copy()}
    if dtype.kind == "f":
        out["negative zeros"] = np.full(shape, -0.0, dtype=dtype)
        out["zeros"] = np.zeros(shape, dtype=dtype)
        out["all NaN"] = np.full(shape, np.nan, dtype=dtype)
        out["infinities"] = np.where(rand > 0, np.inf, -np.inf).astype(dtype)
    return out


@pytest.mark.parametrize("codec", list(CODECS))
@pytest.mark.parametrize("dtype", DTYPES)
def test_write_block_gives_zarrs_bytes(tmp_path, dtype, codec):
    dtype = np.dtype(dtype)
    spec = dict(CODECS[codec])
    sharded = spec.pop("sharded")
    fills = [False] if dtype.kind == "b" else (
        [float("nan"), 0.0, 1.5] if dtype.kind == "f" else [fill_value_for(dtype), 0])
    for f_i, fill in enumerate(fills):
        shape = (12, 3, 4) if sharded else (12,)
        chunks = dict(chunks=(1, 3, 4), shards=(4, 3, 4)) if sharded else dict(chunks=(4,))
        for empty in (False, True):
            stores = [tmp_path / f"{f_i}{empty}{w}.zarr" for w in ("zarr", "direct")]
            arrays = [zarr.create_array(p, shape=shape, dtype=dtype, fill_value=fill,
                                        config={"write_empty_chunks": empty}, **chunks, **spec)
                      for p in stores]
            meta = array_meta(stores[1], "", arrays[1].metadata.to_dict())  # at the root
            n = 4
            for name, block in _patterns(dtype, fill, (n, *shape[1:])).items():
                for k in (0, 2):
                    arrays[0][k * n:(k + 1) * n] = block
                    write_block(stores[1], meta, k, block, write_empty=empty)
                a, b = digest(stores[0]), digest(stores[1])
                assert a == b, (name, fill, empty, sorted(set(a) ^ set(b)))
                back = zarr.open_array(stores[1], mode="r")[:]
                np.testing.assert_array_equal(back[2 * n:3 * n], block)
                if dtype.kind == "f":
                    assert (np.signbit(back[:n]) == np.signbit(block)).all()


def test_is_fill_follows_zarr():
    f32 = np.float32
    assert is_fill(np.full(3, np.nan, f32), f32(np.nan))
    assert not is_fill(np.array([np.nan, 1.0], f32), f32(np.nan))
    assert is_fill(np.zeros(3, f32), f32(0.0))
    assert not is_fill(np.array([0.0, -0.0], f32), f32(0.0))  # bit patterns, as zarr
    assert is_fill(np.full(2, 255, np.uint8), 255)
    assert not is_fill(np.array([False, True]), False)


def test_temporary_files_of_a_killed_writer_are_removed(tmp_path):
    """A writer killed between writing a temporary file and renaming it leaves the file; the
    clean-up of a resume removes it and the rewrite gives the bytes of an uninterrupted run."""
    ref = _every_array_store(tmp_path / "ref.zarr")
    out = _every_array_store(tmp_path / "out.zarr")
    write_shard(ref, 1, *every_array_shard(1), run_id=1)
    child = textwrap.dedent("""
        import os, sys
        from tests.datasets._helpers import every_array_shard
        from demseis.datasets import write_shard
        calls, real = [], os.replace
        def replace(src, dst):
            calls.append(dst)
            if len(calls) == 4:  # the 4th file: three arrays of the shard are in place
                os._exit(9)  # killed: no clean-up runs
            real(src, dst)
        os.replace = replace
        write_shard(sys.argv[1], 1, *every_array_shard(1), run_id=1)
    """)
    res = subprocess.run([sys.executable, "-c", child, str(out)], cwd=ROOT,
                         env={**os.environ, "PYTHONPATH": str(ROOT)}, capture_output=True)
    assert res.returncode == 9, res.stderr.decode()
    left = [f for f in out.rglob("*") if f.name.endswith(".partial")]
    assert len(left) == 1 and re.search(r"\.[0-9a-f]{32}\.partial$", left[0].name), left
    assert temporary_name(Path("x")).name.startswith("x.")
    assert shard_status(out).tolist() == [0, 0, 0]
    assert remove_partial_writes(out) == left
    write_shard(out, 1, *every_array_shard(1), run_id=1)
    assert digest(out) == digest(ref)


def test_put_file_errors_name_the_file_and_leave_no_temporary(tmp_path, monkeypatch):
    (tmp_path / "f").write_text("x")
    with pytest.raises(NotADirectoryError) as info:
        shardio.put_file(tmp_path / "f" / "chunk", b"data")
    assert info.value.filename == str(tmp_path / "f" / "chunk")

    def full(src, dst):
        raise OSError(errno.ENOSPC, "No space left on device", src)

    monkeypatch.setattr(shardio.os, "replace", full)
    with pytest.raises(OSError, match="No space") as info:
        shardio.put_file(tmp_path / "d" / "chunk", b"data")
    assert info.value.filename == str(tmp_path / "d" / "chunk")
    assert sorted(p.name for p in tmp_path.rglob("*")) == ["d", "f"]  # no temporary file
