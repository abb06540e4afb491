"""Checksums of a demseis store: which done shard, sample and array is damaged.

Every chunk of a schema-2 store ends with the crc32c of its encoded bytes (zarr's ``crc32c``
codec, the last codec of every array), and every shard file ends with a checksummed index.
These functions verify those checksums straight from the files, without decoding: a done shard
costs one read of its bytes. ``validate`` reports what they find, a resumed sweep rewrites the
damaged shards (:func:`demseis.datasets.status.shard_status` with ``verify=True``), and the readers
(:class:`~demseis.datasets.FaultSegDataset`, :func:`~demseis.datasets.read_sample`) check the
same checksums on the chunks they read (the loader once per chunk and reader, again when the
shard file changes: :class:`~demseis.datasets._shardio.RawShardReader`).
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from demseis.datasets._shardio import CRC_NBYTES, check_chunk_file, check_shard_file, crc_ok
from demseis.datasets.layout import array_metas, open_store, store_layout
from demseis.datasets.particles import PARTICLE_FIELDS, particle_group_name
from demseis.datasets.records import read_table_chunk, unpack
from demseis.errors import StoreError


def flag_files(path: str | Path, n_shards: int) -> np.ndarray:
    """(n,) int64, increasing: the shards whose done-flag file exists (only the flags of
    shards written so far have a file: a pending flag is the fill value 0, which deletes it),
    from one listing of ``shard_done/c``, so a store planned for 10^6 runs with a few done
    costs what those few cost."""
    try:
        names = os.listdir(Path(path) / "shard_done" / "c")
    except FileNotFoundError:
        names = []
    return np.array(sorted(int(n) for n in names if n.isdigit() and int(n) < n_shards),
                    dtype=np.int64)


def read_done_flags(path: str | Path, n_shards: int, array=None, *,
                    shards: np.ndarray | None = None) -> tuple[np.ndarray, list[int]]:
    """Done flags read from the ``shard_done`` chunk files, with their checksums checked.

    ``array`` (the open ``shard_done`` array, optional): when its codecs do not end in
    ``crc32c`` (a store assembled by hand, not by
    :func:`~demseis.datasets.create.create_store`), it is read through zarr instead, unchecked.
    ``shards``: read only these shards' flags (the others read 0).

    Returns
    -------
    (flags, damaged)
        (n_shards,) uint8 flags (a missing chunk is 0: zarr deletes a chunk set to its fill
        value; a damaged one is 0 too) and the shards whose flag chunk is damaged.
    """
    if array is not None and _last_codec(array) != "crc32c":
        return np.asarray(array[...], dtype=np.uint8), []
    flags = np.zeros(n_shards, dtype=np.uint8)
    damaged = []
    base = Path(path) / "shard_done" / "c"
    for k in (flag_files(path, n_shards) if shards is None else shards).tolist():
        try:
            data = (base / str(k)).read_bytes()
        except FileNotFoundError:  # cleared meanwhile by a rewrite of the shard
            continue
        arr = np.frombuffer(data, dtype=np.uint8)
        if arr.shape[0] != 1 + CRC_NBYTES or not crc_ok(arr):
            damaged.append(k)
        else:
            flags[k] = arr[0]
    return flags, damaged


def _last_codec(array) -> str | None:
    codecs = array.metadata.to_dict().get("codecs", ())
    return codecs[-1].get("name") if codecs else None


def _fmt(values: list[int], limit: int = 8) -> str:
    vals = [str(v) for v in values[:limit]]
    more = len(values) - limit
    return ", ".join(vals) + (f" ... (+{more})" if more > 0 else "")


def shard_damage(path: str | Path, k: int, group=None, layout=None, metas=None) -> list[str]:
    """One line per damaged file of shard ``k`` (empty when every checksum holds).

    Checks each sample array's shard file (index and every chunk, naming the damaged samples),
    each parameter's chunk, and each particle array of the shard's run (when stored: DEM runs).
    A never-written chunk of a sample array or parameter is reported too.
    """
    path = Path(path)
    group = open_store(path, "r+") if group is None else group
    layout = store_layout(group) if layout is None else layout
    s = layout.samples_per_shard
    s0 = k * s
    out = []
    for name in layout.arrays:
        index_problem, damaged, empty = check_shard_file(path / name / "c" / str(k) / "0" / "0", s)
        if index_problem == "missing":
            out.append(f"shard {k}: {name} samples {s0}..{s0 + s - 1} were never written "
                       "(shard file missing)")
            continue
        if index_problem:
            out.append(f"shard {k}: {name} is damaged in samples {s0}..{s0 + s - 1} "
                       f"({index_problem} in the shard file)")
            continue
        if damaged:
            out.append(f"shard {k}: {name} is damaged in samples "
                       f"{_fmt([s0 + i for i in damaged])} (crc32c mismatch)")
        if empty:
            out.append(f"shard {k}: {name} samples {_fmt([s0 + i for i in empty])} were never "
                       "written")
    run_id = k
    if layout.table and layout.params:
        table = (metas or {}).get("params") or array_metas(path)["params"]
        try:  # decoding checks the crc32c (and the records' size)
            rows = read_table_chunk(path, table, k, s)[0]
        except FileNotFoundError:
            out.append(f"shard {k}: parameters of samples {s0}..{s0 + s - 1} were never "
                       "written")
        except ValueError as exc:
            out.append(f"shard {k}: parameters are damaged in samples {s0}..{s0 + s - 1} "
                       f"({exc})")
        else:
            if "run_id" in layout.params:
                ids = np.unique(unpack(rows, list(layout.columns.values()), ["run_id"])["run_id"])
                run_id = int(ids[0]) if ids.size == 1 else k
    for name in () if layout.table else layout.params:  # assembled by hand: an array each
        f = path / "params" / name / "c" / str(k)
        problem = check_chunk_file(f) if f.is_file() else "never written"
        if problem:
            out.append(f"shard {k}: parameter {name} of samples {s0}..{s0 + s - 1}: {problem}")
    run_dir = path / particle_group_name(run_id)
    if (run_dir / "zarr.json").is_file():
        for name in PARTICLE_FIELDS:
            f = run_dir / name / "c" / "0"
            problem = check_chunk_file(f) if f.is_file() else "file missing"
            if problem:
                out.append(f"shard {k}: particles of run {run_id} are damaged: {name} ({problem})")
    return out


def damaged_shards(path: str | Path, group=None) -> dict[int, list[str]]:
    """Damage of every done shard: shard -> problem lines (only damaged shards; a damaged
    done flag counts as a damaged shard)."""
    group = open_store(path, "r+") if group is None else group
    layout = store_layout(group)
    flags, bad_flags = read_done_flags(path, layout.n_shards, group["shard_done"])
    out: dict[int, list[str]] = {k: [f"shard {k}: done flag is damaged (crc32c mismatch)"]
                                 for k in bad_flags}
    try:
        metas = array_metas(Path(path))
    except StoreError:  # codecs the direct reader does not know: run ids through zarr
        metas = {}
    for k in np.flatnonzero(flags == 1).tolist():
        problems = shard_damage(path, k, group, layout, metas)
        if problems:
            out[k] = problems
    return dict(sorted(out.items()))
