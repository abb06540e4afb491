"""Writing one shard of a demseis store: :func:`write_shard`, one task per shard.

A task touches only the files of its own shard (one shard file per sample array, one chunk of
the parameter table, its own particles group and its own done-flag chunk), so concurrent tasks on
distinct shards cannot lose data. The done flag is cleared first and set last, and every file
is written atomically (write-then-rename), so a task killed at any point leaves its shard
not-done and a retry rewrites it from scratch. The chunk and shard files are encoded and
written by :mod:`demseis.datasets._shardio`, with zarr's codecs and the bytes zarr would write,
without zarr's asyncio machinery (through zarr, writing took about 0.15 s of a 0.25 s kinematic
run; see ``docs/store.md``). zarr is not imported here.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from demseis.datasets._shardio import ArrayMeta, write_block
from demseis.datasets.layout import array_metas, check_store_metadata, layout_of
from demseis.datasets.particles import write_particles
from demseis.datasets.records import fill_value_for, pack
from demseis.errors import InputError
from demseis.schema import SampleArray
from demseis.types import Snapshot


def write_shard(
    path: str | Path,
    shard_index: int,
    arrays: Mapping[str, np.ndarray],
    params: Mapping[str, Any],
    particles: Sequence[Snapshot] | None = None,
    *,
    run_id: int | None = None,
) -> None:
    """Write one complete shard (all samples of one run). One task per shard.

    Order: clear the shard's done flag, write every sample array (one shard file each), the
    shard's chunk of the parameter table, the particle snapshots, and set the done flag last. A kill at any point
    leaves the shard not-done; calling again rewrites it (idempotent).

    Parameters
    ----------
    path : store directory (created by :func:`~demseis.datasets.create.create_store`).
    shard_index : k in ``[0, n_shards)``; the shard holds samples ``[k*S, (k+1)*S)``.
    arrays : every sample array of the store, name -> (S, H, W) array. Float arrays must be
        finite; integer arrays integers within their ``valid_range`` as the store declares it
        (:class:`demseis.schema.SampleArray`).
    params : every parameter of the store, name -> (S,) array (or a scalar, broadcast).
        Integer values must fit the dtype exactly; float values must not be NaN (inf is
        allowed, e.g. ``snr_db = inf`` for noise-free samples).
    particles : the DEM run's snapshots (stored for re-rendering), or None.
    run_id : the run id, used to name the particles group. Default: ``params["run_id"]``
        when that parameter exists (it must then be constant in the shard), else
        ``shard_index``.

    Raises
    ------
    InputError
        Missing/extra arrays or parameters, wrong shapes, NaN, labels out of range.
    StoreError
        The store is not a demseis store of this schema version.
    """
    path = Path(path)
    check_store_metadata(path)
    members = array_metas(path)
    layout = layout_of(members)
    k = int(shard_index)
    if k != shard_index or not 0 <= k < layout.n_shards:
        raise InputError(f"shard_index must be in [0, {layout.n_shards}), got {shard_index!r}")
    s = layout.samples_per_shard
    shape = (s, *layout.shape)
    if set(arrays) != set(layout.arrays):
        raise InputError(
            f"arrays must be exactly {sorted(layout.arrays)} (the store's sample arrays), "
            f"got {sorted(arrays)}"
        )
    if set(params) != set(layout.params):
        raise InputError(
            f"params must be exactly {sorted(layout.params)} (the store's parameters), "
            f"got {sorted(params)}"
        )
    data = {n: _as_sample_array(layout.specs[n], arrays[n], dt, shape)
            for n, dt in layout.arrays.items()}
    pdata = {n: _as_param_array(n, params[n], dt, s) for n, dt in layout.params.items()}
    if "run_id" in pdata:
        ids = np.unique(pdata["run_id"])
        if ids.shape[0] != 1:
            raise InputError(f"params['run_id'] must be constant in a shard, got {ids.tolist()}")
        if run_id is not None and int(run_id) != int(ids[0]):
            raise InputError(f"run_id={run_id} disagrees with params['run_id']={int(ids[0])}")
        run_id = int(ids[0])
    if run_id is None:
        run_id = k

    done = members["shard_done"]
    # a rewrite must not leave a done flag over half-new data (the fill value 0 deletes the
    # flag's file, so a damaged flag is no obstacle)
    _set_flag(path, done, k, 0)
    sel = layout.shard_slice(k)
    # each file is encoded here and replaces the old one whole (write-then-rename): unlike a
    # write through zarr, nothing reads the old shard file, so a damaged one is no obstacle
    for n, v in data.items():
        _write_array(path, members[n], sel, v)
    if pdata and layout.table:  # every parameter in one chunk of records (datasets.records)
        _write_array(path, members["params"], sel, pack(pdata, list(layout.columns.values()), s))
    else:  # a store assembled by hand with zarr: an array per parameter
        for n, v in pdata.items():
            _write_array(path, members[f"params/{n}"], sel, v)
    if particles is not None:
        write_particles(path, run_id, particles)
    _set_flag(path, done, k, 1)


def _as_sample_array(spec: SampleArray, value: Any, dtype: np.dtype,
                     shape: tuple[int, ...]) -> np.ndarray:
    name = spec.name
    arr = np.asarray(value)
    if arr.shape != shape:
        raise InputError(f"array {name!r} has shape {arr.shape}, expected {shape}")
    if dtype.kind == "f":
        if arr.dtype.kind not in "fiu":
            raise InputError(f"array {name!r} has dtype {arr.dtype}, expected a float array")
        out = arr.astype(dtype, copy=False)
        if not np.isfinite(out).all():
            raise InputError(f"array {name!r} holds {int((~np.isfinite(out)).sum())} NaN/inf values")
        return out
    if arr.dtype.kind not in "iub":
        raise InputError(f"label array {name!r} has dtype {arr.dtype}, expected integers")
    lo, hi = spec.valid_range or (np.iinfo(dtype).min, np.iinfo(dtype).max)
    hi = int(np.iinfo(dtype).max) if hi is None else hi
    if arr.size and (arr.min() < lo or arr.max() > hi):
        raise InputError(
            f"label array {name!r} has values in [{arr.min()}, {arr.max()}], allowed [{lo}, {hi}]"
        )
    return arr.astype(dtype, copy=False)


def _as_param_array(name: str, value: Any, dtype: np.dtype, n: int) -> np.ndarray:
    arr = np.asarray(value)
    if arr.ndim == 0:
        arr = np.full(n, arr)
    if arr.shape != (n,):
        raise InputError(f"parameter {name!r} has shape {arr.shape}, expected ({n},)")
    if arr.dtype.kind not in "iubf":
        raise InputError(f"parameter {name!r} has dtype {arr.dtype}, expected numbers")
    out = arr.astype(dtype)
    if dtype.kind in "iu":
        if arr.dtype.kind == "f" and not np.isfinite(arr).all():
            raise InputError(f"integer parameter {name!r} holds NaN/inf")
        if not np.array_equal(out.astype(np.float64), arr.astype(np.float64)):
            raise InputError(f"parameter {name!r} values do not fit its dtype {dtype} exactly")
        if (out == fill_value_for(dtype)).any():
            raise InputError(
                f"parameter {name!r} uses {fill_value_for(dtype)}, reserved for missing values"
            )
    elif np.isnan(out).any():
        raise InputError(f"parameter {name!r} holds NaN")
    return out


def _write_array(store: Path, arr: ArrayMeta, sel: slice, data: np.ndarray) -> None:
    """Write ``data`` as ``arr[sel]`` of the store at ``store``: one whole shard of a sample
    array or the shard's chunk of the parameter table, i.e. one file, written atomically with the bytes
    zarr would write (:func:`demseis.datasets._shardio.write_block`).

    :func:`write_shard` writes every data array of a shard through this one function (tests
    replace it to inject faults).
    """
    n = (arr.shards or arr.chunks)[0]
    if sel.start % n or sel.stop - sel.start != n:
        raise ValueError(f"{arr.path}: {sel} is not one whole chunk/shard of {n}")
    # records of zero bytes are data: the table's chunk of a done shard always exists
    write_block(store, arr, sel.start // n, data, write_empty=arr.path == "params")


def _set_flag(store: Path, done: ArrayMeta, k: int, value: int) -> None:
    """Set the done flag of shard ``k`` (0 deletes its chunk file: 0 is the fill value)."""
    write_block(store, done, k, np.array([value], dtype=np.uint8))

