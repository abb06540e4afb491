"""How demseis makes the Zarr nodes of a store: codec chains, and metadata files made by zarr.

zarr makes every byte of the metadata (``zarr.json`` of each group and array) in an in-memory
store (:func:`zarr_files`); :func:`put_files` writes them, each atomically. Through zarr's
``LocalStore``, its existence checks and thread hops took 0.1-0.2 s of a `quick` store's
creation, about half of it.
"""

from __future__ import annotations

import asyncio
from collections.abc import Callable, Iterable, Mapping
from pathlib import Path
from types import ModuleType
from typing import Any

from demseis.datasets._shardio import put_file
from demseis.schema import SampleArray


def zarr_lib() -> ModuleType:
    """The zarr package (its ``codecs``, ``storage`` and ``core.sync`` come with it), imported
    at the first call. The one place demseis imports zarr: it takes about 0.3 s, and ``import
    demseis.datasets``, a shard write without particles and the readers of the Dataset need
    none of it (they read chunk files directly)."""
    import zarr

    return zarr


def sample_compressors(spec: SampleArray) -> tuple:
    """Codecs after ``bytes`` of one chunk of a sample array: [Blosc-lz4,] crc32c.

    Network inputs are stored raw (``spec.compressed`` False) and read as zero-copy crops:
    band-limited float sections compress to only ~80-90 % with lz4/zstd, and decoding costs
    more than the read (measured: 0.47 ms vs 0.90 ms per 320x512 sample).
    """
    codecs = zarr_lib().codecs
    if not spec.compressed:
        return (codecs.Crc32cCodec(),)
    # lz4 decodes at GB/s; labels compress ~200-fold (measured 0.005 of raw for fault masks,
    # 0.02 ms decode per 320x512 sample; bit-shuffle was 5x slower to decode for no gain).
    shuffle = "shuffle" if spec.np_dtype.itemsize > 1 else "noshuffle"
    return (codecs.BloscCodec(cname="lz4", clevel=5, shuffle=shuffle), codecs.Crc32cCodec())


def flag_compressors() -> tuple:
    """Codecs of a done flag (one byte): crc32c only, so the flags are read without zarr."""
    return (zarr_lib().codecs.Crc32cCodec(),)


def small_compressors() -> tuple:
    """Codecs of the small arrays (parameters, flags, particles, coordinates): zstd, crc32c."""
    codecs = zarr_lib().codecs
    return (codecs.ZstdCodec(level=0, checksum=False), codecs.Crc32cCodec())


def zarr_files(build: Callable[[Any], None]) -> dict[str, bytes]:
    """The files (key -> bytes) zarr writes when ``build(store)`` creates groups and arrays in
    the zarr store ``store``, an in-memory one (written to disk by :func:`put_files`)."""
    MemoryStore = zarr_lib().storage.MemoryStore

    files: dict[str, Any] = {}
    build(MemoryStore(files))
    return {key: buf.to_bytes() for key, buf in files.items()}


def put_files(path: Path, files: Mapping[str, bytes]) -> None:
    """Write ``files`` (key -> bytes, keys relative to ``path``) each atomically, the top
    ``zarr.json`` first (what zarr writes first: a store whose creation is cut short is still
    recognised as a demseis store)."""
    for key in sorted(files, key=lambda k: (k != "zarr.json", k)):
        put_file(path.joinpath(*key.split("/")), files[key])


def create_arrays(store: Any, specs: Mapping[str, Mapping[str, Any]]) -> None:
    """Create the arrays ``path -> create_array keywords`` in the zarr store ``store``, all at
    once on zarr's event loop (one at a time, the ~90 metadata writes took 0.4 s of every
    store's creation)."""
    zarr = zarr_lib()
    zarr.core.sync.sync(_gather_all(zarr.api.asynchronous.create_array(store, name=name, zarr_format=3, **kw)
                     for name, kw in specs.items()))


async def _gather_all(coros: Iterable[Any]) -> None:
    """Await every coroutine concurrently; once all have ended, raise the first error (none is
    left running behind an early error)."""
    for r in await asyncio.gather(*coros, return_exceptions=True):
        if isinstance(r, BaseException):
            raise r

