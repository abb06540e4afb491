"""The per-sample parameters of a store as one table: a record of bytes per sample.

Every per-sample parameter of a store lives in one array, ``params`` (N, R) uint8: row ``i``
holds the parameters of sample ``i`` packed as one little-endian record of R bytes, the
columns in name order without padding. Its chunks are (S, R), one file per shard, so a run's
parameters cost one file whatever their number (one array per parameter cost one file each:
117 per run for the generator's parameters). The record layout is in the array's attributes::

    "demseis": {"role": "params", "columns": [
        {"name": "dip_deg", "dtype": "<f4", "units": "deg", "long_name": "dip deg"},
        {"name": "noise_kind", "dtype": "|i1", "units": "1", "long_name": "...",
         "categories": ["white", "band"]}, ...]}

so ``np.asarray(zarr.open_array("STORE/params")[:]).view(record_dtype)`` reads it without
demseis. Bytes, not numbers, because a float64 table would round the 64-bit integers
(``noise_seed``) and a table per dtype would cost a file per dtype.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from demseis.datasets._shardio import ArrayMeta
from demseis.errors import InputError, StoreError

TABLE_ROLE = "params"
"""``demseis.role`` of the parameter table's attributes."""


def fill_value_for(dtype: np.dtype) -> Any:
    """The value marking missing data for ``dtype``: NaN for floats, the maximum for unsigned
    integers (255 for uint8: outside every label range), the minimum for signed integers."""
    dtype = np.dtype(dtype)
    if dtype.kind == "f":
        return float("nan")
    if dtype.kind == "u":
        return int(np.iinfo(dtype).max)
    if dtype.kind == "i":
        return int(np.iinfo(dtype).min)
    raise InputError(f"dtype {dtype} is not supported in a demseis store (use int, uint or float)")


@dataclass(frozen=True)
class ParamColumn:
    """One per-sample parameter of a store: its name, dtype and description.

    Attributes
    ----------
    name : parameter name.
    dtype : its NumPy dtype (native byte order).
    categories : names of the codes 0, 1, ... of a categorical parameter, else None.
    attributes : ``units`` and ``long_name`` (and for a categorical parameter CF
        ``flag_values`` / ``flag_meanings`` and ``categories``).
    """

    name: str
    dtype: np.dtype
    categories: tuple[str, ...] | None = None
    attributes: Mapping[str, Any] = field(default_factory=dict)

    @property
    def fill_value(self) -> Any:
        """The value of the parameter where a sample was never written."""
        return fill_value_for(self.dtype)

    def describe(self) -> dict[str, Any]:
        """The column's entry in the table's attributes."""
        out: dict[str, Any] = {"name": self.name, "dtype": np.dtype(self.dtype).newbyteorder("<").str}
        out.update({k: v for k, v in self.attributes.items() if k != "categories"})
        if self.categories is not None:
            out["categories"] = list(self.categories)
        return out


def record_dtype(columns: Sequence[ParamColumn]) -> np.dtype:
    """The packed little-endian record of ``columns`` (in their order, no padding)."""
    return np.dtype([(c.name, np.dtype(c.dtype).newbyteorder("<")) for c in columns])


def table_attributes(columns: Sequence[ParamColumn]) -> dict[str, Any]:
    """Attributes of the ``params`` table: CF ``long_name`` and the record layout."""
    return {"units": "1", "long_name": "per-sample parameters, one packed record per sample",
            "demseis": {"role": TABLE_ROLE, "columns": [c.describe() for c in columns]}}


def columns_from_attributes(attributes: Mapping[str, Any], where: str) -> dict[str, ParamColumn]:
    """The columns a ``params`` table's attributes declare, name -> :class:`ParamColumn` in
    record order; :class:`StoreError` naming ``where`` when they are not a valid declaration."""
    info = attributes.get("demseis")
    if not isinstance(info, Mapping) or info.get("role") != TABLE_ROLE:
        raise StoreError(f"{where}: its attributes do not describe a parameter table")
    out: dict[str, ParamColumn] = {}
    try:
        for entry in info["columns"]:
            name = str(entry["name"])
            dtype = np.dtype(entry["dtype"]).newbyteorder("=")
            if dtype.kind not in "iuf" or name in out:
                raise ValueError(f"column {name!r} of dtype {dtype}")
            cats = entry.get("categories")
            cats = None if cats is None else tuple(str(c) for c in cats)
            attrs = {k: v for k, v in entry.items() if k not in ("name", "dtype")}
            out[name] = ParamColumn(name, dtype, cats, attrs)
    except (KeyError, TypeError, ValueError) as exc:
        raise StoreError(f"{where}: the parameter table's column declaration is damaged "
                         f"({exc})") from None
    return out


def pack(values: Mapping[str, np.ndarray], columns: Sequence[ParamColumn], n: int) -> np.ndarray:
    """(n, R) uint8: the records of ``n`` samples, ``values`` name -> (n,) array of each
    column (already of the column's dtype)."""
    rec = np.zeros(n, dtype=record_dtype(columns))
    for c in columns:
        rec[c.name] = values[c.name]
    return rec.view(np.uint8).reshape(n, rec.dtype.itemsize)


def unpack(block: np.ndarray, columns: Sequence[ParamColumn],
           names: Sequence[str] | None = None) -> dict[str, np.ndarray]:
    """Name -> (n,) array (native byte order) of the columns ``names`` (default all) of the
    records ``block`` (n, R) uint8."""
    dt = record_dtype(columns)
    if block.ndim != 2 or block.shape[1] != dt.itemsize:
        raise ValueError(f"records of {block.shape[-1]} bytes, the table declares {dt.itemsize}")
    rec = np.ascontiguousarray(block).view(dt).reshape(-1)
    wanted = [c.name for c in columns] if names is None else names
    by_name = {c.name: c for c in columns}
    return {n: rec[n].astype(by_name[n].dtype) for n in wanted}


def read_table_chunk(path: Path, meta: ArrayMeta, k: int, s: int) -> tuple[np.ndarray, tuple[int, int]]:
    """The (S, R) records of shard ``k`` from its table chunk file, its crc32c checked, and the
    identity of the bytes read (size, crc32c: :func:`demseis.datasets.index.chunk_identity`);
    ``FileNotFoundError`` or ``ValueError`` (damaged)."""
    data = meta.block_file(path, k).read_bytes()
    ident = (len(data), int.from_bytes(data[-4:], "little") if len(data) >= 4 else -1)
    return meta.encoder.decode(data, (s, meta.shape[1])), ident
