"""The index of a store's parameter table: the records of many shards in one file.

The parameter table (``params``, :mod:`demseis.datasets.records`) has one chunk file per
shard, so reading the parameters of 10^4 done runs would read 10^4 files. The index holds the
same records ``INDEX_BLOCK`` shards at a time:

- ``params_index`` (N, R) uint8, chunks (S * B, R): the records of the shards of block ``b``
  (file ``params_index/c.<b>.0``);
- ``params_index_files`` (n_shards, 2) int64, chunks (B, 2): for each shard the identity
  (size and crc32c) of the table chunk file its records were copied from, 0 where the block's
  index does not hold the shard.

A reader takes a done shard's records from the index only while its table chunk file is the
one that was indexed (its size and its last 4 bytes, the chunk's crc32c); any other done shard
(written since, or rewritten) is read from its own chunk. So the index is never wrong, only
incomplete, and it needs no lock among the sweep's workers: only the driver writes it
(:func:`update_index`, while the sweep runs and when it ends), and ``demseis migrate`` rebuilds
it. Each file is written atomically, the records before the identities, so a driver killed
between the two leaves identities that still match what they name.

Checking that identity costs one small read per done shard: 1.2 s for 10^4 shards with the
page cache dropped on a local disk, one metadata round trip each on a network filesystem. A
reader skips it when the index is *current* (:func:`index_current`): a full update
(``shards=None``: the end of every sweep, ``demseis migrate``) checked every entry against its
chunk and then set the modification time of ``params_index_files/zarr.json`` (its bytes stay
the same), and the table's directory (``params/``) has not changed since. Every chunk write is
a rename into that directory (zarr's and :func:`~demseis.datasets._shardio.put_file`), which
sets the directory's modification time, so a chunk written after the update makes the index
not current, and readers check identities again until the next full update. A current index
is still spot-checked: one identity per block (an index block copied from another store, or
restored from a backup, fails it and that block is checked shard by shard). Before a sweep
dispatches its runs, the driver drops the entries of every shard it is about to write
(:func:`update_index` with those shards not done), so no entry can name a chunk that a
running sweep replaces.
"""

from __future__ import annotations

import os
import time
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from demseis.datasets._shardio import CRC_NBYTES, ArrayMeta, write_block
from demseis.datasets.integrity import read_done_flags
from demseis.datasets.layout import array_metas, layout_of
from demseis.datasets.records import read_table_chunk

INDEX_BLOCK = 256
"""Shards per block of the index (per file of ``params_index``)."""

INDEX_ARRAYS = ("params_index", "params_index_files")
"""The index's arrays (root arrays of the store)."""


def index_block(n_shards: int) -> int:
    """Shards per block of the index of a store of ``n_shards`` shards."""
    return max(1, min(INDEX_BLOCK, int(n_shards)))


def chunk_identity(f: Path) -> tuple[int, int] | None:
    """(size, crc32c) of a table chunk file: its length and its last 4 bytes (the crc32c zarr
    appends to every chunk), None if the file is missing. Same bytes, same identity: a copied
    store keeps its index, and the index's own bytes are the same in every store of the same
    config and seed."""
    try:
        with open(f, "rb") as fh:
            size = fh.seek(0, os.SEEK_END)
            if size < CRC_NBYTES:
                return size, -1
            fh.seek(size - CRC_NBYTES)
            return size, int.from_bytes(fh.read(CRC_NBYTES), "little")
    except FileNotFoundError:
        return None


@dataclass
class IndexBlock:
    """One block of the index as read: the records of its shards and their identities.

    Attributes
    ----------
    block : block number b (shards ``b * B`` to ``(b + 1) * B - 1``).
    records : (S * B, R) uint8, the rows of the block's shards.
    files : (B, 2) int64, the identity each shard's rows were copied from (0: not indexed).
    """

    block: int
    records: np.ndarray
    files: np.ndarray


def read_block(path: Path, metas: Mapping[str, ArrayMeta], b: int) -> IndexBlock | None:
    """Block ``b`` of the index, None when it was never written or fails its checksum (then
    its shards are read from their own chunks, and the next :func:`update_index` rewrites
    it)."""
    rec_meta, id_meta = metas["params_index"], metas["params_index_files"]
    try:
        ids = id_meta.encoder.decode(id_meta.block_file(path, b).read_bytes(), id_meta.chunks)
        rows = rec_meta.encoder.decode(rec_meta.block_file(path, b).read_bytes(), rec_meta.chunks)
    except (FileNotFoundError, ValueError):
        return None
    return IndexBlock(b, rows, ids)


def stamp_file(path: Path) -> Path:
    """The file whose modification time records the last full update of the index."""
    return path / INDEX_ARRAYS[1] / "zarr.json"


def index_current(path: Path) -> bool:
    """True when the last full :func:`update_index` came after the last change of the table's
    directory (strictly later modification time: a filesystem with coarse times says False
    more often, never True wrongly); False when either cannot be read."""
    stamp, table = _mtime_ns(stamp_file(path)), _mtime_ns(_table_dir(path))
    return stamp is not None and table is not None and stamp > table


def indexed_rows(path: Path, metas: Mapping[str, ArrayMeta], shards: np.ndarray,
                 s: int, *, current: bool = False) -> dict[int, np.ndarray]:
    """The records of each shard of ``shards`` that the index holds for its current table
    chunk file: shard -> (S, R) uint8.

    ``current``: the index is current (:func:`index_current`, checked by the caller): each
    block's entries are taken after one of them matches its chunk, the rest without a read.
    """
    out: dict[int, np.ndarray] = {}
    if not all(n in metas for n in INDEX_ARRAYS) or not len(shards):
        return out
    per, table = metas["params_index_files"].chunks[0], metas["params"]
    for b in np.unique(shards // per).tolist():
        blk = read_block(path, metas, b)
        if blk is None:
            continue
        trust, matched = current, False  # one match first; a mismatch: check every entry
        for k in shards[(shards // per) == b].tolist():
            j = k - b * per
            held = tuple(int(v) for v in blk.files[j])
            if not any(held):
                continue
            if trust and matched:
                out[k] = blk.records[j * s:(j + 1) * s]
            elif chunk_identity(table.block_file(path, k)) == held:
                out[k] = blk.records[j * s:(j + 1) * s]
                matched = True
            else:
                trust = False
    return out


def update_index(path: str | Path, done: np.ndarray | None = None,
                 shards: Iterable[int] | None = None) -> int:
    """Bring the index of the store at ``path`` up to date with its done shards: add the
    records of done shards it lacks (or holds from a file since replaced), drop shards no
    longer done. Driver only (the writer lock held). Returns the number of shards whose entry
    changed. A store without an index (assembled by hand) is left alone.

    ``done``: the (n_shards,) done flags if the caller has them (else read from the store).
    ``shards``: only the blocks holding these shards (the runs a sweep finished since its last
    update, or the runs it is about to write, given as not done), else every block. Only a
    full update (every block) makes the index current (:func:`index_current`), and only if
    the table's directory did not change while it ran.
    """
    path = Path(path)
    metas = array_metas(path)
    if not all(n in metas for n in INDEX_ARRAYS) or "params" not in metas:
        return 0
    table_time = _mtime_ns(_table_dir(path)) if shards is None else None
    layout = layout_of(metas)
    s = layout.samples_per_shard
    id_meta, rec_meta, table = metas["params_index_files"], metas["params_index"], metas["params"]
    per = id_meta.chunks[0]
    n_blocks = -(-layout.n_shards // per)
    blocks = range(n_blocks) if shards is None else sorted({int(k) // per for k in shards})
    if done is None:
        wanted = None if shards is None else np.array(
            [k for b in blocks for k in range(b * per, min((b + 1) * per, layout.n_shards))],
            dtype=np.int64)
        done, _ = read_done_flags(path, layout.n_shards, shards=wanted)
    done_set = set(np.flatnonzero(np.asarray(done) == 1).tolist())
    on_disk = written_blocks(path, id_meta)
    changed = 0
    for b in blocks:
        shards_b = range(b * per, min((b + 1) * per, layout.n_shards))
        if b not in on_disk and not any(k in done_set for k in shards_b):
            continue
        blk = read_block(path, metas, b) if b in on_disk else None
        if blk is None:
            blk = IndexBlock(b, np.zeros(rec_meta.chunks, np.uint8), np.zeros(id_meta.chunks, np.int64))
        dirty = False
        for k in shards_b:
            j = k - b * per
            held = tuple(int(v) for v in blk.files[j])
            ident = chunk_identity(table.block_file(path, k)) if k in done_set else None
            if ident is not None and held == ident:
                continue
            if ident is None and not any(held):
                continue
            blk.files[j] = 0
            if ident is not None:
                try:
                    rows, ident = read_table_chunk(path, table, k, s)
                except (FileNotFoundError, ValueError):  # damaged: `validate` names it
                    rows = None
                if rows is not None:
                    blk.records[j * s:(j + 1) * s] = rows
                    blk.files[j] = ident
            dirty = True
            changed += 1
        if dirty:
            write_block(path, rec_meta, b, blk.records, write_empty=True)
            write_block(path, id_meta, b, blk.files)
    if table_time is not None and _mtime_ns(_table_dir(path)) == table_time:
        _stamp_after(stamp_file(path), table_time)
    return changed


def _table_dir(path: Path) -> Path:
    """The directory of the parameter table's chunk files (every chunk write renames into it)."""
    return path / "params"


def _mtime_ns(p: Path) -> int | None:
    """Modification time of ``p`` in ns, None when it cannot be read."""
    try:
        return os.stat(p).st_mtime_ns
    except OSError:
        return None


def _stamp_after(f: Path, t_ns: int, tries: int = 20) -> None:
    """Set the modification time of ``f`` to now, retried for a few milliseconds while the
    clock (the kernel's coarse one, ticks of a few ms) has not passed ``t_ns``: the index is
    current only when its stamp is strictly later than the table's last change."""
    for _ in range(tries):
        try:
            os.utime(f)
        except OSError:  # read-only store or a missing file: the index stays not current
            return
        if os.stat(f).st_mtime_ns > t_ns:
            return
        time.sleep(0.002)


def written_blocks(path: Path, meta: ArrayMeta) -> set[int]:
    """Blocks of the index whose identity chunk file (``c.<block>.0``) exists."""
    try:
        names = os.listdir(path.joinpath(*meta.path.split("/")))
    except FileNotFoundError:
        return set()
    return {int(p[1]) for p in (n.split(".") for n in names)
            if len(p) == 3 and p[0] == "c" and p[1].isdigit()}
