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
one that was indexed (its size and its last 4 bytes, the chunk's crc32c: one small read per
shard); any other done shard (written since, or rewritten) is read from its own chunk. So the
index is never wrong, only incomplete, and it needs no lock among the sweep's workers:
only the driver writes it (:func:`update_index`, while the sweep runs and when it ends), and
``demseis migrate`` rebuilds it. Each file is written atomically, the records before the
identities, so a driver killed between the two leaves identities that still match what they
name.
"""

from __future__ import annotations

import os
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


def indexed_rows(path: Path, metas: Mapping[str, ArrayMeta], shards: np.ndarray,
                 s: int) -> dict[int, np.ndarray]:
    """The records of each shard of ``shards`` that the index holds for its current table
    chunk file: shard -> (S, R) uint8."""
    out: dict[int, np.ndarray] = {}
    if not all(n in metas for n in INDEX_ARRAYS) or not len(shards):
        return out
    per, table = metas["params_index_files"].chunks[0], metas["params"]
    for b in np.unique(shards // per).tolist():
        blk = read_block(path, metas, b)
        if blk is None:
            continue
        for k in shards[(shards // per) == b].tolist():
            j = k - b * per
            held = tuple(int(v) for v in blk.files[j])
            if any(held) and chunk_identity(table.block_file(path, k)) == held:
                out[k] = blk.records[j * s:(j + 1) * s]
    return out


def update_index(path: str | Path, done: np.ndarray | None = None,
                 shards: Iterable[int] | None = None) -> int:
    """Bring the index of the store at ``path`` up to date with its done shards: add the
    records of done shards it lacks (or holds from a file since replaced), drop shards no
    longer done. Driver only (the writer lock held). Returns the number of shards whose entry
    changed. A store without an index (assembled by hand) is left alone.

    ``done``: the (n_shards,) done flags if the caller has them (else read from the store).
    ``shards``: only the blocks holding these shards (the runs a sweep finished since its last
    update), else every block.
    """
    path = Path(path)
    metas = array_metas(path)
    if not all(n in metas for n in INDEX_ARRAYS) or "params" not in metas:
        return 0
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
    return changed


def written_blocks(path: Path, meta: ArrayMeta) -> set[int]:
    """Blocks of the index whose identity chunk file (``c.<block>.0``) exists."""
    try:
        names = os.listdir(path.joinpath(*meta.path.split("/")))
    except FileNotFoundError:
        return set()
    return {int(p[1]) for p in (n.split(".") for n in names)
            if len(p) == 3 and p[0] == "c" and p[1].isdigit()}
