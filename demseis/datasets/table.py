"""The done samples of a store and their parameters, read at the cost of the done shards.

A store is planned whole (every array has its final shape when it is created), but only the
shards written so far hold data. Reading the parameters through zarr visits every chunk of the
planned store: a 1000-run store with 2 shards done took 10 s to open, a 100,000-run one more
than 14 minutes. Here the done flags are the files of ``shard_done/c`` that exist (a pending
flag has no file) and the parameters are the records of the done shards, from the index of the
parameter table (a file per block of shards, :mod:`demseis.datasets.index`) or from each
shard's chunk of the table, decoded directly
(:meth:`~demseis.datasets._shardio.ChunkEncoder.decode`, crc32c checked), so opening a store
costs what its written samples cost, whatever its planned size.

:func:`read_done_params` gives the compact table (done samples only);
:class:`FullParams` the (N,) per-sample view over the whole store that the public API
promises (``Store.params``, a ``where`` callable), built per parameter when first asked for.
"""

from __future__ import annotations

from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from demseis.datasets._shardio import ArrayMeta
from demseis.datasets.checked import read_error_text
from demseis.datasets.index import index_current, indexed_rows, read_table_chunk
from demseis.datasets.integrity import flag_files, read_done_flags
from demseis.datasets.layout import (StoreLayout, array_metas, check_store_metadata, layout_of,
                                     open_store, param_columns, sample_specs)
from demseis.datasets.records import ParamColumn, unpack
from demseis.errors import StoreError


@dataclass(frozen=True)
class DoneParams:
    """The parameters of the done samples of a store.

    Attributes
    ----------
    path : the store.
    layout : the store's layout.
    shards : (n_done_shards,) int64, the done shards in increasing order.
    samples : (n_done_samples,) int64, their global sample indices in increasing order.
    values : parameter name -> (n_done_samples,) array, in ``samples`` order.
    categories : parameter name -> category names of each categorical parameter.
    metas : parameter name -> its :class:`~demseis.datasets.records.ParamColumn`.
    records : (n_done_samples, R) uint8, the table's records of the done samples (the
        parameters not in ``values`` are unpacked from them when asked for); None for a store
        assembled by hand (``values`` then holds every parameter).
    """

    path: Path
    layout: StoreLayout
    shards: np.ndarray
    samples: np.ndarray
    values: dict[str, np.ndarray]
    categories: dict[str, list[str]]
    metas: dict[str, ParamColumn]
    records: np.ndarray | None = None


def done_shard_indices(path: str | Path, n_shards: int) -> np.ndarray:
    """(n_done,) int64 indices of the done shards (a damaged flag counts as not done), from
    the flag files that exist: no cost per pending shard."""
    flags, _ = read_done_flags(path, n_shards)
    return np.flatnonzero(flags == 1).astype(np.int64)


def read_shard_records(path: Path, table: ArrayMeta, shard: int, s: int,
                       sample: int | None = None) -> np.ndarray:
    """(S, R) records of shard ``shard`` from its chunk of the parameter table, its checksum
    checked; :class:`StoreError` naming the samples (``sample`` alone when given) if the chunk
    is missing or damaged."""
    s0 = shard * s
    which = f"sample {sample}" if sample is not None else f"samples {s0}..{s0 + s - 1}"
    f = table.block_file(path, shard)
    what = f"parameters of {which} in {str(path)!r}"
    try:
        return read_table_chunk(path, table, shard, s)[0]
    except FileNotFoundError:
        raise StoreError(f"{what}: never written (file {str(f)!r} is missing although the "
                         f"shard is done); run `demseis validate {path}`") from None
    except ValueError as exc:  # crc32c mismatch, undecodable bytes
        raise StoreError(f"{what}: damaged ({exc} in {str(f)!r}); run "
                         f"`demseis validate {path}`") from None


def done_records(path: Path, members: Mapping[str, ArrayMeta],
                 layout: StoreLayout) -> tuple[np.ndarray, np.ndarray]:
    """The done shards of a store with a parameter table (increasing) and their records
    ((n_done * S, R) uint8, in shard order): from the index where it holds a shard's current
    chunk (:mod:`demseis.datasets.index`), else from the shard's own chunk, its done flag read
    first (a shard the index holds counts as done while its flag file exists: the flag's own
    checksum is ``validate``'s to check). Costs one directory listing of the flags, one read
    per index block, a read of the last bytes of each candidate's table chunk (is it the one
    indexed?) or, when the index is current (:func:`~demseis.datasets.index.index_current`),
    of one per index block, and one read (flag and chunk) per shard the index lacks."""
    s = layout.samples_per_shard
    candidates = flag_files(path, layout.n_shards)
    indexed = indexed_rows(path, members, candidates, s, current=index_current(path))
    rest = np.array([k for k in candidates.tolist() if k not in indexed], dtype=np.int64)
    flags, _ = read_done_flags(path, layout.n_shards, shards=rest)
    shards = np.array(sorted(set(indexed) | set(np.flatnonzero(flags == 1).tolist())),
                      dtype=np.int64)
    width = members["params"].shape[1]
    rows = np.empty((shards.shape[0] * s, width), dtype=np.uint8)
    for i, k in enumerate(shards.tolist()):
        got = indexed.get(k)
        rows[i * s:(i + 1) * s] = (got if got is not None
                                   else read_shard_records(path, members["params"], k, s))
    return shards, rows


def read_done_params(path: str | Path, names: Sequence[str] | None = None) -> DoneParams:
    """The done shards of the store at ``path`` and the parameters ``names`` (default all) of
    their samples, each chunk's crc32c checked.

    Costs the listing of the flags, a read per block of the index
    (:mod:`demseis.datasets.index`), and a read of the flag and of the table chunk of each done
    shard the index lacks; nothing per pending shard.

    Raises
    ------
    StoreError
        Not a demseis store of this schema version, unreadable metadata, or a missing or
        damaged parameter chunk of a done shard (naming the samples).
    """
    path = Path(path)
    check_store_metadata(path)
    members = array_metas(path)
    try:
        layout = layout_of(members)
    except StoreError:
        layout = None
    if layout is None or not _direct_readable(members, layout):
        return _read_through_zarr(path, members)
    columns = layout.columns
    s = layout.samples_per_shard
    if layout.params:
        shards, rows = done_records(path, members, layout)
    else:
        shards = done_shard_indices(path, layout.n_shards)
        rows = np.zeros((shards.shape[0] * s, 0), np.uint8)
    samples = (shards[:, None] * s + np.arange(s)[None, :]).reshape(-1)
    wanted = list(columns) if names is None else [n for n in names if n in columns]
    values = _unpack(rows, layout, wanted)
    categories = {n: list(c.categories) for n, c in columns.items() if c.categories is not None}
    return DoneParams(path, layout, shards, samples, values, categories, dict(columns), rows)


def _unpack(rows: np.ndarray, layout: StoreLayout, names: Sequence[str]) -> dict[str, np.ndarray]:
    """Columns ``names`` of the records ``rows`` of a store laid out as ``layout``."""
    if not names:
        return {}
    cols = list(layout.columns.values())
    try:
        return unpack(rows, cols, names)
    except ValueError as exc:
        raise StoreError(f"the parameter table does not match its declaration ({exc})") from None


def shard_params(path: str | Path, shard: int,
                 sample: int | None = None) -> dict[str, tuple[np.ndarray, ParamColumn]] | None:
    """Every parameter of shard ``shard``: name -> (its S values, its column), read from the
    shard's chunk of the parameter table with its crc32c checked (one file, no zarr round
    trip); None for a store laid out otherwise (read it through zarr). ``sample``: the sample
    an error names."""
    path = Path(path)
    members = array_metas(path)
    try:
        layout = layout_of(members)
    except StoreError:
        return None
    if not _direct_readable(members, layout):
        return None
    if not layout.params:
        return {}
    s = layout.samples_per_shard
    rows = read_shard_records(path, members["params"], shard, s, sample)
    values = _unpack(rows, layout, list(layout.columns))
    return {n: (values[n], c) for n, c in layout.columns.items()}


def _direct_readable(members: Mapping[str, ArrayMeta], layout: StoreLayout) -> bool:
    """True for the layout :func:`~demseis.datasets.create.create_store` makes: a parameter
    table with one chunk per shard and done flags of one value, every chunk ending in its
    crc32c."""
    flags = members["shard_done"]
    if flags.chunks != (1,) or flags.encoder.names[-1:] != ("crc32c",):
        return False
    if not layout.table:
        return not layout.params
    table = members["params"]
    return (table.shards is None and table.chunks[0] == layout.samples_per_shard
            and table.encoder.names[-1:] == ("crc32c",))


def _read_through_zarr(path: Path, members: Mapping[str, ArrayMeta]) -> DoneParams:
    """:func:`read_done_params` of a store laid out otherwise (assembled by hand with zarr:
    an array per parameter, other chunks, no checksums): every parameter read whole through
    zarr."""
    root = open_store(path, "r")
    sample_names = list(sample_specs(members))
    if not sample_names or "shard_done" not in members:
        raise StoreError(f"store {str(path)!r} has no sample arrays or no 'shard_done' array: "
                         "it is incomplete or not a demseis store")
    n_shards = int(members["shard_done"].shape[0])
    n = int(members[sample_names[0]].shape[0])
    if n_shards == 0 or n % n_shards:
        raise StoreError(f"store {str(path)!r}: {n} samples do not split into {n_shards} shards")
    s = n // n_shards
    columns = param_columns(members)
    layout = StoreLayout(n_shards, s, tuple(members[sample_names[0]].shape[1:]),
                         {k: members[k].dtype for k in sample_names},
                         {k: c.dtype for k, c in columns.items()}, columns=columns,
                         table=False)
    flags, _ = read_done_flags(path, n_shards, root["shard_done"])
    shards = np.flatnonzero(flags == 1).astype(np.int64)
    samples = (shards[:, None] * s + np.arange(s)[None, :]).reshape(-1)
    values = {}
    for name in columns:
        if members[f"params/{name}"].shape != (n,):
            continue
        try:
            values[name] = np.asarray(root["params"][name][:])[samples]
        except Exception as exc:  # noqa: BLE001 - a damaged chunk: name it
            raise StoreError(f"parameter {name!r} of store {str(path)!r} is damaged ({read_error_text(exc)}); "
                             f"run `demseis validate {path}`") from None
    metas = {k: c for k, c in columns.items() if k in values}
    categories = {k: list(c.categories) for k, c in metas.items() if c.categories is not None}
    return DoneParams(path, layout, shards, samples, values, categories, metas)


class FullParams(Mapping):
    """Parameter name -> (N,) array over every sample of the store: the values of the done
    samples, the parameter's fill value elsewhere (NaN, or the integer sentinel). Categorical
    parameters as their names (``"?"`` where not done) with ``decode``.

    Each array is built when first asked for (N values), so a store planned for millions of
    samples pays for the parameters one looks at, not for all of them.
    """

    def __init__(self, table: DoneParams, *, decode: bool = False) -> None:
        self._table = table
        self._decode = decode
        self._cache: dict[str, np.ndarray] = {}

    def _done(self, name: str) -> np.ndarray:
        """Values of parameter ``name`` at the done samples (read now if the table lacks it)."""
        t = self._table
        if name not in t.values:
            t.values.update(_unpack(t.records, t.layout, [name]))
        return t.values[name]

    def _decoded(self, name: str, values: np.ndarray) -> np.ndarray:
        """``values`` as category names (``"?"`` for a code out of range, e.g. the fill
        value) when decoding a categorical parameter, else unchanged."""
        cats = self._table.metas[name].categories
        if not self._decode or cats is None:
            return values
        table = np.asarray(list(cats) + ["?"], dtype=str)
        return table[np.where((values >= 0) & (values < len(cats)), values, len(cats))]

    def __getitem__(self, name: str) -> np.ndarray:
        if name not in self._cache:
            t = self._table
            if name not in t.metas:
                raise KeyError(name)
            meta = t.metas[name]
            full = np.full(t.layout.n_samples, meta.fill_value, dtype=meta.dtype)
            full[t.samples] = self._done(name)
            self._cache[name] = self._decoded(name, full)
        return self._cache[name]

    def take(self, samples: np.ndarray) -> dict[str, np.ndarray]:
        """Every parameter at the sample indices ``samples``, without building the (N,)
        arrays (what a score over a few samples of a huge store needs)."""
        t = self._table
        samples = np.asarray(samples, dtype=np.int64)
        if t.samples.shape[0]:
            pos = np.minimum(np.searchsorted(t.samples, samples), t.samples.shape[0] - 1)
            hit = t.samples[pos] == samples
        else:
            pos, hit = np.zeros(samples.shape, np.int64), np.zeros(samples.shape, bool)
        out = {}
        for name in self:
            vals = np.full(samples.shape, t.metas[name].fill_value, dtype=t.metas[name].dtype)
            vals[hit] = self._done(name)[pos[hit]]
            out[name] = self._decoded(name, vals)
        return out

    def __iter__(self) -> Iterator[str]:
        return iter(self._table.metas)

    def __len__(self) -> int:
        return len(self._table.metas)
