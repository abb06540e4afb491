"""``demseis migrate``: a store of an older schema version converted in place, nothing recomputed.

Version 2 to 3: the per-sample parameters move from one array per parameter (``params/<name>``,
a file per parameter and shard) into one table of records (``params``, a file per shard,
:mod:`demseis.datasets.records`) with its index (:mod:`demseis.datasets.index`). The sample
arrays, the done flags and the particles are not touched, so their bytes stay the same.

The conversion holds the store's writer lock and can be interrupted at any point: the new
table is built beside the old arrays (``.migrate-params``), the two are swapped by renames,
and the root document, written last and atomically, says which version the store is. Run
again, ``migrate`` finishes or undoes what an interrupted run left. On a store of the current
version it rebuilds the index (a damaged one, or one that lags a sweep that was cut short).
"""

from __future__ import annotations

import json
import os
import shutil
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from tqdm import tqdm

from demseis import __version__
from demseis.datasets._nodes import create_arrays, put_files, zarr_files
from demseis.datasets._shardio import array_meta, put_file, write_block
from demseis.datasets.create import _table_specs
from demseis.datasets.index import INDEX_ARRAYS, update_index
from demseis.datasets.integrity import read_done_flags
from demseis.datasets.layout import (MIGRATABLE_VERSIONS, SCHEMA_VERSION, array_metas, layout_of,
                                     root_metadata)
from demseis.datasets.lock import writer_lock
from demseis.datasets.records import pack
from demseis.datasets.status import finalize_store
from demseis.errors import StoreError

_STAGING = ".migrate-params"      # the new table while it is built
_OLD = ".migrate-params-v2"       # the old parameter arrays while the two are swapped


@dataclass
class MigrateReport:
    """What :func:`migrate_store` did.

    Attributes
    ----------
    path : the store.
    from_version, to_version : its schema version before and after.
    shards_moved : done shards whose parameters were copied into the table.
    pending : shards whose parameters could not be read (missing or failing their checksum):
        marked pending, so ``demseis generate`` computes them again.
    files_before, files_after : files under the store before and after.
    """

    path: str
    from_version: int
    to_version: int
    shards_moved: int = 0
    pending: list[int] = field(default_factory=list)
    files_before: int = 0
    files_after: int = 0

    def summary(self) -> str:
        """One line for the CLI."""
        if self.from_version == self.to_version:
            head = f"{self.path}: already schema version {self.to_version}; index rebuilt"
        else:
            head = (f"{self.path}: schema version {self.from_version} -> {self.to_version}; "
                    f"parameters of {self.shards_moved} done run(s) moved into one table")
        tail = f"; files {self.files_before} -> {self.files_after}"
        if self.pending:
            tail += (f"; {len(self.pending)} run(s) had damaged parameters and are pending again "
                     "(`demseis generate` recomputes them)")
        return head + tail


def _count_files(path: Path) -> int:
    return sum(len(files) for _, _, files in os.walk(path))


def _root(path: Path) -> dict:
    """The parsed root ``zarr.json`` of the demseis store at ``path``."""
    meta = root_metadata(path)
    try:
        meta["attributes"]["demseis"]["schema_version"]
    except (KeyError, TypeError):
        raise StoreError(f"{str(path)!r} is not a demseis store (no readable root zarr.json "
                         "with a schema version)") from None
    return meta


def migrate_store(path: str | Path, *, progress: bool = False) -> MigrateReport:
    """Convert the store at ``path`` to this demseis's schema version, in place.

    Raises
    ------
    StoreError
        Not a demseis store, a version this demseis cannot convert, or another writer holds
        the store.
    """
    path = Path(path)
    if not path.is_dir():
        raise StoreError(f"store {str(path)!r} does not exist or is not a directory")
    version = _root(path)["attributes"]["demseis"]["schema_version"]
    if version != SCHEMA_VERSION and version not in MIGRATABLE_VERSIONS:
        raise StoreError(f"store {str(path)!r} has schema version {version!r}; `demseis "
                         f"migrate` converts versions {list(MIGRATABLE_VERSIONS)} to "
                         f"{SCHEMA_VERSION} (regenerate older stores)")
    with writer_lock(path, "demseis migrate"):
        report = MigrateReport(str(path), int(version), SCHEMA_VERSION,
                               files_before=_count_files(path))
        if version == SCHEMA_VERSION:
            shutil.rmtree(path / _OLD, ignore_errors=True)  # left by a run cut short
            shutil.rmtree(path / _STAGING, ignore_errors=True)
            for name in INDEX_ARRAYS:  # rebuilt from the table
                for f in (path / name).glob("c.*"):
                    f.unlink()
            finalize_store(path)
        else:
            _undo_interrupted(path)
            _migrate_v2(path, report, progress)
        report.files_after = _count_files(path)
    return report


def _undo_interrupted(path: Path) -> None:
    """Put a version-2 store back as it was where an earlier migrate stopped before its end."""
    old, params = path / _OLD, path / "params"
    if old.exists():
        if params.exists():  # the new table swapped in, the root not yet rewritten
            shutil.rmtree(params)
        old.rename(params)
    shutil.rmtree(path / _STAGING, ignore_errors=True)


def _migrate_v2(path: Path, report: MigrateReport, progress: bool) -> None:
    members = array_metas(path)
    layout = layout_of(members)  # version 2: an array per parameter
    if layout.table:
        raise StoreError(f"store {str(path)!r} says schema version 2 but holds a parameter "
                         "table; it was changed by hand")
    s, columns = layout.samples_per_shard, list(layout.columns.values())
    files = zarr_files(lambda store: create_arrays(store, _table_specs(layout, columns)))
    # the metadata of the three new arrays (not the root document the in-memory store adds)
    put_files(path, {(_STAGING + key[len("params"):] if key.startswith("params/") else key): v
                     for key, v in files.items() if key.split("/")[0] in ("params", *INDEX_ARRAYS)})
    table = array_meta(path, _STAGING, json.loads((path / _STAGING / "zarr.json").read_bytes()))
    flags, _ = read_done_flags(path, layout.n_shards)
    done = np.flatnonzero(flags == 1).tolist()
    for k in tqdm(done, desc="migrate", unit="run", disable=not progress):
        values = {}
        try:
            for c in columns:
                meta = members[f"params/{c.name}"]
                values[c.name] = meta.encoder.decode(meta.block_file(path, k).read_bytes(), (s,))
        except (OSError, ValueError):
            report.pending.append(k)
            continue
        write_block(path, table, k, pack(values, columns, s), write_empty=True)
        report.shards_moved += 1
    for k in report.pending:  # its parameters are lost: the run is computed again
        put_file(path / "shard_done" / "c" / str(k), None)
        flags[k] = 0
    (path / "params").rename(path / _OLD)
    (path / _STAGING).rename(path / "params")
    root = _root(path)
    root.pop("consolidated_metadata", None)  # lists the old arrays; finalize writes it anew
    root["attributes"]["demseis"] = {**root["attributes"]["demseis"],
                                     "schema_version": SCHEMA_VERSION,
                                     "package_version": __version__,
                                     "migrated_from": 2}
    put_file(path / "zarr.json", json.dumps(root, indent=2).encode())
    shutil.rmtree(path / _OLD)
    update_index(path, flags)
    finalize_store(path)
