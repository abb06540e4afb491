"""Direct crop reads from Zarr v3 shard files (the reading fast path), and the direct writer of
chunk and shard files (the writing fast path, at the end of this module).

A sharded array (codec chain ``sharding_indexed`` with inner codecs ``[bytes, crc32c]`` or
``[bytes, blosc, crc32c]``) stores each (1, H, W) chunk at a byte range of its shard file; the
shard index at the end of the file (Zarr v3 sharding spec: ``n_chunks`` pairs of little-endian
uint64 ``(offset, nbytes)``, then the crc32c of the index) says where. Memory-mapping the shard
file:

- every chunk is checked against its crc32c (the 4 bytes zarr's ``crc32c`` codec appends to
  the encoded chunk) on its first read after its shard file is mapped, so damaged data raises
  :class:`StoreError` naming the sample instead of being returned; while the file stays the
  same (same inode, size, modification and change times) it is not checked again (see
  :class:`RawShardReader`);
- uncompressed chunks are then viewed in place as (H, W) arrays, so a crop copies only its
  window, which is what a NumPy memmap of the data would do;
- Blosc chunks are decoded with numcodecs (the library zarr itself calls), then cropped.

The same checksums let :func:`check_chunk_file` and :func:`check_shard_file` verify a store's
files without decoding anything (``validate``, and the sweep before it skips a done shard).

This skips zarr-python's asyncio machinery, which costs ~0.5 ms per sample on small reads
(measured: 18 ms for a 32-sample uint8 slice whose Blosc decoding takes 0.7 ms). Arrays with
any other codec chain are read through zarr. The result is identical to zarr's (tested).
"""

from __future__ import annotations

import contextlib
import mmap
import os
import uuid
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, NamedTuple

import google_crc32c
import numpy as np
from numcodecs import Zstd, blosc

from demseis.errors import StoreError

_EMPTY = np.uint64(2**64 - 1)
CRC_NBYTES = 4
#: shard files a RawShardReader keeps mapped at once (the oldest is unmapped first)
MAX_OPEN_SHARDS = 64


def crc_ok(encoded: np.ndarray) -> bool:
    """True if ``encoded`` (uint8: payload then its little-endian crc32c) is intact."""
    if encoded.shape[0] < CRC_NBYTES:
        return False
    stored = int.from_bytes(bytes(encoded[-CRC_NBYTES:]), "little")
    return google_crc32c.value(encoded[:-CRC_NBYTES]) == stored


def _map_file(path: Path) -> tuple[np.ndarray, os.stat_result] | None:
    """The bytes of ``path`` as a read-only uint8 array (memory-mapped) and the ``fstat`` of
    the file that was mapped; None if missing."""
    try:
        fh = open(path, "rb")
    except FileNotFoundError:
        return None
    with fh:
        st = os.fstat(fh.fileno())
        if st.st_size == 0:
            return np.zeros(0, np.uint8), st
        mm = mmap.mmap(fh.fileno(), 0, access=mmap.ACCESS_READ)
        return np.frombuffer(mm, dtype=np.uint8), st


def _map(path: Path) -> np.ndarray | None:
    """The bytes of ``path`` as a read-only uint8 array (memory-mapped); None if missing."""
    got = _map_file(path)
    return None if got is None else got[0]


def file_identity(st: os.stat_result) -> tuple[int, int, int, int, int]:
    """What changes when a file is replaced or written: (device, inode, size, mtime, ctime).

    A rename over the file (how zarr writes) gives a new inode; an in-place write changes the
    modification and change times (to the file system's timestamp resolution).
    """
    return st.st_dev, st.st_ino, st.st_size, st.st_mtime_ns, st.st_ctime_ns


def check_chunk_file(path: str | Path) -> str | None:
    """Problem with one unsharded chunk file whose codecs end in ``crc32c``; None if intact.

    A missing file is not a problem here (zarr does not write chunks equal to the fill value);
    the caller decides whether the chunk had to exist.
    """
    data = _map(Path(path))
    if data is None:
        return None
    return None if crc_ok(data) else "crc32c mismatch"


def check_shard_file(path: str | Path, n_chunks: int) -> tuple[str | None, list[int], list[int]]:
    """Verify a shard file of ``n_chunks`` inner chunks whose inner codecs end in ``crc32c``.

    Returns
    -------
    (index_problem, damaged, empty)
        ``index_problem``: None, or why the shard index cannot be trusted (then every chunk is
        unreadable and ``damaged`` lists them all); ``damaged``: local indices of chunks whose
        checksum fails or whose byte range does not fit; ``empty``: local indices of chunks
        never written. A missing file gives ``("missing", [], all)``.
    """
    data = _map(Path(path))
    everything = list(range(n_chunks))
    if data is None:
        return "missing", [], everything
    index = _shard_index(data, n_chunks)
    if isinstance(index, str):
        return index, everything, []
    end = data.shape[0] - n_chunks * 16 - CRC_NBYTES
    damaged, empty = [], []
    for i, (off, nbytes) in enumerate(index.tolist()):
        if off == int(_EMPTY):
            empty.append(i)
        elif off + nbytes > end or not crc_ok(data[off: off + nbytes]):
            damaged.append(i)
    return None, damaged, empty


def _shard_index(data: np.ndarray, n_chunks: int) -> np.ndarray | str:
    """The (n_chunks, 2) ``(offset, nbytes)`` index at the end of shard file bytes ``data``, or
    why it cannot be trusted: ``"truncated"`` or ``"index crc32c mismatch"``."""
    index_nbytes = n_chunks * 16
    if data.shape[0] < index_nbytes + CRC_NBYTES:
        return "truncated"
    raw_index = data[-(index_nbytes + CRC_NBYTES):]
    if not crc_ok(raw_index):
        return "index crc32c mismatch"
    return np.frombuffer(bytes(raw_index[:-CRC_NBYTES]), dtype="<u8").reshape(n_chunks, 2)


def raw_shard_layout(array) -> tuple[int, tuple[int, int], np.dtype, str | None] | None:
    """(samples per shard, (H, W), dtype, "blosc" or None) if ``array`` can be read raw.

    Raw reading needs: 3-D array, chunks (1, H, W), one ``sharding_indexed`` codec whose inner
    codecs are little-endian ``bytes``, optionally ``blosc``, then ``crc32c``; index codecs
    ``bytes`` + ``crc32c``, index at the end, and the default ``/`` chunk key encoding.
    Returns None otherwise.
    """
    meta = array.metadata.to_dict()
    codecs = meta.get("codecs", ())
    if len(meta.get("shape", ())) != 3 or len(codecs) != 1:
        return None
    c = codecs[0]
    if c.get("name") != "sharding_indexed":
        return None
    conf = c.get("configuration", {})
    inner = [d.get("name") for d in conf.get("codecs", ())]
    index = [d.get("name") for d in conf.get("index_codecs", ())]
    endian = [d.get("configuration", {}).get("endian", "little") for d in conf.get("codecs", ())]
    cke = meta.get("chunk_key_encoding", {})
    chunk = tuple(conf.get("chunk_shape", ()))
    shape = tuple(meta["shape"])
    compressor = None
    if inner[-1:] != ["crc32c"]:
        return None
    inner, endian = inner[:-1], endian[:-1]
    if inner == ["bytes", "blosc"]:
        compressor, inner = "blosc", ["bytes"]
        endian = endian[:1]
    if (
        inner != ["bytes"]
        or endian != ["little"]
        or index != ["bytes", "crc32c"]
        or conf.get("index_location", "end") != "end"
        or cke.get("name") != "default"
        or cke.get("configuration", {}).get("separator", "/") != "/"
        or len(chunk) != 3
        or chunk[0] != 1
        or chunk[1:] != shape[1:]
    ):
        return None
    shards = meta["chunk_grid"]["configuration"]["chunk_shape"]
    dtype = np.dtype(array.dtype).newbyteorder("<")
    return int(shards[0]), (int(shape[1]), int(shape[2])), dtype, compressor


class _OpenShard(NamedTuple):
    data: np.ndarray        # the mapped file
    ranges: list            # per chunk: (start, end) byte range, None if never written
    identity: tuple         # file_identity of the mapped file
    verified: list[bool]    # per chunk: crc32c checked on this file (this identity)


class RawShardReader:
    """Crop windows out of the shards of one array, via a memory map of each shard file.

    Every chunk's crc32c is checked on its first read by this reader, and not again while its
    shard file stays the same: each call of :meth:`windows` compares each touched shard file's
    :func:`file_identity` (one ``stat``) with the mapped one's, and a file that was replaced or
    written since is mapped and verified afresh. The flags outlive the map: a shard unmapped
    for :data:`MAX_OPEN_SHARDS` and mapped again with the same identity is not checked again. The checksum pass reads the whole
    chunk from memory (55-75 us per 554 kB section from the page cache, measured on 2 shared
    cores: about what copying a 256x256 crop costs), which is what re-checking on every read
    cost. Damage that reaches a mapped file without going through the file system (a failing
    disk under an evicted page) is seen by the next process or reader, and by
    ``demseis validate``, not by this one.

    Parameters
    ----------
    array_dir : directory of the array inside the store (``STORE/seismic``).
    samples_per_shard : S.
    shape : (H, W).
    dtype : little-endian dtype of the values.
    fill_value : value of never-written chunks.
    compressor : None (raw values) or ``"blosc"``.
    """

    def __init__(self, array_dir: str | Path, samples_per_shard: int, shape: tuple[int, int],
                 dtype: np.dtype, fill_value, compressor: str | None = None) -> None:
        if compressor not in (None, "blosc"):
            raise ValueError(f"compressor must be None or 'blosc', got {compressor!r}")
        self.compressor = compressor
        self.array_dir = Path(array_dir)
        self.s = int(samples_per_shard)
        self.shape = shape
        self.dtype = np.dtype(dtype)
        self.fill_value = fill_value
        self._native = self.dtype.newbyteorder("=")
        self.chunk_nbytes = shape[0] * shape[1] * self.dtype.itemsize
        self._open: dict[int, _OpenShard] = {}
        # shard -> (file identity, checked flags): kept when the map is dropped for the bound,
        # so that a store of more than MAX_OPEN_SHARDS shards is not checked again each epoch
        self._checked: dict[int, tuple[tuple, list[bool]]] = {}

    def _path(self, shard: int) -> str:
        return os.path.join(self.array_dir, "c", str(shard), "0", "0")

    def _damaged(self, shard: int, what: str) -> StoreError:
        first, last = shard * self.s, (shard + 1) * self.s - 1
        return StoreError(f"samples {first}..{last} of array {self.array_dir.name!r} are damaged: "
                          f"shard file {self._path(shard)!r} {what}")

    def _shard(self, shard: int) -> _OpenShard:
        """The mapped shard file, re-mapped (and so re-verified) if the file changed."""
        path = self._path(shard)
        got = self._open.get(shard)
        if got is not None:
            try:
                if file_identity(os.stat(path)) == got.identity:
                    return got
            except FileNotFoundError:
                pass
            del self._open[shard]
        mapped = _map_file(Path(path))
        if mapped is None:
            raise self._damaged(shard, "is missing")
        mm, st = mapped
        index_nbytes = self.s * 16
        index = _shard_index(mm, self.s)
        if isinstance(index, str):
            raise self._damaged(shard, {"truncated": "is truncated"}.get(
                index, "has a corrupt index (crc32c mismatch)"))
        ok = index[:, 0] != _EMPTY
        if (self.compressor is None and (ok & (index[:, 1] != self.chunk_nbytes + CRC_NBYTES)).any()) or (
            ok & (index[:, 0] + index[:, 1] > mm.shape[0] - index_nbytes - CRC_NBYTES)
        ).any():
            raise self._damaged(shard, "has chunk ranges that do not fit")
        if len(self._open) >= MAX_OPEN_SHARDS:  # bound open maps per process
            self._open.pop(next(iter(self._open)))
        ranges = [None if o == int(_EMPTY) else (o, o + nb) for o, nb in index.tolist()]
        identity = file_identity(st)
        checked = self._checked.get(shard)
        verified = checked[1] if checked is not None and checked[0] == identity else [False] * self.s
        self._checked[shard] = (identity, verified)
        got = _OpenShard(mm, ranges, identity, verified)
        self._open[shard] = got
        return got

    def window(self, sample: int, rows: slice, cols: slice) -> np.ndarray:
        """Copy of ``array[sample, rows, cols]`` (a new C-contiguous array)."""
        return self.windows([sample], [(rows, cols)])[0]

    def windows(self, samples: Sequence[int],
                windows: Sequence[tuple[slice, slice]]) -> list[np.ndarray]:
        """Copies of ``array[samples[m], *windows[m]]``, each shard file looked up once."""
        shards: dict[int, _OpenShard] = {}
        out = []
        for sample, (rows, cols) in zip(samples, windows):
            shard, local = divmod(int(sample), self.s)
            sh = shards.get(shard)
            if sh is None:
                sh = shards[shard] = self._shard(shard)
            byte_range = sh.ranges[local]
            if byte_range is None:  # never written: the fill value
                h = len(range(*rows.indices(self.shape[0])))
                w = len(range(*cols.indices(self.shape[1])))
                out.append(np.full((h, w), self.fill_value, dtype=self._native))
                continue
            start, end = byte_range
            if not sh.verified[local]:
                if not crc_ok(sh.data[start:end]):
                    raise StoreError(f"sample {int(sample)} of array {self.array_dir.name!r} is "
                                     f"damaged (crc32c mismatch in shard file "
                                     f"{self._path(shard)!r})")
                sh.verified[local] = True
            if self.compressor == "blosc":
                raw = blosc.decompress(sh.data[start:end - CRC_NBYTES])
                if len(raw) != self.chunk_nbytes:
                    raise StoreError(f"chunk {int(sample)} of {str(self.array_dir)!r} decodes to "
                                     f"{len(raw)} bytes, expected {self.chunk_nbytes}")
                view = np.frombuffer(raw, dtype=self.dtype).reshape(self.shape)
            else:
                view = np.ndarray(self.shape, dtype=self.dtype, buffer=sh.data, offset=start)
            out.append(np.array(view[rows, cols], dtype=self._native, order="C"))
        return out


# --------------------------------------------------------------------------------------------
# writing: the encoder of the files parsed above
#
# ``write_shard`` writes ~90 files per shard. Through zarr's asyncio machinery that took ~0.15 s
# of a kinematic run's ~0.25 s (one event-loop round trip and thread hop per array and codec);
# encoded here with the same numcodecs / google_crc32c calls zarr makes and written with plain
# file operations it takes a few ms. The bytes are zarr's (tested file by file against zarr).

#: zarr's temporary file names: ``<file>.<uuid4 hex>.partial`` (``LocalStore``); this writer
#: uses the same names, so one clean-up (``remove_partial_writes``) removes both.
PARTIAL_SUFFIX = ".partial"


@dataclass(frozen=True)
class ArrayMeta:
    """What the direct writer needs of one array's ``zarr.json`` (Zarr format 3).

    Attributes
    ----------
    path : the array's path inside the store, e.g. ``"params/dip_deg"``.
    shape : array shape.
    dtype : native-order value dtype.
    chunks : shape of one chunk (of one inner chunk when sharded), like ``zarr.Array.chunks``.
    shards : shape of one shard file, or None when not sharded (``zarr.Array.shards``).
    fill_value : the fill value (a chunk equal to it is not written, as zarr does).
    encoder : codecs of one (inner) chunk.
    key_separator : separator of the chunk key (``c/0/0/0``).
    categories : the names of the codes of a categorical parameter (its ``categories``
        attribute), else None.
    attributes : the array's attributes (units, long_name, and for a sample array its role,
        fill and valid range: :meth:`demseis.schema.SampleArray.store_attributes`).
    """

    path: str
    shape: tuple[int, ...]
    dtype: np.dtype
    chunks: tuple[int, ...]
    shards: tuple[int, ...] | None
    fill_value: Any
    encoder: ChunkEncoder
    key_separator: str = "/"
    categories: tuple[str, ...] | None = None
    attributes: Mapping[str, Any] = field(default_factory=dict)

    def chunk_key(self, coords: Sequence[int]) -> str:
        """Key (path below the array) of the chunk or shard file at grid position ``coords``."""
        sep = self.key_separator
        return "c" + "".join(sep + str(int(c)) for c in coords) if coords else "c"

    def block_file(self, store: str | Path, index: int) -> Path:
        """The chunk (or shard) file number ``index`` along the first axis, in the store at
        ``store`` (every demseis array has one chunk across its other axes)."""
        coords = (int(index),) + (0,) * (len(self.shape) - 1)
        return Path(store, *self.path.split("/"), *self.chunk_key(coords).split("/"))


@dataclass(frozen=True)
class ChunkEncoder:
    """The codec chain of one chunk: ``bytes`` (with its byte order), then bytes-to-bytes
    codecs (``blosc``, ``zstd``, ``crc32c``) in order."""

    dtype: np.dtype                                   # on-disk dtype, with its byte order
    steps: tuple[Callable[[bytes], bytes], ...] = ()  # bytes -> bytes codecs, in order
    names: tuple[str, ...] = ()                       # their names (blosc, zstd, crc32c)

    def encode(self, chunk: np.ndarray) -> bytes:
        """Encoded bytes of ``chunk`` (C order, as zarr's ``bytes`` codec flattens it)."""
        data = np.ascontiguousarray(chunk, dtype=self.dtype).tobytes()
        for step in self.steps:
            data = step(data)
        return data

    def decode(self, data: bytes | np.ndarray, shape: Sequence[int]) -> np.ndarray:
        """The chunk of ``shape`` encoded as ``data`` (the inverse of :meth:`encode`), its
        crc32c checked; ``ValueError`` saying what is wrong (``crc32c mismatch``, a size that
        does not fit) for damaged bytes."""
        buf = np.frombuffer(data, dtype=np.uint8)
        for name in reversed(self.names):
            if name == "crc32c":
                if not crc_ok(buf):
                    raise ValueError("crc32c mismatch")
                buf = buf[:-CRC_NBYTES]
            elif name == "zstd":
                buf = np.frombuffer(Zstd().decode(bytes(buf)), dtype=np.uint8)
            else:  # blosc
                buf = np.frombuffer(blosc.decompress(bytes(buf)), dtype=np.uint8)
        n = int(np.prod(shape)) * self.dtype.itemsize
        if buf.shape[0] != n:
            raise ValueError(f"decodes to {buf.shape[0]} bytes, expected {n}")
        return buf.view(self.dtype).reshape(tuple(shape)).astype(self.dtype.newbyteorder("="))


def _append_crc32c(data: bytes) -> bytes:
    """zarr's ``crc32c`` codec: the payload then its crc32c, little-endian uint32."""
    return data + int(google_crc32c.value(data)).to_bytes(CRC_NBYTES, "little")


def _blosc_step(conf: Mapping[str, Any]) -> Callable[[bytes], bytes]:
    """zarr's ``blosc`` codec: numcodecs ``Blosc`` with the stored configuration."""
    # zarr turns Blosc's threads off when it is imported (zarr.codecs.blosc): with threads,
    # Blosc may store the compressed blocks in another order (measured: other bytes for a
    # 4 MB float32 buffer), so compress single-threaded as zarr does
    blosc.use_threads = False
    shuffle = {"noshuffle": 0, "shuffle": 1, "bitshuffle": 2}[conf["shuffle"]]
    codec = blosc.Blosc(cname=conf["cname"], clevel=int(conf["clevel"]), shuffle=shuffle,
                        blocksize=int(conf.get("blocksize", 0)), typesize=int(conf["typesize"]))
    return codec.encode


def _zstd_step(conf: Mapping[str, Any]) -> Callable[[bytes], bytes]:
    """zarr's ``zstd`` codec: numcodecs ``Zstd`` with the stored configuration."""
    return Zstd(level=int(conf.get("level", 0)), checksum=bool(conf.get("checksum", False))).encode


def chunk_encoder(codecs: Sequence[Mapping[str, Any]], dtype: np.dtype, where: str) -> ChunkEncoder:
    """The :class:`ChunkEncoder` of a Zarr v3 codec list (``bytes`` then ``blosc`` / ``zstd``
    / ``crc32c``); :class:`StoreError` naming ``where`` for any other codec."""
    names = [c.get("name") for c in codecs]
    if not names or names[0] != "bytes":
        raise StoreError(f"{where}: codecs {names} do not start with 'bytes'; the direct writer "
                         "needs that")
    endian = (codecs[0].get("configuration") or {}).get("endian", "little")
    disk = np.dtype(dtype).newbyteorder({"little": "<", "big": ">"}[endian])
    steps = []
    step_names = []
    for c in codecs[1:]:
        step_names.append(str(c.get("name")))
        conf = c.get("configuration") or {}
        if c.get("name") == "crc32c":
            steps.append(_append_crc32c)
        elif c.get("name") == "blosc":
            steps.append(_blosc_step(conf))
        elif c.get("name") == "zstd":
            steps.append(_zstd_step(conf))
        else:
            raise StoreError(f"{where}: codec {c.get('name')!r} is not one the direct writer "
                             "encodes (blosc, zstd, crc32c)")
    return ChunkEncoder(disk, tuple(steps), tuple(step_names))


_FLOAT_FILLS = {"NaN": float("nan"), "Infinity": float("inf"), "-Infinity": float("-inf")}


def _fill_value(value: Any, dtype: np.dtype) -> Any:
    """A ``fill_value`` of ``zarr.json`` as a NumPy scalar of ``dtype``."""
    if isinstance(value, str):
        if value in _FLOAT_FILLS:
            return dtype.type(_FLOAT_FILLS[value])
        if value.startswith("0x"):  # the bit pattern, big-endian hex
            return np.frombuffer(bytes.fromhex(value[2:]), dtype=dtype.newbyteorder(">"))[0]
    return dtype.type(value)


def array_meta(store: str | Path, name: str, meta: Mapping[str, Any]) -> ArrayMeta:
    """:class:`ArrayMeta` of array ``name`` of ``store`` from its parsed ``zarr.json``.

    Supported: a regular chunk grid, the default chunk key encoding, and either the codecs of
    :func:`chunk_encoder` or one ``sharding_indexed`` codec (index at the end, index codecs
    ``bytes`` little-endian + ``crc32c``, inner chunks splitting the shard along the first
    axis only) around them; :class:`StoreError` otherwise.
    """
    where = f"array {name!r} of {str(store)!r}"
    try:
        dtype = np.dtype(meta["data_type"])
        shape = tuple(int(v) for v in meta["shape"])
        grid = meta["chunk_grid"]
        outer = tuple(int(v) for v in grid["configuration"]["chunk_shape"])
        cke = meta.get("chunk_key_encoding", {})
        codecs = list(meta["codecs"])
        fill = _fill_value(meta["fill_value"], dtype)
        attrs = dict(meta.get("attributes") or {})
        cats = attrs.get("categories")
        cats = None if cats is None else tuple(str(c) for c in cats)
    except (KeyError, TypeError, ValueError) as exc:
        raise StoreError(f"{where}: unreadable metadata ({exc!r})") from None
    if grid.get("name") != "regular" or cke.get("name") != "default":
        raise StoreError(f"{where}: chunk grid {grid.get('name')!r} / key encoding "
                         f"{cke.get('name')!r}; the direct writer needs 'regular' / 'default'")
    sep = (cke.get("configuration") or {}).get("separator", "/")
    if len(codecs) == 1 and codecs[0].get("name") == "sharding_indexed":
        conf = codecs[0].get("configuration") or {}
        inner = tuple(int(v) for v in conf.get("chunk_shape", ()))
        index_codecs = [(c.get("name"), (c.get("configuration") or {}).get("endian", "little"))
                        for c in conf.get("index_codecs", ())]
        if (conf.get("index_location", "end") != "end"
                or index_codecs != [("bytes", "little"), ("crc32c", "little")]
                or len(inner) != len(outer) or inner[1:] != outer[1:]
                or inner[0] < 1 or outer[0] % inner[0]):
            raise StoreError(f"{where}: a shard layout the direct writer does not encode "
                             f"({conf})")
        encoder = chunk_encoder(conf.get("codecs", ()), dtype, where)
        return ArrayMeta(name, shape, dtype, inner, outer, fill, encoder, sep, cats, attrs)
    return ArrayMeta(name, shape, dtype, outer, None, fill, chunk_encoder(codecs, dtype, where),
                     sep, cats, attrs)


def is_fill(chunk: np.ndarray, fill_value: Any) -> bool:
    """True if every value of ``chunk`` is the fill value, as zarr decides it (NaN equals NaN;
    a float fill of zero compares bit patterns, so -0.0 is not the fill 0.0)."""
    flat = chunk.reshape(-1)
    fill = np.asarray(fill_value, dtype=chunk.dtype)
    if chunk.dtype.kind == "f" and fill == 0:
        bits = f"u{chunk.dtype.itemsize}"
        flat, fill = flat.view(bits), fill.view(bits)
    elif chunk.dtype.kind == "f" and np.isnan(fill):
        # the first value decides almost every chunk (data rarely starts with the fill value)
        return bool(np.isnan(flat[:1]).all() and np.isnan(flat).all())
    return bool((flat[:1] == fill).all() and (flat == fill).all())


def encode_block(meta: ArrayMeta, block: np.ndarray, *, write_empty: bool = False) -> bytes | None:
    """Bytes of one chunk file (``meta.shards`` None) or one shard file of ``meta``, as zarr
    writes it; None where zarr writes no file (every value is the fill value, and not
    ``write_empty``).

    ``block`` has the chunk's (or shard's) full shape. A shard file holds its inner chunks in
    order along the first axis (zarr's Morton order, for a grid that varies along one axis
    only), those equal to the fill value left out (index entry ``(2**64-1, 2**64-1)``), then
    the index of ``(offset, nbytes)`` little-endian uint64 pairs and its crc32c.
    """
    if meta.shards is None:
        if block.shape != meta.chunks:
            raise ValueError(f"{meta.path}: block of shape {block.shape}, chunk {meta.chunks}")
        if not write_empty and is_fill(block, meta.fill_value):
            return None
        return meta.encoder.encode(block)
    if block.shape != meta.shards:
        raise ValueError(f"{meta.path}: block of shape {block.shape}, shard {meta.shards}")
    step = meta.chunks[0]
    n = meta.shards[0] // step
    index = np.full((n, 2), _EMPTY, dtype="<u8")
    parts: list[bytes] = []
    offset = 0
    for i in range(n):
        chunk = block[i * step:(i + 1) * step]
        if not write_empty and is_fill(chunk, meta.fill_value):
            continue
        data = meta.encoder.encode(chunk)
        index[i] = (offset, len(data))
        offset += len(data)
        parts.append(data)
    if not parts:
        return None
    parts.append(_append_crc32c(index.tobytes()))
    return b"".join(parts)


def temporary_name(path: Path) -> Path:
    """``<path>.<uuid4 hex>.partial``: the temporary file of an atomic write of ``path``, named
    as zarr's ``LocalStore`` names its own."""
    return path.with_name(f"{path.name}.{uuid.uuid4().hex}{PARTIAL_SUFFIX}")


def put_file(path: Path, data: bytes | None) -> None:
    """Write ``data`` to ``path`` atomically (a temporary file in the same directory, then
    ``os.replace``), creating missing directories; ``None`` deletes ``path`` (if present).

    Readers see the old file, the new one or none, never a torn one. A process killed between
    the write and the rename leaves the temporary file (see :func:`temporary_name`); any other
    error removes it and propagates (an ``OSError`` of the temporary file names ``path``).
    """
    if data is None:
        path.unlink(missing_ok=True)
        return
    tmp = temporary_name(path)
    try:
        try:
            fh = open(tmp, "wb")
        except FileNotFoundError:
            path.parent.mkdir(parents=True, exist_ok=True)
            fh = open(tmp, "wb")
        with fh:
            fh.write(data)
        os.replace(tmp, path)
    except BaseException as exc:
        with contextlib.suppress(OSError):  # e.g. no such directory: then no such file
            tmp.unlink()
        if isinstance(exc, OSError) and exc.filename in (tmp, str(tmp)):  # name the file meant
            raise OSError(exc.errno, exc.strerror, str(path)) from exc
        raise


def write_block(store: str | Path, meta: ArrayMeta, index: int, block: np.ndarray, *,
                write_empty: bool = False) -> None:
    """Write ``block`` as chunk (or shard) number ``index`` along the first axis of the array
    ``meta`` of ``store``: the file zarr would write for ``array[index * n:(index + 1) * n] =
    block`` (``n`` the chunk's or shard's length), atomically; deleted where zarr writes none.

    The grid must have one chunk (shard) across every other axis, as every demseis array has.
    """
    outer = meta.shards or meta.chunks
    if any(c < s for c, s in zip(outer[1:], meta.shape[1:])):
        raise ValueError(f"{meta.path}: more than one chunk across the non-leading axes")
    put_file(meta.block_file(store, index), encode_block(meta, block, write_empty=write_empty))
