"""The demseis Zarr store: creation, shard writing, resume status, particles, finalisation.

Layout (Zarr format 3, one group; see ``docs/store.md`` for the full schema)::

    STORE/
      zarr.json                  root attrs: demseis={schema_version, package_version}, config, grid,
                                 failures (shard -> error text, written by the driver)
      seismic, fault, damage,    (N, H, W) arrays, chunks (1, H, W), shards (S, H, W)
      strain, layer[, impedance]
      params/<name>              (N,) per-sample parameters, chunks (S,): one chunk per shard
      shard_done                 (n_shards,) uint8, chunks (1,): 1 once a shard is complete
      particles/run_<id:05d>/    particle snapshots of one DEM run (written by its shard task)

Who writes what
---------------
- The driver alone calls :func:`create_store` (creates every array and writes the root attrs),
  :func:`record_failures` and :func:`finalize_store` (consolidated metadata, once, at the end).
- Exactly one task per shard calls :func:`write_shard`. It touches only the files of its own
  shard (one shard file per sample array, one chunk per parameter array, its own particles
  group and its own done-flag chunk), so concurrent tasks on distinct shards cannot lose data.
  The done flag is cleared first and set last, and every file is written atomically
  (write-then-rename), so a task killed at any point leaves its shard not-done and a retry
  rewrites it from scratch. zarr creates every array (its metadata); the chunk and shard files
  of a shard are encoded and written by :mod:`demseis.datasets._shardio`, with zarr's codecs
  and the bytes zarr would write, without zarr's asyncio machinery (through zarr, writing took
  about 0.15 s of a 0.25 s kinematic run; see ``docs/store.md``).

Missing data is detectable: float arrays are filled with NaN and integer arrays with a sentinel
outside their valid range (255 for uint8 labels, the dtype minimum for signed integers), so a
chunk that was never written reads as an invalid value and :func:`validate_store` reports it.
"""

from __future__ import annotations

import json
import os
import re
import shutil
import warnings
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np

from demseis import __version__
from demseis.datasets._shardio import PARTIAL_SUFFIX, ArrayMeta, array_meta, put_file, write_block
from demseis.types import Snapshot
from demseis.errors import InputError, StoreError

SCHEMA_VERSION = 2
"""Version of the on-disk layout. Readers refuse stores of any other version.

1: the first layout. 2: a crc32c checksum on every chunk, coordinate arrays (``depth`` or
``twt``, and ``x``), ``units`` and ``long_name`` on every array, categorical parameters with
their category names, dimension names on the particle arrays.
"""


@dataclass(frozen=True)
class ArraySpec:
    """Declaration of one per-sample array (one line of :data:`SAMPLE_ARRAY_SPECS`).

    Attributes
    ----------
    dtype : fixed on-disk dtype.
    units : UDUNITS string (``"1"`` for dimensionless values and labels).
    long_name : what the array holds, written as the ``long_name`` attribute.
    valid_range : inclusive (low, high) of an integer label (high None: unbounded), checked by
        :func:`write_shard` and ``validate``; None for float arrays.
    compressed : Blosc-lz4 (labels, strain) or raw (network inputs, read as zero-copy crops).
    """

    dtype: str
    units: str
    long_name: str
    valid_range: tuple[int, int | None] | None = None
    compressed: bool = True


SAMPLE_ARRAY_SPECS: dict[str, ArraySpec] = {
    "seismic": ArraySpec("float32", "1", "seismic amplitude (band-limited, with noise)",
                         compressed=False),
    "fault": ArraySpec("uint8", "1", "fault label: 1 on a slip surface, 0 elsewhere", (0, 1)),
    "damage": ArraySpec("uint8", "1", "damage class: 0 background, 1 damage zone, 2 fault core",
                        (0, 2)),
    "strain": ArraySpec("float32", "1", "maximum shear strain since the reference snapshot"),
    "layer": ArraySpec("int16", "1", "layer index (-1: no rock, above the free surface)",
                       (-1, None)),
    "impedance": ArraySpec("float32", "kg/(m^2 s)", "acoustic impedance", compressed=False),
    "fault_id": ArraySpec("int16", "1", "fault instance id on fault cells (0: no fault)",
                          (0, None)),
    "slip_m": ArraySpec("float32", "m", "slip (displacement jump) of the nearest fault trace"),
    "dip_deg": ArraySpec("float32", "degree", "dip of the nearest fault trace"),
    "sense": ArraySpec("uint8", "1", "sense of slip: 0 none, 1 normal, 2 reverse", (0, 2)),
}
"""Every per-sample array a store may hold, in store order: adding one is one line here."""

SAMPLE_ARRAYS: dict[str, np.dtype] = {n: np.dtype(a.dtype) for n, a in SAMPLE_ARRAY_SPECS.items()}
"""Known per-sample arrays and their fixed dtypes (from :data:`SAMPLE_ARRAY_SPECS`)."""

DEFAULT_ARRAYS: tuple[str, ...] = ("seismic", "fault", "damage", "strain", "layer")
"""Arrays written when ``arrays`` is not given (impedance is opt-in)."""

LABEL_RANGES: dict[str, tuple[int, int | None]] = {
    n: a.valid_range for n, a in SAMPLE_ARRAY_SPECS.items() if a.valid_range is not None
}
"""Inclusive valid value range of each integer label array (None: no upper bound)."""

UNCOMPRESSED_ARRAYS: tuple[str, ...] = tuple(
    n for n, a in SAMPLE_ARRAY_SPECS.items() if not a.compressed
)
"""Sample arrays stored without compression: network inputs, read as zero-copy crops.

Band-limited float sections compress to only ~80-90 % with lz4/zstd, and decoding costs more
than the read (measured: 0.47 ms vs 0.90 ms per 320x512 sample). Labels and strain compress
many-fold and are stored with Blosc-lz4.
"""

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
        codes, read back as strings by :func:`to_xarray` and accepted as strings by ``where=``).
    """

    dtype: str
    long_name: str | None = None
    units: str | None = None
    categories: tuple[str, ...] | None = None

_ALLOWED_PARAM_KINDS = "iuf"


# --------------------------------------------------------------------------------------------
# small helpers


def fill_value_for(dtype: np.dtype) -> Any:
    """The fill value marking never-written data for ``dtype``.

    NaN for floats, the maximum for unsigned integers (255 for uint8: outside every label range)
    and the minimum for signed integers (-32768 for int16).
    """
    dtype = np.dtype(dtype)
    if dtype.kind == "f":
        return float("nan")
    if dtype.kind == "u":
        return int(np.iinfo(dtype).max)
    if dtype.kind == "i":
        return int(np.iinfo(dtype).min)
    raise InputError(f"dtype {dtype} is not supported in a demseis store (use int, uint or float)")


def _sample_compressors(name: str, dtype: np.dtype) -> tuple:
    """Codecs after ``bytes`` of one chunk of sample array ``name``: [Blosc-lz4,] crc32c."""
    from zarr.codecs import BloscCodec, Crc32cCodec

    if name in UNCOMPRESSED_ARRAYS:
        return (Crc32cCodec(),)
    # lz4 decodes at GB/s; labels compress ~200-fold (measured 0.005 of raw for fault masks,
    # 0.02 ms decode per 320x512 sample; bit-shuffle was 5x slower to decode for no gain).
    shuffle = "shuffle" if dtype.itemsize > 1 else "noshuffle"
    return (BloscCodec(cname="lz4", clevel=5, shuffle=shuffle), Crc32cCodec())


def _flag_compressors() -> tuple:
    """Codecs of a done flag (one byte): crc32c only, so the flags are read without zarr."""
    from zarr.codecs import Crc32cCodec

    return (Crc32cCodec(),)


def _small_compressors() -> tuple:
    """Codecs of the small arrays (parameters, flags, particles, coordinates): zstd, crc32c."""
    from zarr.codecs import Crc32cCodec, ZstdCodec

    return (ZstdCodec(level=0, checksum=False), Crc32cCodec())


def _particle_group_name(run_id: int) -> str:
    return f"particles/run_{int(run_id):05d}"


def _root_metadata(path: Path) -> dict | None:
    """Parsed ``zarr.json`` of ``path`` or None if there is none / it is not JSON."""
    meta = path / "zarr.json"
    if not meta.is_file():
        return None
    try:
        return json.loads(meta.read_text())
    except (OSError, ValueError):
        return None


def _is_demseis_store(path: Path) -> bool:
    meta = _root_metadata(path)
    return bool(
        meta
        and meta.get("node_type") == "group"
        and isinstance(meta.get("attributes", {}).get("demseis"), dict)
    )


def _check_store_metadata(path: Path) -> dict:
    """Root metadata of a demseis store of this schema version, else :class:`StoreError`."""
    if not path.exists():
        raise StoreError(f"store {str(path)!r} does not exist")
    if not path.is_dir():
        raise StoreError(f"store {str(path)!r} is a file, not a Zarr store directory")
    meta = _root_metadata(path)
    if meta is None:
        raise StoreError(f"{str(path)!r} is not a Zarr store (no readable zarr.json)")
    if meta.get("zarr_format") != 3 or meta.get("node_type") != "group":
        raise StoreError(
            f"{str(path)!r} is not a Zarr v3 group (zarr_format={meta.get('zarr_format')!r}, "
            f"node_type={meta.get('node_type')!r})"
        )
    info = meta.get("attributes", {}).get("demseis")
    if not isinstance(info, dict) or "schema_version" not in info:
        raise StoreError(f"{str(path)!r} is a Zarr store but was not written by demseis")
    version = info["schema_version"]
    if version != SCHEMA_VERSION:
        hint = ""
        if isinstance(version, int) and version < SCHEMA_VERSION:
            # refused, not read: an old store has no chunk checksums, so none of the integrity
            # guarantees of this version would hold for it
            hint = ("; it was written by an older demseis: regenerate it with `demseis generate` "
                    "(or `demseis render` from its particles with that older version)")
        raise StoreError(
            f"store {str(path)!r} has schema version {version!r} but this demseis "
            f"({__version__}) reads schema version {SCHEMA_VERSION}{hint}"
        )
    return meta


# --------------------------------------------------------------------------------------------
# layout


@dataclass(frozen=True)
class StoreLayout:
    """Shape of a store, derived from its arrays.

    Attributes
    ----------
    n_shards : number of shards (one shard = one DEM run).
    samples_per_shard : S, samples in every shard.
    shape : (H, W) of one sample (rows = depth, columns = x).
    arrays : sample array name -> dtype, in store order.
    params : parameter name -> dtype, sorted by name.
    """

    n_shards: int
    samples_per_shard: int
    shape: tuple[int, int]
    arrays: dict[str, np.dtype] = field(default_factory=dict)
    params: dict[str, np.dtype] = field(default_factory=dict)

    @property
    def n_samples(self) -> int:
        """Total number of samples N = n_shards * samples_per_shard."""
        return self.n_shards * self.samples_per_shard

    def shard_slice(self, shard_index: int) -> slice:
        """Sample slice ``[k*S, (k+1)*S)`` of shard ``k``."""
        s = self.samples_per_shard
        return slice(shard_index * s, (shard_index + 1) * s)

    def describe_difference(self, other: StoreLayout) -> list[str]:
        """Human-readable differences between two layouts (empty if equal)."""
        diffs = []
        for name in ("n_shards", "samples_per_shard", "shape"):
            a, b = getattr(self, name), getattr(other, name)
            if tuple(np.atleast_1d(a)) != tuple(np.atleast_1d(b)):
                diffs.append(f"{name}: {a} vs {b}")
        for name in ("arrays", "params"):
            a = {k: str(v) for k, v in getattr(self, name).items()}
            b = {k: str(v) for k, v in getattr(other, name).items()}
            if a != b:
                diffs.append(f"{name}: {a} vs {b}")
        return diffs


def _array_members(group) -> dict:
    """Every array of the store's root and of ``params``, path -> ``zarr.Array`` (e.g.
    ``"seismic"``, ``"params/dip_deg"``), their metadata read at once (two ``members()`` calls;
    one ``group[name]`` at a time, the ~90 reads took 0.1-0.2 s, paid by every shard write)."""
    import zarr

    members = dict(group.members())
    out = {k: v for k, v in members.items() if isinstance(v, zarr.Array)}
    if isinstance(members.get("params"), zarr.Group):
        out.update({f"params/{k}": v for k, v in members["params"].members()
                    if isinstance(v, zarr.Array)})
    return out


def _array_metas(path: Path) -> dict[str, ArrayMeta]:
    """Every array of the store's root and of ``params`` (the arrays of :func:`_array_members`),
    path -> :class:`~demseis.datasets._shardio.ArrayMeta`, read from their ``zarr.json`` files
    directly (a few ms for a `quick` store; through zarr, 0.05 s of every shard write).

    Raises
    ------
    StoreError
        A ``zarr.json`` is unreadable, or an array uses codecs the direct writer does not
        encode (not a store demseis created).
    """
    out: dict[str, ArrayMeta] = {}
    for prefix in ("", "params/"):
        base = path / prefix
        try:
            names = sorted(os.listdir(base))
        except FileNotFoundError:
            continue
        for name in names:
            meta_file = base / name / "zarr.json"
            try:
                meta = json.loads(meta_file.read_bytes())
            except (FileNotFoundError, NotADirectoryError):
                continue
            except (OSError, ValueError) as exc:
                raise StoreError(f"cannot read {str(meta_file)!r}: {exc}") from exc
            if isinstance(meta, dict) and meta.get("node_type") == "array":
                out[prefix + name] = array_meta(path, prefix + name, meta)
    return out


def store_layout(group) -> StoreLayout:
    """Derive the :class:`StoreLayout` of an open demseis store group.

    Raises
    ------
    StoreError
        If ``shard_done`` or every sample array is missing, or arrays disagree in shape.
    """
    return _layout_of(_array_members(group))


def _layout_of(members: Mapping[str, Any]) -> StoreLayout:
    """:func:`store_layout` from the arrays :func:`_array_members` or :func:`_array_metas`
    read (anything with ``shape``, ``dtype``, ``chunks`` and ``shards`` like a zarr array)."""
    if "shard_done" not in members:
        raise StoreError("store has no 'shard_done' array: it is incomplete or not a demseis store")
    n_shards = int(members["shard_done"].shape[0])
    arrays: dict[str, np.dtype] = {}
    shape = None
    samples_per_shard = None
    for name in SAMPLE_ARRAYS:
        if name not in members:
            continue
        arr = members[name]
        arrays[name] = np.dtype(arr.dtype)
        s = int(arr.shards[0]) if arr.shards is not None else int(arr.chunks[0])
        sh = tuple(int(v) for v in arr.shape[1:])
        if shape is None:
            shape, samples_per_shard = sh, s
        if sh != shape or s != samples_per_shard or arr.shape[0] != n_shards * s:
            raise StoreError(
                f"array {name!r} has shape {arr.shape} and {s} samples per shard, inconsistent "
                f"with {n_shards} shards of {samples_per_shard} samples of {shape}"
            )
    if not arrays:
        raise StoreError("store has no sample arrays (seismic, fault, ...)")
    params: dict[str, np.dtype] = {}
    for name in sorted(members):
        if name.startswith("params/"):
            params[name[len("params/"):]] = np.dtype(members[name].dtype)
    return StoreLayout(n_shards, int(samples_per_shard), shape, arrays, params)


# --------------------------------------------------------------------------------------------
# open / attrs


def open_store(path: str | Path, mode: str = "r"):
    """Open a demseis store and check that this demseis can read it.

    Parameters
    ----------
    path : store directory.
    mode : ``"r"`` (read only, uses consolidated metadata when present) or ``"r+"``
        (read/write, always reads the metadata files themselves).

    Returns
    -------
    zarr.Group

    Raises
    ------
    StoreError
        The path is missing, is not a Zarr v3 group, was not written by demseis, or has
        another schema version; the message says which.
    """
    import zarr

    if mode not in ("r", "r+"):
        raise InputError(f"mode must be 'r' or 'r+', got {mode!r}")
    path = Path(path)
    _check_store_metadata(path)
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message=".*[Cc]onsolidated metadata.*")
        try:
            if mode == "r":
                return zarr.open_group(path, mode="r")
            return zarr.open_group(path, mode="r+", use_consolidated=False)
        except Exception as exc:  # corrupt metadata inside a store demseis wrote
            raise StoreError(f"cannot open store {str(path)!r}: {exc}") from exc


def read_store_attrs(path: str | Path) -> dict:
    """Root attributes of a demseis store (``demseis``, ``config``, ``grid``, ``failures`` ...).

    Reads ``zarr.json`` directly, so it is cheap and always current.
    """
    return dict(_check_store_metadata(Path(path)).get("attributes", {}))


def stored_config(path: str | Path) -> dict | None:
    """The resolved config a store was created with (``attrs["config"]``), None if absent.

    The generator compares it with the config of a new run before resuming into ``path``.
    """
    return read_store_attrs(path).get("config")


def read_layout(path: str | Path) -> StoreLayout:
    """The :class:`StoreLayout` of the store at ``path``."""
    return store_layout(open_store(path, "r+"))


# --------------------------------------------------------------------------------------------
# creation


def _normalise_dtypes(arrays: Mapping[str, Any] | Iterable[str] | None) -> dict[str, np.dtype]:
    if arrays is None:
        return {name: SAMPLE_ARRAYS[name] for name in DEFAULT_ARRAYS}
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
                f"unknown sample array {name!r}; allowed: {', '.join(SAMPLE_ARRAYS)}"
            )
        fixed = SAMPLE_ARRAYS[name]
        if dtype is not None and np.dtype(dtype) != fixed:
            raise InputError(f"sample array {name!r} must have dtype {fixed}, got {np.dtype(dtype)}")
        out[name] = fixed
    if not out:
        raise InputError("arrays is empty: a store needs at least one sample array")
    # store order is the canonical SAMPLE_ARRAYS order, independent of the caller's order
    return {name: out[name] for name in SAMPLE_ARRAYS if name in out}


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
    n_shards : number of shards = number of DEM runs (>= 1).
    samples_per_shard : S, samples per shard (>= 1).
    shape : (H, W) of one sample.
    arrays : sample arrays to create, dict name -> dtype (dtypes must match
        :data:`SAMPLE_ARRAYS`) or a list of names; default :data:`DEFAULT_ARRAYS`.
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
    the store is left as it is (attrs untouched; compare :func:`stored_config` first) and
    returned, provided its layout equals the requested one; otherwise :class:`StoreError`
    names the difference.

    Raises
    ------
    StoreError
        ``path`` exists and is not a demseis store, or it is one with another layout / schema.
    InputError
        A bad argument.
    """
    import zarr

    path = Path(path)
    if int(n_shards) < 1 or int(n_shards) != n_shards:
        raise InputError(f"n_shards must be a positive integer, got {n_shards!r}")
    if int(samples_per_shard) < 1 or int(samples_per_shard) != samples_per_shard:
        raise InputError(f"samples_per_shard must be a positive integer, got {samples_per_shard!r}")
    shape_t = tuple(int(v) for v in shape)
    if len(shape_t) != 2 or min(shape_t) < 1:
        raise InputError(f"shape must be (H, W) with positive sizes, got {tuple(shape)!r}")
    array_dtypes = _normalise_dtypes(arrays)
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

    if path.exists():
        if not path.is_dir():
            raise StoreError(f"{str(path)!r} exists and is a file, not a store directory")
        if _is_demseis_store(path):
            if not overwrite:
                group = open_store(path, "r+")  # schema version check
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

    root_attrs = {
        "demseis": {"schema_version": SCHEMA_VERSION, "package_version": __version__},
        **attrs,
    }
    h, w = shape_t
    n = wanted.n_samples
    s = wanted.samples_per_shard
    row_dim, coords = _grid_coords(attrs.get("grid"), shape_t)
    specs: dict[str, dict[str, Any]] = {}  # array path -> create_array keywords
    for name, dtype in array_dtypes.items():
        spec = SAMPLE_ARRAY_SPECS[name]
        specs[name] = dict(
            shape=(n, h, w),
            dtype=dtype,
            chunks=(1, h, w),
            shards=(s, h, w),
            fill_value=fill_value_for(dtype),
            compressors=_sample_compressors(name, dtype),
            dimension_names=("sample", row_dim, "x"),
            attributes={"units": spec.units, "long_name": spec.long_name},
        )
    for name, spec in param_specs.items():
        specs[f"params/{name}"] = dict(
            shape=(n,),
            dtype=spec.dtype,
            chunks=(s,),  # one chunk per shard: each shard task owns exactly one chunk file
            fill_value=fill_value_for(spec.dtype),
            compressors=_small_compressors(),
            dimension_names=("sample",),
            attributes=_param_attrs(name, spec),
        )
    specs["shard_done"] = dict(
        shape=(wanted.n_shards,),
        dtype="uint8",
        chunks=(1,),
        fill_value=0,
        compressors=_flag_compressors(),
        dimension_names=("shard",),
        attributes={"units": "1", "long_name": "1 once the shard (one DEM run) is complete",
                    "flag_values": [0, 1], "flag_meanings": "pending done"},
    )

    def build(store) -> None:
        group = zarr.create_group(store, zarr_format=3, attributes=root_attrs)
        for name, values in coords.items():
            units, long_name = COORDS[name]
            group.create_array(name, shape=values.shape, dtype="float64", chunks=values.shape,
                               fill_value=float("nan"), compressors=_small_compressors(),
                               dimension_names=(name,),
                               attributes={"units": units, "long_name": long_name})[...] = values
        group.create_group("params")
        _create_arrays(store, specs)
        group.create_group("particles")

    _put_files(path, _zarr_files(build))
    return open_store(path, "r+")


def _zarr_files(build: Callable[[Any], None]) -> dict[str, bytes]:
    """The files (key -> bytes) zarr writes when ``build(store)`` creates groups and arrays in
    the zarr store ``store``, an in-memory one: zarr makes every byte of the metadata, and
    :func:`_put_files` writes them (through zarr's ``LocalStore``, its existence checks and
    thread hops took 0.1-0.2 s of a `quick` store's creation, about half of it)."""
    from zarr.storage import MemoryStore

    files: dict[str, Any] = {}
    build(MemoryStore(files))
    return {key: buf.to_bytes() for key, buf in files.items()}


def _put_files(path: Path, files: Mapping[str, bytes]) -> None:
    """Write ``files`` (key -> bytes, keys relative to ``path``) each atomically, the top
    ``zarr.json`` first (what zarr writes first: a store whose creation is cut short is still
    recognised as a demseis store)."""
    for key in sorted(files, key=lambda k: (k != "zarr.json", k)):
        put_file(path.joinpath(*key.split("/")), files[key])


def _create_arrays(store: Any, specs: Mapping[str, Mapping[str, Any]]) -> None:
    """Create the arrays ``path -> create_array keywords`` in the zarr store ``store``, all at
    once on zarr's event loop (one at a time, the ~90 metadata writes took 0.4 s of every
    store's creation)."""
    import zarr
    from zarr.core.sync import sync

    sync(_gather_all(zarr.api.asynchronous.create_array(store, name=name, zarr_format=3, **kw)
                     for name, kw in specs.items()))


def _grid_coords(grid: Any, shape: tuple[int, int]) -> tuple[str, dict[str, np.ndarray]]:
    """Row dimension name and coordinate values of the sample axes, from the ``grid`` attr.

    Cell centres as :class:`demseis.seismic.grid.Grid` defines them: ``x = x0_m + (j + 0.5)
    cell_m``, depth below the top ``(i + 0.5) cell_m``; time-domain stores (``domain = "time"``)
    have rows ``twt = k dt_s`` (the axis of :func:`demseis.seismic.time_axis`). No coordinates
    when the attr is absent or does not match the sample shape.
    """
    if not isinstance(grid, Mapping):
        return "depth", {}
    time = grid.get("domain", "depth") == "time"
    row_dim = "twt" if time else "depth"
    try:
        cell, nx = float(grid["cell_m"]), int(grid["nx"])
        x = float(grid["x0_m"]) + (np.arange(nx) + 0.5) * cell
        rows = (np.arange(int(grid["nt"])) * float(grid["dt_s"]) if time
                else (np.arange(int(grid["nz"])) + 0.5) * cell)
    except (KeyError, TypeError, ValueError):
        return row_dim, {}
    if (rows.shape[0], x.shape[0]) != shape:
        return row_dim, {}
    return row_dim, {row_dim: rows, "x": x}


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


# --------------------------------------------------------------------------------------------
# shard writing


def _as_sample_array(name: str, value: Any, dtype: np.dtype, shape: tuple[int, ...]) -> np.ndarray:
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
    lo, hi = LABEL_RANGES.get(name, (np.iinfo(dtype).min, np.iinfo(dtype).max))
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
    array or one whole chunk of a parameter, i.e. one file, written atomically with the bytes
    zarr would write (:func:`demseis.datasets._shardio.write_block`).

    :func:`write_shard` writes every data array of a shard through this one function (tests
    replace it to inject faults).
    """
    n = (arr.shards or arr.chunks)[0]
    if sel.start % n or sel.stop - sel.start != n:
        raise ValueError(f"{arr.path}: {sel} is not one whole chunk/shard of {n}")
    write_block(store, arr, sel.start // n, data)


def _set_flag(store: Path, done: ArrayMeta, k: int, value: int) -> None:
    """Set the done flag of shard ``k`` (0 deletes its chunk file: 0 is the fill value)."""
    write_block(store, done, k, np.array([value], dtype=np.uint8))


async def _gather_all(coros: Iterable[Any]) -> None:
    """Await every coroutine concurrently; once all have ended, raise the first error (none is
    left running behind an early error)."""
    import asyncio

    for r in await asyncio.gather(*coros, return_exceptions=True):
        if isinstance(r, BaseException):
            raise r


def write_particles(path: str | Path, run_id: int, snapshots: Sequence[Snapshot]) -> None:
    """Write the particle snapshots of DEM run ``run_id`` into ``particles/run_<id>``.

    Replaces the group if present. Called by :func:`write_shard` (the task owning that run).
    The per-element arrays of all snapshots are concatenated; ``offsets[k]:offsets[k+1]``
    selects snapshot ``k``.
    """
    import zarr

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
    name = _particle_group_name(run_id)
    _check_store_metadata(path)  # a demseis store of this version
    values = {k: data[k].astype(dtype, copy=False) for k, (dtype, *_) in PARTICLE_FIELDS.items()}
    specs = {
        k: dict(
            shape=values[k].shape,
            dtype=dtype,
            chunks=(max(1, values[k].shape[0]),),
            fill_value=0,
            compressors=_small_compressors(),
            dimension_names=(dim,),
            attributes={"units": units, "long_name": long_name},
        )
        for k, (dtype, dim, units, long_name) in PARTICLE_FIELDS.items()
    }

    def build(store) -> None:  # the group at the top of its own in-memory store
        zarr.create_group(store, zarr_format=3,
                          attributes={"run_id": int(run_id), "n_snapshots": len(snaps)})
        _create_arrays(store, specs)

    files = _zarr_files(build)
    if (path / name).exists():  # the group is replaced, as by zarr's overwrite=True
        shutil.rmtree(path / name)
    _put_files(path / name, files)
    for k in PARTICLE_FIELDS:
        if values[k].shape[0]:  # an empty array has no chunk
            meta = array_meta(path, f"{name}/{k}", json.loads(files[f"{k}/zarr.json"]))
            # every chunk is written, also one of zeros (zarr's write_empty_chunks): a missing
            # file means damage
            write_block(path, meta, 0, values[k], write_empty=True)


def read_particles(path: str | Path, run_id: int) -> list[Snapshot]:
    """The particle snapshots of DEM run ``run_id``, as written by :func:`write_shard`.

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
    import zarr

    path = Path(path)
    _check_store_metadata(path)
    name = _particle_group_name(run_id)
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


def write_shard(
    path: str | Path,
    shard_index: int,
    arrays: Mapping[str, np.ndarray],
    params: Mapping[str, Any],
    particles: Sequence[Snapshot] | None = None,
    *,
    run_id: int | None = None,
) -> None:
    """Write one complete shard (all samples of one DEM run). One task per shard.

    Order: clear the shard's done flag, write every sample array (one shard file each), the
    parameter chunks, the particle snapshots, and set the done flag last. A kill at any point
    leaves the shard not-done; calling again rewrites it (idempotent).

    Parameters
    ----------
    path : store directory (created by :func:`create_store`).
    shard_index : k in ``[0, n_shards)``; the shard holds samples ``[k*S, (k+1)*S)``.
    arrays : every sample array of the store, name -> (S, H, W) array. Float arrays must be
        finite; label arrays integers within :data:`LABEL_RANGES`.
    params : every parameter of the store, name -> (S,) array (or a scalar, broadcast).
        Integer values must fit the dtype exactly; float values must not be NaN (inf is
        allowed, e.g. ``snr_db = inf`` for noise-free samples).
    particles : the DEM run's snapshots (stored for re-rendering), or None.
    run_id : the DEM run id, used to name the particles group. Default: ``params["run_id"]``
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
    _check_store_metadata(path)
    members = _array_metas(path)
    layout = _layout_of(members)
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
    data = {n: _as_sample_array(n, arrays[n], dt, shape) for n, dt in layout.arrays.items()}
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
    writes = {**data, **{f"params/{n}": v for n, v in pdata.items()}}
    for n, v in writes.items():
        _write_array(path, members[n], sel, v)
    if particles is not None:
        write_particles(path, run_id, particles)
    _set_flag(path, done, k, 1)


# --------------------------------------------------------------------------------------------
# status, failures, finalisation


def shard_status(path: str | Path, *, verify: bool = False) -> np.ndarray:
    """Done flags of every shard: (n_shards,) uint8, 0 = pending (or failed), 1 = done.

    A flag whose chunk fails its checksum reads as 0 (pending). With ``verify``, a done shard
    whose files are damaged (:func:`demseis.datasets.integrity.shard_damage`: every chunk's
    crc32c, the shard indexes, missing files) also reads as 0, so a resumed sweep rewrites it;
    this reads every byte of the done shards once (no decoding).
    """
    from demseis.datasets.integrity import damaged_shards, read_done_flags

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
    done = np.asarray(group["shard_done"][...])
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
    """Remove killed writers' temporary files and write consolidated metadata (once, at the end
    of a sweep, when no shard task runs any more). Driver only.

    Any later metadata write (resume, :func:`record_failures`) drops the consolidated copy;
    calling this again restores it.
    """
    import zarr

    open_store(path, "r+")
    remove_partial_writes(path)  # of a killed dask worker, or of a killed earlier driver
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message=".*[Cc]onsolidated metadata.*")
        zarr.consolidate_metadata(str(Path(path)))
