"""demseis.datasets: the sharded Zarr store, its validation, and the PyTorch Dataset.

Writing (driver: :func:`create_store`, :func:`record_failures`, :func:`finalize_store`; one task
per shard: :func:`write_shard`), resuming (:func:`shard_status`, :func:`stored_config`), reading
(:func:`open_store`, :func:`read_store_attrs`, :func:`read_particles`, :func:`read_sample`,
:class:`FaultSegDataset`, :class:`ShardAwareSampler`, :func:`to_xarray`), checking
(:func:`validate_store`, :func:`damaged_shards`), converting an older store
(:func:`migrate_store`) and the writer lock (:func:`writer_lock`).
The sample arrays a store may hold are declared in :mod:`demseis.schema`. Modules: ``layout``
(version, shape, metadata checks, opening), ``create``, ``write`` (one shard), ``particles``,
``status`` (done flags, failures, finalisation), ``records`` (the parameter table), ``index``
(its index), ``table`` (the done samples' parameters), ``integrity`` (checksums),
``validate``, ``migrate``, ``dataset``, ``read``, ``xarray_io`` and ``lock``. The on-disk layout is documented in
``docs/store.md``. Importing this package imports neither torch, xarray nor zarr.
"""

from demseis.datasets.create import ParamSpec, create_store
from demseis.datasets.dataset import (FaultSegDataset, Sample, ShardAwareSampler, read_sample,
                                      split_of_shards)
from demseis.datasets.integrity import damaged_shards, shard_damage
from demseis.datasets.layout import (SCHEMA_VERSION, StoreLayout, open_store, read_layout,
                                     read_store_attrs, store_layout, stored_config)
from demseis.datasets.lock import StoreLock, writer_lock
from demseis.datasets.migrate import MigrateReport, migrate_store
from demseis.datasets.particles import read_particles, write_particles
from demseis.datasets.read import read_params
from demseis.datasets.status import (finalize_store, record_failures, remove_partial_writes,
                                     shard_status)
from demseis.datasets.table import DoneParams, FullParams, read_done_params
from demseis.datasets.validate import ValidationReport, validate_store
from demseis.datasets.write import write_shard
from demseis.datasets.xarray_io import to_xarray

__all__ = [
    "SCHEMA_VERSION",
    "DoneParams",
    "FaultSegDataset",
    "FullParams",
    "MigrateReport",
    "ParamSpec",
    "Sample",
    "ShardAwareSampler",
    "StoreLayout",
    "StoreLock",
    "ValidationReport",
    "create_store",
    "damaged_shards",
    "finalize_store",
    "migrate_store",
    "open_store",
    "read_layout",
    "read_params",
    "read_done_params",
    "read_particles",
    "read_sample",
    "read_store_attrs",
    "record_failures",
    "remove_partial_writes",
    "shard_damage",
    "shard_status",
    "split_of_shards",
    "store_layout",
    "stored_config",
    "to_xarray",
    "validate_store",
    "write_particles",
    "write_shard",
    "writer_lock",
]
