"""Particle snapshots of a DEM run in a store: ``particles/run_<id:05d>/``.

Written by the shard task of the run (:func:`~demseis.datasets.write.write_shard`), so that
``demseis render`` can re-render a run at new frequencies and noise levels without re-running
the DEM; read back exactly by :func:`read_particles`.
"""

from __future__ import annotations

import json
import shutil
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from demseis.datasets._nodes import (create_arrays, put_files, small_compressors, zarr_files,
                                     zarr_lib)
from demseis.datasets._shardio import array_meta, write_block
from demseis.datasets.layout import check_store_metadata
from demseis.errors import InputError, StoreError
from demseis.types import Snapshot

# zarr is imported inside the functions that use it: it takes ~0.3 s to import, and
# ``import demseis.datasets`` needs none of it.

PARTICLE_FIELDS: dict[str, tuple[str, str, str, str]] = {
    "ids": ("int64", "element", "1", "element id (stable across the snapshots of a run)"),
    "x_m": ("float64", "element", "m", "element centre x"),
    "y_m": ("float64", "element", "m", "element centre elevation"),
    "radius_m": ("float64", "element", "m", "element radius"),
    "layer": ("int16", "element", "1", "layer index (growth layers >= n_layers)"),
    "deposited": ("bool", "element", "1", "added by syn-tectonic sedimentation"),
    "offsets": ("int64", "snapshot_edge", "1",
                "snapshot k is elements offsets[k]:offsets[k+1]"),
    "index": ("int32", "snapshot", "1", "snapshot index"),
    "step": ("int64", "snapshot", "1", "integrator step of the snapshot"),
    "throw_m": ("float64", "snapshot", "m", "basement throw at the snapshot"),
}
"""Arrays of one ``particles/run_<id>`` group: dtype, dimension, units, long_name (the first six
are concatenated over snapshots). Units in the names, and no name equal to a coordinate of
the root group: xarray's DataTree would shadow it with the inherited coordinate."""


def particle_group_name(run_id: int) -> str:
    """Path of the particle group of DEM run ``run_id`` inside the store."""
    return f"particles/run_{int(run_id):05d}"


def write_particles(path: str | Path, run_id: int, snapshots: Sequence[Snapshot]) -> None:
    """Write the particle snapshots of DEM run ``run_id`` into ``particles/run_<id>``.

    Replaces the group if present. Called by :func:`~demseis.datasets.write.write_shard` (the
    task owning that run). The per-element arrays of all snapshots are concatenated;
    ``offsets[k]:offsets[k+1]`` selects snapshot ``k``.
    """
    zarr = zarr_lib()

    snaps = list(snapshots)
    if not snaps:
        raise InputError(f"particles of run {run_id}: the list of snapshots is empty")
    for k, sn in enumerate(snaps):
        if not isinstance(sn, Snapshot):
            raise InputError(f"particles[{k}] is a {type(sn).__name__}, expected a Snapshot")
        n = sn.ids.shape[0]
        for attr, shp in (("ids", (n,)), ("xy", (n, 2)), ("radius", (n,)), ("layer", (n,)),
                          ("deposited", (n,))):
            if np.shape(getattr(sn, attr)) != shp:
                raise InputError(
                    f"particles[{k}].{attr} has shape {np.shape(getattr(sn, attr))}, expected {shp}"
                )
    counts = np.array([sn.ids.shape[0] for sn in snaps], dtype=np.int64)
    data = {
        "ids": np.concatenate([np.asarray(sn.ids) for sn in snaps]),
        "x_m": np.concatenate([np.asarray(sn.xy)[:, 0] for sn in snaps]),
        "y_m": np.concatenate([np.asarray(sn.xy)[:, 1] for sn in snaps]),
        "radius_m": np.concatenate([np.asarray(sn.radius) for sn in snaps]),
        "layer": np.concatenate([np.asarray(sn.layer) for sn in snaps]),
        "deposited": np.concatenate([np.asarray(sn.deposited) for sn in snaps]),
        "offsets": np.concatenate([[0], np.cumsum(counts)]),
        "index": np.array([sn.index for sn in snaps]),
        "step": np.array([sn.step for sn in snaps]),
        "throw_m": np.array([sn.throw_m for sn in snaps]),
    }
    path = Path(path)
    name = particle_group_name(run_id)
    check_store_metadata(path)  # a demseis store of this version
    values = {k: data[k].astype(dtype, copy=False) for k, (dtype, *_) in PARTICLE_FIELDS.items()}
    specs = {
        k: dict(
            shape=values[k].shape,
            dtype=dtype,
            chunks=(max(1, values[k].shape[0]),),
            fill_value=0,
            compressors=small_compressors(),
            dimension_names=(dim,),
            attributes={"units": units, "long_name": long_name},
        )
        for k, (dtype, dim, units, long_name) in PARTICLE_FIELDS.items()
    }

    def build(store) -> None:  # the group at the top of its own in-memory store
        zarr.create_group(store, zarr_format=3,
                          attributes={"run_id": int(run_id), "n_snapshots": len(snaps)})
        create_arrays(store, specs)

    files = zarr_files(build)
    # The group is built under a hidden name beside its place and renamed into it, so a writer
    # killed at any moment leaves the old group, the new one or none, and a hidden scratch
    # directory that the next write of this run removes (readers and validate skip hidden
    # names). Only the shard task of the run writes it, so the names cannot collide.
    final = path / name
    staging, old = final.with_name(f".{final.name}.partial"), final.with_name(f".{final.name}.old")
    for scratch in (staging, old):
        shutil.rmtree(scratch, ignore_errors=True)
    put_files(staging, files)
    for k in PARTICLE_FIELDS:
        if values[k].shape[0]:  # an empty array has no chunk
            rel = staging.relative_to(path).as_posix()
            meta = array_meta(path, f"{rel}/{k}", json.loads(files[f"{k}/zarr.json"]))
            # every chunk is written, also one of zeros (zarr's write_empty_chunks): a missing
            # file means damage
            write_block(path, meta, 0, values[k], write_empty=True)
    if final.exists():  # the group is replaced, as by zarr's overwrite=True
        final.rename(old)
    staging.rename(final)
    shutil.rmtree(old, ignore_errors=True)


def read_particles(path: str | Path, run_id: int) -> list[Snapshot]:
    """The particle snapshots of DEM run ``run_id``, as written by :func:`write_particles`.

    Returns
    -------
    list[Snapshot]
        In snapshot order, with the dtypes of :class:`~demseis.types.Snapshot`
        (ids int64, xy (n, 2) float64, radius float64, layer int16, deposited bool).

    Raises
    ------
    StoreError
        The store is not readable, or it holds no particles for ``run_id``.
    """
    zarr = zarr_lib()

    path = Path(path)
    check_store_metadata(path)
    name = particle_group_name(run_id)
    if not (path / name / "zarr.json").is_file():
        raise StoreError(f"store {str(path)!r} holds no particle snapshots for run {run_id}")
    try:
        group = zarr.open_group(path / name, mode="r", use_consolidated=False)
        d = {k: group[k][...] for k in PARTICLE_FIELDS}
    except Exception as exc:
        raise StoreError(f"particles of run {run_id} in {str(path)!r} are unreadable: {exc}") from exc
    off = d["offsets"]
    if off.shape[0] != d["index"].shape[0] + 1 or off[-1] != d["ids"].shape[0]:
        raise StoreError(f"particles of run {run_id} in {str(path)!r} have inconsistent offsets")
    snaps = []
    for k in range(d["index"].shape[0]):
        s = slice(int(off[k]), int(off[k + 1]))
        snaps.append(
            Snapshot(
                index=int(d["index"][k]),
                step=int(d["step"][k]),
                throw_m=float(d["throw_m"][k]),
                ids=d["ids"][s].copy(),
                xy=np.stack([d["x_m"][s], d["y_m"][s]], axis=1),
                radius=d["radius_m"][s].copy(),
                layer=d["layer"][s].copy(),
                deposited=d["deposited"][s].copy(),
            )
        )
    return snaps

