"""demseis.datasets: the sharded Zarr store, its validation, and the PyTorch Dataset.

Writing (driver: :func:`create_store`, :func:`record_failures`, :func:`finalize_store`; one task
per shard: :func:`write_shard`), resuming (:func:`shard_status`, :func:`stored_config`), reading
(:func:`open_store`, :func:`read_store_attrs`, :func:`read_particles`, :func:`read_sample`,
:class:`FaultSegDataset`, :class:`ShardAwareSampler`, :func:`to_xarray`), checking
(:func:`validate_store`, :func:`damaged_shards`) and the writer lock (:func:`writer_lock`).
The layout is documented in ``docs/store.md``. Importing this package imports neither torch nor
xarray.
"""

from demseis.datasets.dataset import (
    FaultSegDataset,
    Sample,
    ShardAwareSampler,
    read_sample,
    split_of_shards,
)
from demseis.datasets.integrity import damaged_shards, shard_damage
from demseis.datasets.lock import StoreLock, writer_lock
from demseis.datasets.store import (
    DEFAULT_ARRAYS,
    LABEL_RANGES,
    SAMPLE_ARRAY_SPECS,
    SAMPLE_ARRAYS,
    SCHEMA_VERSION,
    ArraySpec,
    ParamSpec,
    StoreLayout,
    create_store,
    finalize_store,
    open_store,
    read_layout,
    read_particles,
    read_store_attrs,
    record_failures,
    remove_partial_writes,
    shard_status,
    store_layout,
    stored_config,
    write_particles,
    write_shard,
)
from demseis.datasets.validate import ValidationReport, validate_store
from demseis.datasets.xarray_io import to_xarray

__all__ = [
    "DEFAULT_ARRAYS",
    "LABEL_RANGES",
    "SAMPLE_ARRAY_SPECS",
    "SAMPLE_ARRAYS",
    "SCHEMA_VERSION",
    "ArraySpec",
    "FaultSegDataset",
    "ParamSpec",
    "Sample",
    "ShardAwareSampler",
    "StoreLayout",
    "StoreLock",
    "ValidationReport",
    "create_store",
    "damaged_shards",
    "finalize_store",
    "open_store",
    "read_layout",
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
