"""Creation of a demseis store (driver only): :func:`create_store` and what it declares.

The sample arrays are those of :data:`demseis.schema.SAMPLE_ARRAYS` (dtype, units,
description, compression); the per-sample parameters are declared by the caller
(:class:`ParamSpec`); the coordinate arrays of the sample axes come from the ``grid`` attribute.
zarr creates every array's metadata, in memory (:mod:`demseis.datasets._nodes`).
"""

from __future__ import annotations

import json
import shutil
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np

from demseis import __version__
from demseis.datasets._nodes import (create_arrays, flag_compressors, put_files,
                                     sample_compressors, small_compressors, zarr_files, zarr_lib)
from demseis.datasets.index import index_block
from demseis.datasets.layout import (SCHEMA_VERSION, StoreLayout, domain_varies, is_demseis_store,
                                     open_store, root_metadata_lost, store_layout)
from demseis.datasets.records import ParamColumn, fill_value_for, record_dtype, table_attributes
from demseis.errors import InputError, StoreError
from demseis.schema import SAMPLE_ARRAYS, sample_array, stored_arrays

# zarr is imported inside create_store: it takes ~0.3 s to import, and ``import
# demseis.datasets`` (and a shard write) needs none of it.

COORDS: dict[str, tuple[str, str]] = {
    "depth": ("m", "depth below the model top (cell centres)"),
    "twt": ("s", "two-way time below the model top"),
    "x": ("m", "horizontal position (cell centres)"),
}
"""Coordinate arrays of the sample axes: units and long_name. Rows are ``depth`` (depth-domain
stores) or ``twt`` (time-domain stores), columns are ``x``."""

UNIT_SUFFIXES: tuple[tuple[str, str], ...] = (
    ("_kg_m3", "kg/m^3"), ("_m_s2", "m/s^2"), ("_m_s", "m/s"), ("_n_m", "N/m"),
    ("_deg", "deg"), ("_hz", "Hz"), ("_db", "dB"), ("_cells", "cells"), ("_m", "m"),
    ("_s", "s"), ("_n", "N"),
)
"""Units of a parameter given without units (:class:`ParamSpec`), from its name's suffix (the
project's names carry units), longest first; any other name is dimensionless (``"1"``). The
generator passes the declared units of :mod:`demseis.parameters`; a test keeps the two in step."""


def units_of(name: str) -> str:
    """Units of a parameter called ``name`` (from :data:`UNIT_SUFFIXES`)."""
    for suffix, units in UNIT_SUFFIXES:
        if name.endswith(suffix):
            return units
    return "1"


@dataclass(frozen=True)
class ParamSpec:
    """Declaration of one per-sample parameter passed to :func:`create_store`.

    Attributes
    ----------
    dtype : integer or float dtype.
    long_name : what it is (default: the name with spaces).
    units : e.g. ``"m"``, ``"Hz"``, ``"1"`` (dimensionless); default from the name's suffix
        (:func:`units_of`).
    categories : names of the codes 0, 1, ... of a categorical parameter (stored as integer
        codes, read back as strings by :func:`~demseis.datasets.xarray_io.to_xarray` and
        accepted as strings by ``where=``).
    """

    dtype: str
    long_name: str | None = None
    units: str | None = None
    categories: tuple[str, ...] | None = None


_ALLOWED_PARAM_KINDS = "iuf"


def _normalise_arrays(arrays: Mapping[str, Any] | Iterable[str] | None) -> dict[str, np.dtype]:
    """Name -> fixed dtype (from the schema) of the sample arrays ``arrays`` asks for, in store
    order (the order of :data:`demseis.schema.SAMPLE_ARRAYS`, whatever the caller's order)."""
    if arrays is None:
        arrays = stored_arrays()
    if isinstance(arrays, Mapping):
        items = list(arrays.items())
    elif isinstance(arrays, str):
        raise InputError(f"arrays must be a dict name -> dtype or a list of names, got {arrays!r}")
    else:
        items = [(name, None) for name in arrays]
    out: dict[str, np.dtype] = {}
    for name, dtype in items:
        if name not in SAMPLE_ARRAYS:
            raise InputError(
                f"unknown sample array {name!r}; allowed: {', '.join(SAMPLE_ARRAYS.names())}"
            )
        fixed = sample_array(name).np_dtype
        if dtype is not None and np.dtype(dtype) != fixed:
            raise InputError(f"sample array {name!r} must have dtype {fixed}, got {np.dtype(dtype)}")
        out[name] = fixed
    if not out:
        raise InputError("arrays is empty: a store needs at least one sample array")
    return {name: out[name] for name in SAMPLE_ARRAYS.names() if name in out}


def _normalise_params(params: Mapping[str, Any] | None) -> dict[str, ParamSpec]:
    out: dict[str, ParamSpec] = {}
    for name, value in (params or {}).items():
        if not isinstance(name, str) or not name.isidentifier():
            raise InputError(f"parameter name {name!r} must be an identifier")
        spec = value if isinstance(value, ParamSpec) else ParamSpec(value)
        try:
            dt = np.dtype(spec.dtype)
        except TypeError as exc:
            raise InputError(f"parameter {name!r}: {spec.dtype!r} is not a NumPy dtype") from exc
        if dt.kind not in _ALLOWED_PARAM_KINDS or dt.itemsize > 8:
            raise InputError(
                f"parameter {name!r} has dtype {dt}; allowed: signed/unsigned integers and floats"
            )
        if spec.categories is not None:
            cats = tuple(spec.categories)
            if dt.kind not in "iu" or not cats or len(set(cats)) != len(cats) or not all(
                    isinstance(c, str) and c for c in cats):
                raise InputError(f"parameter {name!r}: categories must be distinct non-empty "
                                 f"strings of an integer parameter, got {spec.categories!r}")
            spec = replace(spec, categories=cats)
        out[name] = replace(spec, dtype=str(dt))
    return dict(sorted(out.items()))


def create_store(
    path: str | Path,
    *,
    n_shards: int,
    samples_per_shard: int,
    shape: Sequence[int],
    arrays: Mapping[str, Any] | Iterable[str] | None = None,
    params: Mapping[str, Any] | None = None,
    attrs: Mapping[str, Any] | None = None,
    overwrite: bool = False,
):
    """Create (or reopen for resume) a demseis store. Driver only.

    Parameters
    ----------
    path : store directory.
    n_shards : number of shards = number of runs (>= 1).
    samples_per_shard : S, samples per shard (>= 1).
    shape : (H, W) of one sample.
    arrays : sample arrays to create, dict name -> dtype (dtypes must match
        :data:`demseis.schema.SAMPLE_ARRAYS`) or a list of names; default: the arrays every
        store holds (:func:`demseis.schema.stored_arrays`: all but the opt-in ones, such as
        impedance).
    params : per-sample parameters, dict name -> dtype (integer or float) or
        :class:`ParamSpec` (dtype, long_name, units, categories), e.g.
        ``{"run_id": "int32", "noise_kind": ParamSpec("int8", categories=("white", "band"))}``.
    attrs : root attributes, JSON-serialisable; should hold ``config`` (the full resolved
        config) and ``grid`` ({"x0_m", "top_m", "cell_m", "nz", "nx"}, plus ``domain="time"``,
        ``dt_s``, ``nt`` for time-domain samples): the coordinate arrays ``depth`` (or ``twt``)
        and ``x`` are written from it. ``demseis`` is added.
    overwrite : replace an existing demseis store (or an empty directory). A non-empty
        directory that is not a demseis store is never deleted.

    Returns
    -------
    zarr.Group
        The store opened read/write.

    Notes
    -----
    If ``path`` already holds a demseis store and ``overwrite`` is False, this is a resume:
    the store is left as it is (attrs untouched; compare
    :func:`~demseis.datasets.layout.stored_config` first) and returned, provided its layout
    equals the requested one; otherwise :class:`StoreError` names the difference. Damaged
    metadata is rewritten first (:func:`repair_metadata`): an array's or group's ``zarr.json``
    that is missing or does not parse, and a lost root ``zarr.json`` of a store whose
    ``shard_done`` array is intact (then the root is written from ``attrs``). A store that
    lacks some of ``params`` (written before they were declared) gets the new parameter table
    and its done shards become pending (:func:`_extend_table`): a resume recomputes them.

    Raises
    ------
    StoreError
        ``path`` exists and is not a demseis store, or it is one with another layout / schema.
    InputError
        A bad argument.
    """
    path = Path(path)
    if int(n_shards) < 1 or int(n_shards) != n_shards:
        raise InputError(f"n_shards must be a positive integer, got {n_shards!r}")
    if int(samples_per_shard) < 1 or int(samples_per_shard) != samples_per_shard:
        raise InputError(f"samples_per_shard must be a positive integer, got {samples_per_shard!r}")
    shape_t = tuple(int(v) for v in shape)
    if len(shape_t) != 2 or min(shape_t) < 1:
        raise InputError(f"shape must be (H, W) with positive sizes, got {tuple(shape)!r}")
    array_dtypes = _normalise_arrays(arrays)
    param_specs = _normalise_params(params)
    param_dtypes = {k: np.dtype(v.dtype) for k, v in param_specs.items()}
    attrs = dict(attrs or {})
    if "demseis" in attrs:
        raise InputError("attrs must not contain 'demseis': it is written by create_store")
    try:
        json.dumps(attrs)
    except (TypeError, ValueError) as exc:
        raise InputError(f"attrs are not JSON-serialisable: {exc}") from exc
    wanted = StoreLayout(int(n_shards), int(samples_per_shard), shape_t, array_dtypes, param_dtypes)

    files = _store_files(wanted, param_specs, attrs)
    if path.exists():
        if not path.is_dir():
            raise StoreError(f"{str(path)!r} exists and is a file, not a store directory")
        if not overwrite and root_metadata_lost(path):
            # a resume finds the root document damaged: the arrays say it is a demseis store
            put_files(path, {"zarr.json": files["zarr.json"]})
        if is_demseis_store(path):
            if not overwrite:
                repair_metadata(path, files)
                group = open_store(path, "r+")  # schema version check
                have = store_layout(group)
                if _adds_parameters(have, wanted):
                    _extend_table(path, files)
                    group = open_store(path, "r+")
                    have = store_layout(group)
                diffs = have.describe_difference(wanted)
                if diffs:
                    raise StoreError(
                        f"store {str(path)!r} exists with another layout ({'; '.join(diffs)}); "
                        "use overwrite to replace it or choose another path"
                    )
                return group
            shutil.rmtree(path)
        elif any(path.iterdir()):
            raise StoreError(
                f"{str(path)!r} exists, is not empty and is not a demseis store; "
                "refusing to write into or delete it"
            )
    put_files(path, files)
    return open_store(path, "r+")


def _adds_parameters(have: StoreLayout, wanted: StoreLayout) -> bool:
    """True when ``wanted`` differs from the store's layout ``have`` only by parameters the
    store lacks (a store written before they were declared)."""
    return (have.table and set(have.params) < set(wanted.params)
            and all(wanted.params[k] == v for k, v in have.params.items())
            and not replace(have, params={}).describe_difference(replace(wanted, params={})))


def _extend_table(path: Path, files: Mapping[str, bytes]) -> None:
    """Declare the parameter table of ``files`` (more columns) in the store at ``path``. Its
    records lack the new columns, so every done shard becomes pending (its done flag first,
    then its table chunk and the index go): resuming computes the runs again, with the bytes
    they had (the new parameters at their defaults made them so). Interrupted, the next resume
    finds the same difference and finishes."""
    for sub in ("shard_done/c", "params", "params_index", "params_index_files"):
        base = path.joinpath(*sub.split("/"))
        for f in base.iterdir() if base.is_dir() else ():
            if f.name != "zarr.json" and f.is_file():
                f.unlink()
    put_files(path, {k: v for k, v in files.items()
                     if k.split("/")[0] in ("params", "params_index", "params_index_files")
                     and k.endswith("zarr.json")})


def repair_metadata(path: Path, files: Mapping[str, bytes]) -> list[str]:
    """Rewrite each metadata document of ``files`` (key -> the bytes create_store writes)
    that is missing or does not parse as JSON below ``path`` (the root ``zarr.json`` is left
    to the caller: it holds the store's config and its consolidated metadata). A document
    that parses but differs is left alone: the layout check names the difference. Returns the
    keys rewritten."""
    fixed = []
    for key, data in files.items():
        if key == "zarr.json" or not key.endswith("zarr.json"):
            continue
        f = path.joinpath(*key.split("/"))
        try:
            json.loads(f.read_bytes())
            continue
        except (OSError, ValueError):
            put_files(path, {key: data})
            fixed.append(key)
    return fixed


def _store_files(wanted: StoreLayout, param_specs: Mapping[str, ParamSpec],
                 attrs: Mapping[str, Any]) -> dict[str, bytes]:
    """Every file :func:`create_store` writes for the layout ``wanted`` (key -> bytes): the
    metadata of the root, the groups and the arrays, and the coordinate arrays' chunks."""
    zarr = zarr_lib()

    root_attrs = {
        "demseis": {"schema_version": SCHEMA_VERSION, "package_version": __version__},
        **attrs,
    }
    h, w = wanted.shape
    n = wanted.n_samples
    s = wanted.samples_per_shard
    row_dim, coords = _grid_coords(attrs.get("grid"), wanted.shape)
    specs: dict[str, dict[str, Any]] = {}  # array path -> create_array keywords
    for name, dtype in wanted.arrays.items():
        spec = sample_array(name)
        specs[name] = dict(
            shape=(n, h, w),
            dtype=dtype,
            chunks=(1, h, w),
            shards=(s, h, w),
            fill_value=fill_value_for(dtype),
            compressors=sample_compressors(spec),
            dimension_names=("sample", row_dim, "x"),
            attributes=spec.store_attributes(),
        )
    if param_specs:
        specs.update(_table_specs(wanted, param_columns_of(param_specs)))
    specs["shard_done"] = dict(
        shape=(wanted.n_shards,),
        dtype="uint8",
        chunks=(1,),
        fill_value=0,
        compressors=flag_compressors(),
        dimension_names=("shard",),
        attributes={"units": "1", "long_name": "1 once the shard (one DEM run) is complete",
                    "flag_values": [0, 1], "flag_meanings": "pending done"},
    )

    def build(store) -> None:
        group = zarr.create_group(store, zarr_format=3, attributes=root_attrs)
        for name, values in coords.items():
            units, long_name = COORDS[name]
            group.create_array(name, shape=values.shape, dtype="float64", chunks=values.shape,
                               fill_value=float("nan"), compressors=small_compressors(),
                               dimension_names=(name,),
                               attributes={"units": units, "long_name": long_name})[...] = values
        create_arrays(store, specs)
        group.create_group("particles")

    return zarr_files(build)


def _grid_coords(grid: Any, shape: tuple[int, int]) -> tuple[str, dict[str, np.ndarray]]:
    """Row dimension name and coordinate values of the sample axes, from the ``grid`` attr.

    Cell centres as :class:`demseis.types.Grid` defines them: ``x = x0_m + (j + 0.5)
    cell_m`` (``dx_m``, the trace spacing, where the store has it), depth below the top ``(i + 0.5) cell_m``; time-domain stores (``domain = "time"``)
    have rows ``twt = k dt_s`` (the axis of :func:`demseis.seismic.time_axis`). No coordinates
    when the attr is absent or does not match the sample shape, or when the sampling varies
    from sample to sample (``grid["sampling"]``: each sample's is in the parameter table); the
    rows are ``row`` where the domain varies (``dt_s`` 0 in the table: a depth section).
    """
    if not isinstance(grid, Mapping):
        return "depth", {}
    time = grid.get("domain", "depth") == "time"
    row_dim = "twt" if time else "depth"
    if domain_varies(grid):
        return "row", {}             # depth cells in some samples, time samples in others
    if grid.get("sampling"):
        return row_dim, {}
    try:
        cell, nx = float(grid["cell_m"]), int(grid["nx"])
        x = float(grid["x0_m"]) + (np.arange(nx) + 0.5) * float(grid.get("dx_m", cell))
        rows = (np.arange(int(grid["nt"])) * float(grid["dt_s"]) if time
                else (np.arange(int(grid["nz"])) + 0.5) * cell)
    except (KeyError, TypeError, ValueError):
        return row_dim, {}
    if (rows.shape[0], x.shape[0]) != shape:
        return row_dim, {}
    return row_dim, {row_dim: rows, "x": x}


#: the table's and the index's chunk files are ``c.<k>.0`` beside their ``zarr.json``: one
#: file per shard (or block) and no directory per shard
_FLAT_KEYS = {"name": "default", "separator": "."}


def param_columns_of(param_specs: Mapping[str, ParamSpec]) -> list[ParamColumn]:
    """The columns of the parameter table of ``param_specs`` (name order)."""
    return [ParamColumn(name, np.dtype(spec.dtype), spec.categories, _param_attrs(name, spec))
            for name, spec in sorted(param_specs.items())]


def _table_specs(wanted: StoreLayout, columns: list[ParamColumn]) -> dict[str, dict[str, Any]]:
    """The parameter table (``params``, one chunk of records per shard) and its index
    (:mod:`demseis.datasets.index`): create_array keywords by path."""
    n, s, n_shards = wanted.n_samples, wanted.samples_per_shard, wanted.n_shards
    width = record_dtype(columns).itemsize
    block = index_block(n_shards)
    common = dict(dtype="uint8", fill_value=0, compressors=small_compressors(),
                  chunk_key_encoding=_FLAT_KEYS)
    return {
        "params": dict(shape=(n, width), chunks=(s, width), dimension_names=("sample", "byte"),
                       attributes=table_attributes(columns), **common),
        "params_index": dict(
            shape=(n, width), chunks=(s * block, width), dimension_names=("sample", "byte"),
            attributes={"units": "1", "long_name": f"the records of params, {block} shards per "
                        "chunk (an index: see params_index_files)"}, **common),
        "params_index_files": dict(
            shape=(n_shards, 2), dtype="int64", chunks=(block, 2), fill_value=0,
            compressors=small_compressors(), chunk_key_encoding=_FLAT_KEYS,
            dimension_names=("shard", "identity"),
            attributes={"units": "1", "long_name": "size and crc32c of the params chunk each "
                        "shard's index rows were copied from; 0: not indexed"}),
    }


def _param_attrs(name: str, spec: ParamSpec) -> dict[str, Any]:
    """``units``, ``long_name`` and, for a categorical parameter, CF ``flag_values`` /
    ``flag_meanings`` plus ``categories`` (the names in code order)."""
    out: dict[str, Any] = {
        "units": spec.units if spec.units is not None else units_of(name),
        "long_name": spec.long_name or name.replace("_", " "),
    }
    if spec.categories is not None:
        out["categories"] = list(spec.categories)
        out["flag_values"] = list(range(len(spec.categories)))
        out["flag_meanings"] = " ".join(c.replace(" ", "_") for c in spec.categories)
    return out


