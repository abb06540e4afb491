"""demseis.datasets: the sharded Zarr store, its validation, and the PyTorch Dataset.

Writing (driver: :func:`create_store`, :func:`record_failures`, :func:`finalize_store`; one task
per shard: :func:`write_shard`), resuming (:func:`shard_status`, :func:`stored_config`), reading
(:func:`open_store`, :func:`read_store_attrs`, :func:`read_particles`, :class:`FaultSegDataset`,
:class:`ShardAwareSampler`) and checking (:func:`validate_store`). The layout is documented in
``docs/store.md``. Importing this package does not import torch.
"""

from demseis.datasets.dataset import FaultSegDataset, ShardAwareSampler, split_of_shards
from demseis.datasets.store import (
    DEFAULT_ARRAYS,
    LABEL_RANGES,
    SAMPLE_ARRAYS,
    SCHEMA_VERSION,
    StoreLayout,
    create_store,
    finalize_store,
    open_store,
    read_layout,
    read_particles,
    read_store_attrs,
    record_failures,
    shard_status,
    store_layout,
    stored_config,
    write_particles,
    write_shard,
)
from demseis.datasets.validate import ValidationReport, validate_store

__all__ = [
    "DEFAULT_ARRAYS",
    "LABEL_RANGES",
    "SAMPLE_ARRAYS",
    "SCHEMA_VERSION",
    "FaultSegDataset",
    "ShardAwareSampler",
    "StoreLayout",
    "ValidationReport",
    "create_store",
    "finalize_store",
    "open_store",
    "read_layout",
    "read_particles",
    "read_store_attrs",
    "record_failures",
    "shard_status",
    "split_of_shards",
    "store_layout",
    "stored_config",
    "validate_store",
    "write_particles",
    "write_shard",
]
