"""Reads of a store's sample arrays whose failures name the sample and the array.

zarr raises its own exceptions for a damaged chunk (a ``ValueError`` of the crc32c codec, a
short read of a truncated shard file) and silently returns fill values where a done shard's
file was deleted. :class:`CheckedArray` turns both into one :class:`StoreError` naming the
sample and the array, which the CLI prints as one line (exit 2).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from demseis.errors import StoreError


class CheckedArray:
    """An (N, H, W) zarr array of a store whose reads raise :class:`StoreError` naming the
    damaged sample and the array (a chunk failing its crc32c, a truncated or missing shard
    file) instead of zarr's own exception; what every read-only command reads through."""

    def __init__(self, array: Any, path: str | Path, name: str) -> None:
        self._array = array
        self.path = str(path)
        self.name = name
        self.shape = tuple(int(v) for v in array.shape)
        self.ndim = len(self.shape)
        self.dtype = array.dtype

    def _damaged(self, samples: Any, exc: BaseException) -> StoreError:
        """The error naming the first damaged sample of ``samples`` (an index, a slice or an
        index array of the first axis), each read alone to find it."""
        rows = _rows(samples, self.shape[0])
        cause = exc
        for i in np.atleast_1d(rows).tolist():
            try:
                self._array[int(i)]
            except Exception as one:  # noqa: BLE001 - this sample is the damaged one
                return StoreError(f"sample {int(i)} of array {self.name!r} in {self.path!r} is "
                                  f"damaged ({read_error_text(one)}); run `demseis validate "
                                  f"{self.path}`")
        return StoreError(f"array {self.name!r} in {self.path!r} is unreadable "
                          f"({read_error_text(cause)}); run `demseis validate {self.path}`")

    def _check_files(self, samples: Any) -> None:
        """A sample whose shard file is missing reads as fill values through zarr: name it.

        Only the samples of done shards are read by the commands, so a missing shard file
        there is damage (a deleted file), not a pending shard."""
        shards = getattr(self._array, "shards", None)
        if not shards:
            return
        rows = _rows(samples, self.shape[0])
        base = Path(self.path, *self.name.split("/"), "c")
        for k in np.unique(rows // int(shards[0])).tolist():
            f = base.joinpath(str(k), *("0",) * (self.ndim - 1))
            if not f.is_file():
                i = int(rows[rows // int(shards[0]) == k][0])
                raise StoreError(f"sample {i} of array {self.name!r} in {self.path!r} is "
                                 f"missing (its shard file {str(f)!r} is gone); run `demseis "
                                 f"validate {self.path}`")

    def __getitem__(self, key: Any) -> np.ndarray:
        first = key[0] if isinstance(key, tuple) else key
        self._check_files(first)
        try:
            return np.asarray(self._array[key])
        except Exception as exc:  # noqa: BLE001 - zarr's checksum ValueError, a short file
            raise self._damaged(first, exc) from None

    def get_orthogonal_selection(self, selection: tuple) -> np.ndarray:
        """zarr's orthogonal selection, its errors naming the damaged sample."""
        self._check_files(selection[0])
        try:
            return np.asarray(self._array.get_orthogonal_selection(selection))
        except Exception as exc:  # noqa: BLE001
            raise self._damaged(selection[0], exc) from None


def _rows(samples: Any, n: int) -> np.ndarray:
    """The sample indices (along the first axis of length ``n``) that ``samples`` selects: an
    index, a slice, an index or boolean array; without building an ``arange(n)``."""
    if isinstance(samples, (int, np.integer)):
        return np.array([int(samples) % n])
    if isinstance(samples, slice):
        return np.arange(*samples.indices(n))
    arr = np.asarray(samples)
    return np.flatnonzero(arr) if arr.dtype == bool else arr.astype(np.int64).reshape(-1) % n


def read_error_text(exc: BaseException) -> str:
    """A failed chunk read as one short line: a checksum mismatch in words (zarr's message
    shows the two checksums' raw bytes), anything else as its message on one line."""
    text = " ".join(str(exc).split()) or type(exc).__name__
    if "checksum do not match" in text:
        return "crc32c checksum mismatch: its bytes on disk changed since they were written"
    return text if len(text) <= 200 else text[:197] + "..."
