"""PyTorch access to a demseis store: :class:`FaultSegDataset` and :class:`ShardAwareSampler`.

Neither class imports torch at module import time, and neither subclasses torch's classes
(``DataLoader`` only needs ``__len__``/``__getitem__`` and an iterable sampler), so
``demseis.datasets`` stays light for the dask workers that only write stores.
"""

from __future__ import annotations

import sys
from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numcodecs import blosc

from demseis.datasets._shardio import RawShardReader, raw_shard_layout
from demseis.datasets.checked import CheckedArray, read_error_text
from demseis.datasets.layout import open_store, store_layout
from demseis.datasets.records import fill_value_for
from demseis.datasets.status import shard_status
from demseis.datasets.table import FullParams, read_done_params, shard_params
from demseis.errors import InputError, StoreError, import_torch

SPLITS = ("train", "val", "test")


def split_of_shards(n_shards: int, fractions: Sequence[float] = (0.8, 0.1, 0.1),
                    seed: int = 0) -> np.ndarray:
    """Split label (0 train, 1 val, 2 test) of every shard, i.e. of every run.

    The shards (one run each) are permuted with ``numpy.random.default_rng(seed)`` and cut
    at the cumulative fractions: val and test get ``round(f * n_shards)`` shards each (at least
    one when their fraction is positive and there are at least three shards), train the rest.
    It depends only on ``n_shards``, ``fractions`` and ``seed``, not on which shards are done,
    so a run never changes split when a store is resumed.

    Returns
    -------
    (n_shards,) int8 array
    """
    f = np.asarray(fractions, dtype=float)
    if f.shape != (3,) or (f < 0).any() or not np.isclose(f.sum(), 1.0):
        raise InputError(
            f"split_fractions must be three non-negative fractions (train, val, test) summing to "
            f"1, got {tuple(fractions)!r}"
        )
    n = int(n_shards)
    n_val, n_test = (int(round(x * n)) for x in f[1:])
    if n >= 3:
        n_val = max(n_val, 1) if f[1] > 0 else 0
        n_test = max(n_test, 1) if f[2] > 0 else 0
    n_val = min(n_val, n)
    n_test = min(n_test, n - n_val)
    labels = np.zeros(n, dtype=np.int8)
    order = np.random.default_rng(seed).permutation(n)
    labels[order[n - n_val - n_test: n - n_test]] = 1
    labels[order[n - n_test:]] = 2
    return labels


_MASK64 = (1 << 64) - 1


def _in_dataloader_worker() -> bool:
    """True inside a torch DataLoader worker process (torch is then already imported)."""
    data = sys.modules.get("torch.utils.data")
    return bool(data is not None and data.get_worker_info() is not None)


def _splitmix64(x: np.ndarray) -> np.ndarray:
    """SplitMix64 finaliser on uint64 arrays (a bijective, well-mixing integer hash)."""
    x = x + np.uint64(0x9E3779B97F4A7C15)
    x = (x ^ (x >> np.uint64(30))) * np.uint64(0xBF58476D1CE4E5B9)
    x = (x ^ (x >> np.uint64(27))) * np.uint64(0x94D049BB133111EB)
    return x ^ (x >> np.uint64(31))


def crop_offsets(seed: int, epoch: int, samples: np.ndarray, n_rows: int,
                 n_cols: int) -> tuple[np.ndarray, np.ndarray]:
    """Crop window origins of ``samples`` in ``epoch``: row in [0, n_rows), column in [0, n_cols).

    A pure function of (seed, epoch, sample index), vectorised: SplitMix64 of the three
    chained, one 32-bit half per coordinate, reduced by multiply-shift (bias < n / 2**32).
    """
    with np.errstate(over="ignore"):
        key = _splitmix64(np.asarray([seed & _MASK64], dtype=np.uint64))
        key = _splitmix64(key ^ np.uint64(epoch & _MASK64))
        h = _splitmix64(key ^ np.asarray(samples, dtype=np.uint64))
    lo = h & np.uint64(0xFFFFFFFF)
    hi = h >> np.uint64(32)
    rows = ((lo * np.uint64(n_rows)) >> np.uint64(32)).astype(np.int64)
    cols = ((hi * np.uint64(n_cols)) >> np.uint64(32)).astype(np.int64)
    return rows, cols


def _where_value(name: str, c: Any, v: np.ndarray,
                 categories: Mapping[str, Sequence[str]]) -> Any:
    """A ``where`` value as the stored number: a category name -> its code, ``"inf"`` -> inf.

    Raises InputError naming the parameter and the valid values for anything else.
    """
    cats = categories.get(name)
    if cats is not None:
        if isinstance(c, str):
            if c not in cats:
                raise InputError(f"where[{name!r}] = {c!r} is not a category of {name}; valid: "
                                 + ", ".join(repr(x) for x in cats))
            return cats.index(c)
        if isinstance(c, (int, np.integer)) and not isinstance(c, bool) and 0 <= c < len(cats):
            return int(c)
        raise InputError(f"where[{name!r}] = {c!r}: expected one of "
                         + ", ".join(repr(x) for x in cats))
    if c is None:  # an open end of a (low, high) range
        return None
    if isinstance(c, str):
        try:
            c = float(c)  # "inf", "-inf", "20"
        except ValueError:
            raise InputError(f"where[{name!r}] = {c!r}: expected a number") from None
    if isinstance(c, bool) or not isinstance(c, (int, float, np.integer, np.floating)):
        raise InputError(f"where[{name!r}] = {c!r}: expected a number")
    if np.isnan(c):
        raise InputError(f"where[{name!r}] = nan matches nothing; give a number")
    return c


def _where_mask(where: Any, params: Mapping[str, np.ndarray], n: int,
                categories: Mapping[str, Sequence[str]] | None = None) -> np.ndarray:
    """Boolean mask of the samples selected by ``where`` (see :class:`FaultSegDataset`)."""
    categories = categories or {}
    if where is None:
        return np.ones(n, dtype=bool)
    if callable(where):
        mask = np.asarray(where(params))
        if mask.shape != (n,) or mask.dtype != bool:
            raise InputError(
                f"where(params) must return a ({n},) bool array, got {mask.dtype} {mask.shape}"
            )
        return mask
    if not isinstance(where, Mapping):
        raise InputError(f"where must be None, a dict or a callable, got {type(where).__name__}")
    mask = np.ones(n, dtype=bool)
    for name, cond in where.items():
        if name not in params:
            raise InputError(f"where: unknown parameter {name!r}; stored: {sorted(params)}")
        v = params[name]
        if isinstance(cond, tuple):
            if len(cond) != 2:
                raise InputError(f"where[{name!r}]: a range is (low, high), got {cond!r}")
            lo, hi = (_where_value(name, c, v, categories) for c in cond)
            m = np.ones(n, dtype=bool)
            if lo is not None:
                m &= v >= lo
            if hi is not None:
                m &= v <= hi
        elif isinstance(cond, (list, set, frozenset, np.ndarray)):
            m = np.zeros(n, dtype=bool)
            for c in cond:
                m |= _equal(v, _where_value(name, c, v, categories))
        else:
            if cond is None:
                raise InputError(f"where[{name!r}] = None: give a value, a (low, high) range or "
                                 "a list")
            m = _equal(v, _where_value(name, cond, v, categories))
        mask &= m
    return mask


def _equal(v: np.ndarray, c: Any) -> np.ndarray:
    if v.dtype.kind == "f" and np.isfinite(c):
        # parameters are float32 on disk: compare at float32 precision
        return np.isclose(v, c, rtol=1e-6, atol=0.0)
    return v == c


@dataclass(frozen=True)
class Sample:
    """One stored sample: its arrays (name -> (H, W)) and parameters (categorical ones as
    their names)."""

    index: int
    arrays: dict[str, np.ndarray]
    params: dict[str, Any]


def read_sample(path: str | Path, index: int, arrays: Sequence[str] | None = None) -> Sample:
    """Read sample ``index`` of a store, checking every chunk's checksum.

    Parameters
    ----------
    path : store directory.
    index : global sample index in ``[0, N)``.
    arrays : sample arrays to read (default: all).

    Raises
    ------
    InputError
        ``index`` out of range, or an array the store does not hold.
    StoreError
        The sample's shard is not done, or a chunk of the sample is damaged (the message names
        the sample and the array).
    """
    group = open_store(path, "r")
    layout = store_layout(group)
    n = layout.n_samples
    if isinstance(index, bool) or not isinstance(index, (int, np.integer)) or not 0 <= index < n:
        raise InputError(f"sample index {index!r} is outside the store's samples 0..{n - 1}")
    index = int(index)
    names = list(layout.arrays) if arrays is None else list(arrays)
    for name in names:
        if name not in layout.arrays:
            raise InputError(f"array {name!r} is not in store {str(path)!r}; it holds "
                             f"{list(layout.arrays)}")
    k = index // layout.samples_per_shard
    if shard_status(path)[k] != 1:
        raise StoreError(f"sample {index} of {str(path)!r} is in shard {k}, which is not done "
                         "(pending or failed); rerun the generator to complete it")
    # checksums and missing shard files: a StoreError naming the sample and the array
    out = {name: CheckedArray(group[name], path, name)[index] for name in names}
    params: dict[str, Any] = {}
    direct = shard_params(path, k, index)  # one file per parameter; None: read through zarr
    if direct is not None:
        for name, (values, meta) in direct.items():
            value = values[index - k * layout.samples_per_shard].item()
            cats = meta.categories
            params[name] = cats[int(value)] if cats and 0 <= int(value) < len(cats) else value
        return Sample(index, out, params)
    for name in layout.params:
        arr = group["params"][name]
        try:
            value = arr[index].item()
        except Exception as exc:  # noqa: BLE001
            raise StoreError(f"parameter {name!r} of sample {index} in {str(path)!r} is damaged "
                             f"({read_error_text(exc)}); run `demseis validate {path}`") from exc
        cats = arr.attrs.get("categories")
        params[name] = cats[int(value)] if cats and 0 <= int(value) < len(cats) else value
    return Sample(index, out, params)


class FaultSegDataset:
    """A map-style PyTorch dataset over the done shards of a demseis store.

    Parameters
    ----------
    path : store directory.
    inputs : sample arrays stacked as input channels, e.g. ``("seismic",)``.
    targets : sample arrays returned as targets, e.g. ``("fault",)``.
    where : sample filter on the per-sample parameters. None (all), a dict
        ``name -> value`` (equal; floats at float32 precision), ``name -> (low, high)``
        (inclusive range, either end None), ``name -> [v1, v2, ...]`` (any of), several keys
        combined with AND; or a callable ``f(params) -> (N,) bool`` where ``params`` maps every
        parameter name to its (N,) array over all samples. Categorical parameters take their
        names (``{"noise_kind": "band"}``; an unknown name is an error listing the valid ones),
        numbers may be given as strings (``"inf"``). A filter that selects none of the done
        samples is an error naming it.
    split : None (every run) or ``"train"``, ``"val"``, ``"test"``: the samples of the runs
        in that split (:func:`split_of_shards`). Splits never share a run.
    split_fractions : (train, val, test) fractions of runs.
    split_seed : seed of the run permutation (fixed: the same store gives the same split).
    crop : None (whole samples), an int (square) or (h, w): a random window, the same for the
        inputs and the targets of one sample.
    transform : callable ``(x, y) -> (x, y)`` applied to the tensors of each item.
    seed : seed of the crop positions. The window of sample ``i`` in epoch ``e`` is a hash of
        ``(seed, e, i)`` (:func:`crop_offsets`), so it does not depend on worker count or order.
    long_labels : return label targets (fault, damage, layer) as int64 instead of their compact
        storage dtypes (uint8, uint8, int16). Compact labels move 8x fewer bytes from the
        DataLoader workers (measured to be the bottleneck with 2 workers); cast on the device:
        ``y.long()`` for ``CrossEntropyLoss``, ``y.float()`` for ``BCEWithLogitsLoss``.

    Items
    -----
    ``(x, y)`` where ``x`` is a float32 tensor (C, h, w) with one channel per input, and ``y``
    is, for one target, a tensor (h, w): uint8 for fault (0/1) and damage (0/1/2), int16 for
    layer (int64 for all three with ``long_labels=True``), float32 for strain, impedance and
    seismic; for several targets, a dict name -> such tensor. Batched by the default collate:
    x (B, C, h, w), y (B, h, w).

    Notes
    -----
    The store is opened lazily in each process; pickling keeps only the path, the options and
    the selected sample indices (numbers), so the dataset works with ``num_workers > 0``. Reads
    go through ``__getitems__``: a batch reads each shard it touches in one Zarr call per array,
    so a :class:`ShardAwareSampler` (batches from few shards) makes epochs fast. Use
    :meth:`set_epoch` between epochs to draw new crops (with non-persistent workers).
    """

    def __init__(
        self,
        path: str | Path,
        inputs: Sequence[str] = ("seismic",),
        targets: Sequence[str] = ("fault",),
        *,
        where: Mapping[str, Any] | Callable[[Mapping[str, np.ndarray]], np.ndarray] | None = None,
        split: str | None = None,
        split_fractions: Sequence[float] = (0.8, 0.1, 0.1),
        split_seed: int = 0,
        crop: int | Sequence[int] | None = None,
        transform: Callable | None = None,
        seed: int = 0,
        long_labels: bool = False,
    ) -> None:
        self.path = str(path)
        self.long_labels = bool(long_labels)
        self.inputs = tuple(inputs) if not isinstance(inputs, str) else (inputs,)
        self.targets = tuple(targets) if not isinstance(targets, str) else (targets,)
        self.transform = transform
        self.seed = int(seed)
        self.epoch = 0
        self.split = split
        group = open_store(self.path, "r")
        layout = store_layout(group)
        self.layout = layout
        if not self.inputs:
            raise InputError("inputs is empty: give at least one sample array, e.g. ('seismic',)")
        for name in self.inputs + self.targets:
            if name not in layout.arrays:
                raise InputError(
                    f"array {name!r} is not in store {self.path!r}; it holds {list(layout.arrays)}"
                )
        if split is not None and split not in SPLITS:
            raise InputError(f"split must be one of {SPLITS} or None, got {split!r}")
        self.crop = _normalise_crop(crop, layout.shape)

        s = layout.samples_per_shard
        # the done samples and their parameters only: no cost per pending shard
        table = read_done_params(self.path)
        self.categories = dict(table.categories)
        done_idx, params = table.samples, table.values
        n_done = int(done_idx.size)
        if callable(where):  # promised the (N,) columns of every sample
            sample_ok = _where_mask(where, FullParams(table), layout.n_samples)[done_idx]
        else:
            sample_ok = _where_mask(where, params, n_done, self.categories)
        if where is not None and n_done and not sample_ok.any():
            raise InputError(f"where={where!r} selects none of the {n_done} done samples of "
                             f"{self.path!r}")
        if split is not None:
            labels = split_of_shards(layout.n_shards, split_fractions, split_seed)
            sample_ok &= labels[done_idx // s] == SPLITS.index(split)
        self.indices = done_idx[sample_ok].astype(np.int64)
        self._params = {n: v[sample_ok] for n, v in params.items()}
        self._arrays: dict[str, Any] | None = None
        self._raw: dict[str, RawShardReader] = {}

    # -- pickling: path and numbers only; each worker reopens the store lazily
    def __getstate__(self) -> dict:
        state = self.__dict__.copy()
        state["_arrays"] = None
        state["_raw"] = {}
        return state

    def __setstate__(self, state: dict) -> None:
        self.__dict__.update(state)

    def __len__(self) -> int:
        return int(self.indices.shape[0])

    def set_epoch(self, epoch: int) -> None:
        """Use crop windows of ``epoch`` (call before creating the epoch's iterator)."""
        self.epoch = int(epoch)

    @property
    def run_ids(self) -> np.ndarray:
        """(len,) run id of each item (``params/run_id`` if stored, else the shard index)."""
        if "run_id" in self._params:
            return self._params["run_id"].astype(np.int64)
        return self.indices // self.layout.samples_per_shard

    @property
    def shard_of_item(self) -> np.ndarray:
        """(len,) shard index of each item."""
        return self.indices // self.layout.samples_per_shard

    def params(self, i: int) -> dict[str, Any]:
        """Parameters of item ``i`` as a dict of Python scalars."""
        return {n: v[i].item() for n, v in self._params.items()}

    def _open_arrays(self) -> None:
        """Open the store in this process: zarr arrays plus raw readers where possible."""
        group = open_store(self.path, "r")
        self._arrays, self._raw = {}, {}
        if _in_dataloader_worker():
            # one decoding thread per worker process: the workers are the parallelism
            blosc.use_threads = False
        for n in set(self.inputs + self.targets):
            arr = group[n]
            self._arrays[n] = arr
            raw = raw_shard_layout(arr)
            if raw is not None and raw[0] == self.layout.samples_per_shard:
                self._raw[n] = RawShardReader(Path(self.path) / n, raw[0], raw[1], raw[2],
                                              fill_value_for(arr.dtype), raw[3])

    def _windows(self, globals_: np.ndarray) -> list[tuple[slice, slice]]:
        h, w = self.layout.shape
        if self.crop is None:
            return [(slice(0, h), slice(0, w))] * len(globals_)
        ch, cw = self.crop
        r0, c0 = crop_offsets(self.seed, self.epoch, globals_, h - ch + 1, w - cw + 1)
        return [(slice(r, r + ch), slice(c, c + cw)) for r, c in zip(r0.tolist(), c0.tolist())]

    def _read_numpy(self, positions: Sequence[int]) -> dict[str, list[np.ndarray]]:
        """Cropped arrays of items ``positions``: name -> list of (h, w) arrays, in order."""
        pos = np.asarray(positions, dtype=np.int64)
        if pos.ndim != 1:
            raise InputError("positions must be a 1-D sequence of item indices")
        n = len(self)
        if pos.size and (pos.min() < -n or pos.max() >= n):
            raise IndexError(f"item index out of range for a dataset of {n} items")
        globals_ = self.indices[pos]
        windows = self._windows(globals_)
        names = list(dict.fromkeys(self.inputs + self.targets))
        out = {name: [None] * len(pos) for name in names}
        s = self.layout.samples_per_shard
        shards = globals_ // s
        if self._arrays is None:
            self._open_arrays()
        for name in names:
            raw = self._raw.get(name)
            if raw is None:
                continue
            out[name] = raw.windows(globals_.tolist(), windows)  # crops of mapped shards
        zarr_names = [n for n in names if n not in self._raw]
        for shard in np.unique(shards).tolist() if zarr_names else []:
            members = np.nonzero(shards == shard)[0]
            wanted = np.unique(globals_[members])
            lo, hi = int(wanted[0]), int(wanted[-1]) + 1
            for name in zarr_names:
                arr = self._arrays[name]
                # One covering slice (at most one shard: S samples). zarr 3.1's orthogonal
                # (integer-list) selection is ~8x slower than the covering slice (measured).
                try:
                    block = arr[lo:hi]
                except Exception as exc:  # noqa: BLE001 - checksum mismatch, truncated file
                    raise StoreError(f"samples {lo}..{hi - 1} of array {name!r} in {self.path!r} "
                                     f"are unreadable ({read_error_text(exc)}); run `demseis validate "
                                     f"{self.path}`") from exc
                rows = wanted - lo
                lookup = dict(zip(wanted.tolist(), rows.tolist()))
                for m in members.tolist():
                    rs, cs = windows[m]
                    out[name][m] = block[lookup[int(globals_[m])], rs, cs]
        return out

    def _item(self, data: dict[str, list[np.ndarray]], m: int):
        torch = import_torch("the PyTorch Dataset")

        if len(self.inputs) == 1:  # no stacking copy for the usual single input
            x = data[self.inputs[0]][m][None].astype(np.float32, copy=False)
        else:
            x = np.stack([data[n][m] for n in self.inputs]).astype(np.float32, copy=False)
        ys = {}
        for n in self.targets:
            v = data[n][m]
            if self.layout.arrays[n].kind in "iu":
                v = v.astype(np.int64) if self.long_labels else v
            else:
                v = v.astype(np.float32, copy=False)
            ys[n] = torch.from_numpy(np.ascontiguousarray(v))
        y = ys[self.targets[0]] if len(self.targets) == 1 else ys
        xt = torch.from_numpy(np.ascontiguousarray(x))
        if self.transform is not None:
            xt, y = self.transform(xt, y)
        return xt, y

    def __getitem__(self, i: int):
        data = self._read_numpy([int(i)])
        return self._item(data, 0)

    def __getitems__(self, indices: Sequence[int]) -> list:
        """Items of a whole batch, reading each touched shard once per array."""
        data = self._read_numpy(indices)
        return [self._item(data, m) for m in range(len(indices))]


def _normalise_crop(crop: Any, shape: tuple[int, int]) -> tuple[int, int] | None:
    if crop is None:
        return None
    c = (int(crop), int(crop)) if np.isscalar(crop) else tuple(int(v) for v in crop)
    if len(c) != 2 or min(c) < 1:
        raise InputError(f"crop must be a positive int or (h, w), got {crop!r}")
    if c[0] > shape[0] or c[1] > shape[1]:
        raise InputError(f"crop {c} is larger than the samples {shape}")
    return c


class ShardAwareSampler:
    """Epoch order that reads shards, not scattered samples.

    Shards are visited in a random order; ``shards_per_block`` shards at a time have their
    items shuffled together. With ``DataLoader(ds, batch_size=B, sampler=...)`` a batch then
    spans at most ``shards_per_block + 1`` shards, each read with one Zarr call per array (see
    :meth:`FaultSegDataset.__getitems__`). ``shards_per_block`` trades batch diversity (runs per
    batch) for read speed.

    Parameters
    ----------
    dataset : a :class:`FaultSegDataset` (uses its ``shard_of_item``).
    shuffle : random shard order and item order within blocks; False gives store order.
    shards_per_block : shards mixed together (>= 1).
    seed : base seed; the order of epoch ``e`` comes from ``default_rng([seed, e])``.
    """

    def __init__(self, dataset: FaultSegDataset, *, shuffle: bool = True,
                 shards_per_block: int = 2, seed: int = 0) -> None:
        if int(shards_per_block) < 1:
            raise InputError(f"shards_per_block must be >= 1, got {shards_per_block!r}")
        self.shard_of_item = np.asarray(dataset.shard_of_item)
        self.shuffle = bool(shuffle)
        self.shards_per_block = int(shards_per_block)
        self.seed = int(seed)
        self.epoch = 0

    def set_epoch(self, epoch: int) -> None:
        """Use the order of ``epoch``."""
        self.epoch = int(epoch)

    def __len__(self) -> int:
        return int(self.shard_of_item.shape[0])

    def __iter__(self) -> Iterator[int]:
        return iter(self.order().tolist())

    def order(self) -> np.ndarray:
        """The item order of the current epoch (a permutation of ``range(len)``)."""
        items = np.arange(len(self))
        if not self.shuffle:
            return items
        rng = np.random.default_rng([self.seed, self.epoch])
        shards, inverse = np.unique(self.shard_of_item, return_inverse=True)
        rank = np.empty(shards.size, dtype=np.int64)
        rank[rng.permutation(shards.size)] = np.arange(shards.size)
        block = rank[inverse] // self.shards_per_block
        # sort by block, random order inside each block
        return np.lexsort((rng.random(items.size), block))
