"""The store as an xarray Dataset (optional: ``pip install demseis[xarray]``).

A schema-2 store is xarray-native on its own: ``xarray.open_datatree(path, engine="zarr")``
opens every group (each array has ``dimension_names``, ``units`` and ``long_name``; the sample
axes have coordinate arrays ``depth`` or ``twt``, and ``x``). :func:`to_xarray` adds what
xarray cannot infer: the per-sample parameters become coordinates along ``sample``, the
categorical ones decoded to their names, and a ``done`` coordinate marks the samples of
complete shards.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from demseis.datasets.layout import open_store, store_layout
from demseis.datasets.read import read_params
from demseis.datasets.status import shard_status
from demseis.errors import DemseisError, StoreError

XARRAY_EXTRA = "pip install 'demseis[xarray]'"


def _import_xarray():
    try:
        import xarray
    except ImportError:
        raise DemseisError(
            f"to_xarray needs the optional dependency xarray: {XARRAY_EXTRA}"
        ) from None
    return xarray


def to_xarray(path: str | Path) -> Any:
    """The samples of a store as a lazy :class:`xarray.Dataset`.

    Returns
    -------
    xarray.Dataset
        Data variables: every sample array (``fault_dip_deg`` for the per-pixel ``dip_deg``,
        whose name the per-sample parameter holds), dims ``(sample, depth, x)`` (or ``(sample, twt,
        x)`` for time-domain stores), read lazily with dask, with ``units`` and ``long_name``.
        Coordinates: ``depth`` (m) or ``twt`` (s), ``x`` (m); every parameter along ``sample``
        (categorical ones as strings, e.g. ``noise_kind`` = ``"white"``/``"band"``), and
        ``done`` (bool, the sample's shard is complete; other samples read as fill values).
        ``attrs`` hold the store's root attributes (config, grid, ...).

    Raises
    ------
    DemseisError
        xarray is not installed (the message names the extra).
    StoreError
        ``path`` is not a demseis store of this schema version.
    """
    group = open_store(path, "r")  # schema check first: a clear error for old stores
    xr = _import_xarray()
    layout = store_layout(group)
    try:
        ds = xr.open_zarr(path, consolidated=False, zarr_format=3, mask_and_scale=False)
    except Exception as exc:  # noqa: BLE001 - corrupt metadata
        raise StoreError(f"xarray cannot open store {str(path)!r}: {exc}") from exc
    keep = [n for n in layout.arrays]
    ds = ds[keep]
    # a per-pixel array named like a per-sample parameter (dip_deg: the traces' dip against the
    # basement fault's dip) would be replaced by the parameter's coordinate: prefix it
    clash = {n: f"fault_{n}" for n in keep if n in layout.params}
    ds = ds.rename(clash)
    coords: dict[str, Any] = {}
    params = read_params(path)  # the table's columns over every sample (fill where not done)
    for name, column in layout.columns.items():
        values = params[name]
        attrs = dict(column.attributes)
        cats = column.categories
        if cats:
            codes = values
            names = np.array(list(cats) + [""], dtype=object)
            safe = np.where((codes >= 0) & (codes < len(cats)), codes, len(cats))
            coords[name] = xr.Variable("sample", names[safe].astype(str),
                                       {k: v for k, v in attrs.items()
                                        if k not in ("flag_values", "flag_meanings")})
        else:
            coords[name] = xr.Variable("sample", values, attrs)
    done = np.repeat(shard_status(path) == 1, layout.samples_per_shard)
    coords["done"] = xr.Variable("sample", done,
                                 {"units": "1", "long_name": "the sample's shard is complete"})
    ds = ds.assign_coords(coords)
    ds.attrs = dict(group.attrs)
    return ds
