"""The layout of a demseis store: its version, its shape, and the checks every reader makes.

Layout (Zarr format 3, one group; see ``docs/store.md`` for the full schema)::

    STORE/
      zarr.json               root attrs: demseis={schema_version, package_version}, config,
                              grid, failures (shard -> error text, written by the driver)
      depth (or twt), x       coordinates of the sample axes
      seismic, fault, ...     (N, H, W) sample arrays, chunks (1, H, W), shards (S, H, W): those
                              of demseis.schema.SAMPLE_ARRAYS chosen at creation, in its order
      params/<name>           (N,) per-sample parameters, chunks (S,): one chunk per shard
      shard_done              (n_shards,) uint8, chunks (1,): 1 once a shard is complete
      particles/run_<id:05d>/ particle snapshots of one DEM run (written by its shard task)

Missing data is detectable: float arrays are filled with NaN and integer arrays with a sentinel
outside their valid range (255 for uint8 labels, the dtype minimum for signed integers), so a
chunk that was never written reads as an invalid value and
:func:`~demseis.datasets.validate.validate_store` reports it.
"""

from __future__ import annotations

import json
import os
import warnings
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from demseis import __version__
from demseis.datasets._nodes import zarr_lib
from demseis.datasets._shardio import ArrayMeta, array_meta
from demseis.datasets.records import ParamColumn, columns_from_attributes
from demseis.errors import InputError, StoreError
from demseis.schema import SAMPLE_ARRAYS, SampleArray, spec_from_attributes

# zarr is imported inside the functions that use it: it takes ~0.3 s to import, and neither
# ``import demseis.datasets`` nor a shard write (write_shard, which reads the metadata files
# itself) needs it.

SCHEMA_VERSION = 3
"""Version of the on-disk layout. Readers refuse stores of any other version
(``demseis migrate`` converts a version-2 store).

1: the first layout. 2: a crc32c checksum on every chunk, coordinate arrays (``depth`` or
``twt``, and ``x``), ``units`` and ``long_name`` on every array, categorical parameters with
their category names, dimension names on the particle arrays. 3: every per-sample parameter in
one table of records (``params``, one file per shard: :mod:`demseis.datasets.records`) and its
index (``params_index``, ``params_index_files``: :mod:`demseis.datasets.index`), instead of an
array per parameter (``params/<name>``, one file per parameter and shard).
"""

MIGRATABLE_VERSIONS = (2,)
"""Schema versions ``demseis migrate`` converts to :data:`SCHEMA_VERSION`."""


#: root arrays that are not sample arrays: the done flags, the coordinates of the axes, the
#: parameter table and its index
NOT_SAMPLE_ARRAYS = ("shard_done", "depth", "twt", "x", "params", "params_index",
                     "params_index_files")


def domain_varies(grid: Any) -> bool:
    """Whether a store's ``grid`` attribute says each run has its own domain (depth sections
    and time sections in one store; the parameter table's ``dt_s`` is 0 for a depth one)."""
    return isinstance(grid, Mapping) and "domain" in (grid.get("sampling") or {})


def root_metadata(path: Path) -> dict | None:
    """Parsed ``zarr.json`` of ``path`` or None if there is none / it is not JSON."""
    meta = path / "zarr.json"
    if not meta.is_file():
        return None
    try:
        return json.loads(meta.read_text())
    except (OSError, ValueError):
        return None


def root_metadata_lost(path: Path) -> bool:
    """True when the root ``zarr.json`` of ``path`` is missing or unreadable while the store's
    ``shard_done`` array is intact: a demseis store whose root document was damaged (which
    :func:`~demseis.datasets.create.create_store` rewrites on resume)."""
    if root_metadata(path) is not None:
        return False
    try:
        meta = json.loads((path / "shard_done" / "zarr.json").read_bytes())
    except (OSError, ValueError):
        return False
    return isinstance(meta, dict) and meta.get("node_type") == "array"


def is_demseis_store(path: Path) -> bool:
    """True when ``path`` holds the root group of a demseis store (of any schema version)."""
    meta = root_metadata(path)
    return bool(
        meta
        and meta.get("node_type") == "group"
        and isinstance(meta.get("attributes", {}).get("demseis"), dict)
    )


def check_store_metadata(path: Path) -> dict:
    """Root metadata of a demseis store of this schema version, else :class:`StoreError`
    naming what is wrong (read from ``zarr.json`` directly, without zarr)."""
    if not path.exists():
        raise StoreError(f"store {str(path)!r} does not exist")
    if not path.is_dir():
        raise StoreError(f"store {str(path)!r} is a file, not a Zarr store directory")
    meta = root_metadata(path)
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
        if version in MIGRATABLE_VERSIONS:
            hint = (f"; convert it with `demseis migrate {path}` (its samples keep their bytes, "
                    "nothing is recomputed)")
        elif isinstance(version, int) and version < SCHEMA_VERSION:
            # refused, not read: an old store has no chunk checksums, so none of the integrity
            # guarantees of this version would hold for it
            hint = ("; it was written by an older demseis: regenerate it with `demseis generate` "
                    "(or `demseis render` from its particles with that older version)")
        raise StoreError(
            f"store {str(path)!r} has schema version {version!r} but this demseis "
            f"({__version__}) reads schema version {SCHEMA_VERSION}{hint}"
        )
    return meta


@dataclass(frozen=True)
class StoreLayout:
    """Shape of a store, derived from its arrays.

    Attributes
    ----------
    n_shards : number of shards (one shard = one run).
    samples_per_shard : S, samples in every shard.
    shape : (H, W) of one sample (rows = depth, columns = x).
    arrays : sample array name -> dtype, in store order.
    params : parameter name -> dtype, sorted by name.
    specs : sample array name -> its declaration as the store describes it (role, units,
        fill, valid range: :func:`sample_specs`); not compared by :meth:`describe_difference`.
    columns : parameter name -> its :class:`~demseis.datasets.records.ParamColumn` (dtype,
        categories, units), in the order of the table's records; not compared.
    table : True when the parameters are one table of records (``params``, as
        :func:`~demseis.datasets.create.create_store` makes them), False for one array per
        parameter (``params/<name>``, a store assembled by hand with zarr).
    """

    n_shards: int
    samples_per_shard: int
    shape: tuple[int, int]
    arrays: dict[str, np.dtype] = field(default_factory=dict)
    params: dict[str, np.dtype] = field(default_factory=dict)
    specs: dict[str, SampleArray] = field(default_factory=dict, compare=False, repr=False)
    columns: dict[str, ParamColumn] = field(default_factory=dict, compare=False, repr=False)
    table: bool = field(default=True, compare=False)

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
    one ``group[name]`` at a time, the ~90 reads took 0.1-0.2 s)."""
    zarr = zarr_lib()

    try:
        with warnings.catch_warnings():  # an array directory without zarr.json: named below
            warnings.filterwarnings("ignore", message=".*not recognized as a component.*")
            members = dict(group.members())
        out = {k: v for k, v in members.items() if isinstance(v, zarr.Array)}
        if isinstance(members.get("params"), zarr.Group):
            out.update({f"params/{k}": v for k, v in members["params"].members()
                        if isinstance(v, zarr.Array)})
    except Exception as exc:  # noqa: BLE001 - a damaged zarr.json of an array (JSON, schema)
        text = " ".join(str(exc).split())[:200]
        where = str(getattr(group.store, "root", group.store))
        raise StoreError(f"a metadata file (zarr.json) of store {where!r} is damaged "
                         f"({type(exc).__name__}: {text}); `demseis validate` names it, "
                         "`demseis generate` rewrites it") from None
    return out


def array_metas(path: Path) -> dict[str, ArrayMeta]:
    """Every array of the store's root and of ``params`` (the arrays of :func:`store_layout`),
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


def metadata_problems(path: str | Path) -> list[str]:
    """One line per damaged metadata document below the root of the store at ``path``: every
    group and array directory must hold a ``zarr.json`` that parses as JSON, is a Zarr v3 group
    or array, and (for an array) has metadata the direct writer understands (data type, shape,
    chunk grid, codecs). Chunk directories (``c/``) are not entered, so the cost is that of the
    metadata files, whatever the number of chunks. Hidden directories (a name starting with
    ``.``) are a writer's scratch, not part of the store: a particle group being built, or
    ``demseis migrate``'s staging; they are not entered either."""
    path = Path(path)
    out: list[str] = []
    for top, dirs, _files in os.walk(path):
        here = Path(top)
        rel = here.relative_to(path).as_posix()
        dirs[:] = sorted(d for d in dirs if d != "c" and not d.startswith("."))
        if rel == ".":
            continue
        meta_file = here / "zarr.json"
        try:
            meta = json.loads(meta_file.read_bytes())
        except FileNotFoundError:
            out.append(f"metadata of {rel!r} is missing (no {str(meta_file)!r})")
            continue
        except (OSError, ValueError) as exc:
            out.append(f"metadata of {rel!r} is damaged ({str(meta_file)!r}: {exc})")
            continue
        kind = meta.get("node_type") if isinstance(meta, dict) else None
        if kind not in ("array", "group") or meta.get("zarr_format") != 3:
            out.append(f"metadata of {rel!r} is not a Zarr v3 group or array "
                       f"({str(meta_file)!r})")
        elif kind == "array":
            try:
                array_meta(path, rel, meta)
            except StoreError as exc:
                out.append(f"metadata of {rel!r} is damaged ({exc})")
    return out


def store_layout(group) -> StoreLayout:
    """Derive the :class:`StoreLayout` of an open demseis store group.

    Raises
    ------
    StoreError
        If ``shard_done`` or every sample array is missing, or arrays disagree in shape.
    """
    return layout_of(_array_members(group))


def _attributes(member: Any) -> Mapping[str, Any]:
    """Attributes of a zarr array or an :class:`ArrayMeta`."""
    if isinstance(member, ArrayMeta):
        return member.attributes
    attrs = getattr(member, "attrs", None)
    return {} if attrs is None else dict(attrs)


def sample_specs(members: Mapping[str, Any]) -> dict[str, SampleArray]:
    """The sample arrays among a store's root arrays, name -> declaration, in store order.

    An array that describes itself (a ``demseis`` attribute, :meth:`SampleArray.store_attributes`)
    is declared by its attributes, so an array a plug-in added reads, validates and trains
    without the plug-in. An array without one (a store written before arrays described
    themselves) is a sample array when its name is registered, with the registered
    declaration. Order: the registered arrays in registry order, then the others by name.

    Raises
    ------
    StoreError
        An array's attributes name a role but are not a valid declaration.
    """
    out: dict[str, SampleArray] = {}
    for name, member in members.items():
        if "/" in name or name in NOT_SAMPLE_ARRAYS:
            continue
        try:
            spec = spec_from_attributes(name, member.dtype, _attributes(member))
        except InputError as exc:
            raise StoreError(str(exc)) from None
        if spec is None and name in SAMPLE_ARRAYS:
            spec = SAMPLE_ARRAYS.get(name)
        if spec is not None:
            out[name] = spec
    known = SAMPLE_ARRAYS.names()
    order = [n for n in known if n in out] + sorted(n for n in out if n not in known)
    return {n: out[n] for n in order}


def layout_of(members: Mapping[str, Any]) -> StoreLayout:
    """:func:`store_layout` from the arrays :func:`_array_members` or :func:`array_metas`
    read (anything with ``shape``, ``dtype``, ``chunks`` and ``shards`` like a zarr array)."""
    if "shard_done" not in members:
        raise StoreError("store has no 'shard_done' array: it is incomplete or not a demseis store")
    n_shards = int(members["shard_done"].shape[0])
    arrays: dict[str, np.dtype] = {}
    shape = None
    samples_per_shard = None
    specs = sample_specs(members)
    for name in specs:
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
    columns = param_columns(members)
    params = {name: np.dtype(c.dtype) for name, c in columns.items()}
    return StoreLayout(n_shards, int(samples_per_shard), shape, arrays, params, specs, columns,
                       "params" in members)


def param_columns(members: Mapping[str, Any]) -> dict[str, ParamColumn]:
    """The per-sample parameters of a store, name -> column: the columns of its ``params``
    table in record order (name order, as :func:`~demseis.datasets.create.create_store`
    writes them), or (a store assembled by hand with zarr) its ``params/<name>`` arrays by
    name."""
    table = members.get("params")
    if table is not None:
        return columns_from_attributes(_attributes(table), "array 'params'")
    out = {}
    for name in sorted(members):
        if name.startswith("params/"):
            attrs = _attributes(members[name])
            cats = attrs.get("categories")
            out[name[len("params/"):]] = ParamColumn(
                name[len("params/"):], np.dtype(members[name].dtype),
                None if cats is None else tuple(str(c) for c in cats), attrs)
    return out


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
    zarr = zarr_lib()

    if mode not in ("r", "r+"):
        raise InputError(f"mode must be 'r' or 'r+', got {mode!r}")
    path = Path(path)
    check_store_metadata(path)
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
    return dict(check_store_metadata(Path(path)).get("attributes", {}))


def stored_config(path: str | Path) -> dict | None:
    """The resolved config a store was created with (``attrs["config"]``), None if absent.

    The generator compares it with the config of a new run before resuming into ``path``.
    """
    return read_store_attrs(path).get("config")


def read_layout(path: str | Path) -> StoreLayout:
    """The :class:`StoreLayout` of the store at ``path``."""
    return store_layout(open_store(path, "r+"))

