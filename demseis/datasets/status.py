"""Shard status and the driver's end of a sweep: done flags, failures, clean-up, finalisation.

The driver alone calls :func:`record_failures` and :func:`finalize_store` (consolidated
metadata, once, at the end), and :func:`remove_partial_writes` while no shard task runs.
"""

from __future__ import annotations

import re
import warnings
from collections.abc import Mapping
from pathlib import Path

import numpy as np

from demseis.datasets._nodes import zarr_lib
from demseis.datasets._shardio import PARTIAL_SUFFIX
from demseis.datasets.index import update_index
from demseis.datasets.integrity import damaged_shards, read_done_flags
from demseis.datasets.layout import open_store
from demseis.errors import InputError

# zarr is imported inside finalize_store: it takes ~0.3 s to import, and ``import
# demseis.datasets`` needs none of it.


def shard_status(path: str | Path, *, verify: bool = False) -> np.ndarray:
    """Done flags of every shard: (n_shards,) uint8, 0 = pending (or failed), 1 = done.

    A flag whose chunk fails its checksum reads as 0 (pending). With ``verify``, a done shard
    whose files are damaged (:func:`demseis.datasets.integrity.shard_damage`: every chunk's
    crc32c, the shard indexes, missing files) also reads as 0, so a resumed sweep rewrites it;
    this reads every byte of the done shards once (no decoding).
    """
    group = open_store(path, "r+")
    flags, _ = read_done_flags(path, int(group["shard_done"].shape[0]), group["shard_done"])
    status = (flags == 1).astype(np.uint8)
    if verify:
        for k in damaged_shards(path, group):
            status[k] = 0
    return status


def record_failures(path: str | Path, failures: Mapping[int, str]) -> dict[str, str]:
    """Record failed shards' error text in the root attr ``failures``. Driver only.

    Entries of earlier runs whose shard is now done are dropped; new entries replace old ones
    of the same shard. Call before :func:`finalize_store`.

    Parameters
    ----------
    failures : shard index -> error text.

    Returns
    -------
    dict
        The ``failures`` attr as stored (shard index as string -> text, sorted by index).
    """
    group = open_store(path, "r+")
    n_shards = int(group["shard_done"].shape[0])
    done, _ = read_done_flags(path, n_shards, group["shard_done"])  # no read per pending shard
    merged = {int(k): str(v) for k, v in dict(group.attrs.get("failures", {})).items()}
    for k, text in failures.items():
        if not 0 <= int(k) < n_shards:
            raise InputError(f"failed shard index {k!r} is outside [0, {n_shards})")
        merged[int(k)] = str(text)
    out = {str(k): merged[k] for k in sorted(merged) if not done[k]}
    group.attrs["failures"] = out
    return out


# zarr's LocalStore and demseis's own writer (_shardio.put_file, _shardio.temporary_name) write
# each file as ``<name>.<uuid4 hex>.partial`` and rename it into place; a writer killed between
# the two leaves the temporary file behind
_PARTIAL_WRITE = re.compile(r"\.[0-9a-f]{32}" + re.escape(PARTIAL_SUFFIX) + "$")


def remove_partial_writes(path: str | Path) -> list[Path]:
    """Delete the temporary files of writers that were killed mid-write. Driver only.

    Only call this while holding the store's writer lock with no shard task running (before a
    sweep starts, or after every task has finished): then any such file belongs to a process
    that is gone. The files are harmless to readers (no key names them) but they make two
    stores of the same config differ and they leak disk.

    Returns the files removed.
    """
    removed = []
    for f in Path(path).rglob("*" + PARTIAL_SUFFIX):
        if f.is_file() and _PARTIAL_WRITE.search(f.name):
            f.unlink(missing_ok=True)
            removed.append(f)
    return removed


def finalize_store(path: str | Path) -> None:
    """Remove killed writers' temporary files, bring the index of the parameter table up to
    date (:func:`~demseis.datasets.index.update_index`) and write consolidated metadata (once,
    at the end of a sweep, when no shard task runs any more). Driver only.

    Any later metadata write (resume, :func:`record_failures`) drops the consolidated copy;
    calling this again restores it.
    """
    zarr = zarr_lib()

    open_store(path, "r+")
    remove_partial_writes(path)  # of a killed dask worker, or of a killed earlier driver
    update_index(path)
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message=".*[Cc]onsolidated metadata.*")
        zarr.consolidate_metadata(str(Path(path)))
