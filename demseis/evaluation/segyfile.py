"""Read a 2-D SEG-Y section or the lines of a 3-D cube, and write another section or cube
with a SEG-Y file's headers.

Used by ``demseis predict`` (fault probability of a field or synthetic section, written with
the input's textual, binary and trace headers) and by ``demseis score`` (a ``.sgy``
prediction). A section is (samples, traces): one column per trace, rows down the trace, as
the store's ``seismic`` arrays and ``demseis export-segy`` lay them out.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import segyio

from demseis.errors import InputError

#: file name endings read as SEG-Y
SEGY_SUFFIXES = (".sgy", ".segy")


def is_segy(path: str | Path) -> bool:
    """True when ``path`` ends in ``.sgy`` or ``.segy`` (any case)."""
    return str(path).lower().endswith(SEGY_SUFFIXES)


def read_segy_section(path: str | Path) -> np.ndarray:
    """The traces of the SEG-Y file ``path`` as a (samples, traces) float32 section.

    Raises
    ------
    InputError
        The file is missing, not SEG-Y, or has no traces.
    """
    if not os.path.isfile(path):
        raise InputError(f"{str(path)!r} does not exist")
    try:
        with segyio.open(str(path), "r", ignore_geometry=True) as f:
            traces = np.asarray(f.trace.raw[:], dtype=np.float32)
    except (RuntimeError, OSError, ValueError) as exc:
        raise InputError(f"{str(path)!r}: cannot read as SEG-Y ({exc})") from None
    if traces.ndim != 2 or traces.size == 0:
        raise InputError(f"{str(path)!r}: no traces")
    return np.ascontiguousarray(traces.T)


def write_segy_like(section: np.ndarray, template: str | Path, out: str | Path) -> Path:
    """Write the (samples, traces) ``section`` to ``out`` with ``template``'s headers.

    The textual, binary and every trace header are copied; the sample format becomes IEEE
    float32 (format 5), so that values in [0, 1] survive whatever format the template has. The
    file is written under a temporary name and renamed.
    """
    out = Path(out)
    sec = np.ascontiguousarray(section, dtype=np.float32)
    tmp = out.with_name(f".{out.name}.tmp{os.getpid()}")
    try:
        with segyio.open(str(template), "r", ignore_geometry=True) as src:
            if (src.tracecount, len(src.samples)) != (sec.shape[1], sec.shape[0]):
                raise InputError(f"section of shape {sec.shape} does not fit {str(template)!r} "
                                 f"({len(src.samples)} samples x {src.tracecount} traces)")
            with _float_copy(src, tmp) as dst:
                dst.trace = np.ascontiguousarray(sec.T)  # a trace per row
        os.replace(tmp, out)
    finally:
        tmp.unlink(missing_ok=True)
    return out


def _float_copy(src: Any, path: Path) -> Any:
    """A new SEG-Y file at ``path`` with ``src``'s geometry and its textual, binary and trace
    headers, whose samples are IEEE float32 (format 5), open for writing its traces."""
    spec = segyio.tools.metadata(src)
    spec.format = 5
    dst = segyio.create(str(path), spec)
    try:
        dst.text[0] = src.text[0]
        dst.bin = src.bin
        dst.bin.update(format=5)
        for i in range(src.tracecount):
            dst.header[i] = src.header[i]
    except BaseException:
        dst.close()
        raise
    return dst


@dataclass(frozen=True)
class CubeGeometry:
    """The inline / crossline geometry of a 3-D SEG-Y cube (segyio's, from the trace headers'
    inline and crossline numbers at bytes 189 and 193)."""

    ilines: np.ndarray
    xlines: np.ndarray
    n_samples: int

    @property
    def shape(self) -> tuple[int, int, int]:
        """(inlines, crosslines, samples)."""
        return (len(self.ilines), len(self.xlines), self.n_samples)


def cube_geometry(path: str | Path) -> CubeGeometry | None:
    """The geometry of ``path`` if it is a regular 3-D cube (at least 2 inlines and 2
    crosslines, every inline and crossline pair present once); None for a 2-D line, or a file
    whose traces have no such geometry (read as one section, a trace per column)."""
    if not os.path.isfile(path):
        raise InputError(f"{str(path)!r} does not exist")
    try:
        with segyio.open(str(path), "r") as f:
            if f.unstructured or len(f.ilines) < 2 or len(f.xlines) < 2:
                return None
            return CubeGeometry(np.asarray(f.ilines), np.asarray(f.xlines), len(f.samples))
    except (RuntimeError, OSError, ValueError):  # no inline/crossline geometry
        return None


def open_cube(path: str | Path) -> Any:
    """The cube ``path`` opened for reading with its geometry (a segyio file; use ``with``)."""
    return segyio.open(str(path), "r")


def read_inline(f: Any, index: int) -> np.ndarray:
    """Inline ``index`` (its position, not its number) of an open cube as a (samples,
    crosslines) float32 section."""
    return np.ascontiguousarray(np.asarray(f.iline[f.ilines[index]], np.float32).T)


def read_crossline(f: Any, index: int) -> np.ndarray:
    """Crossline ``index`` of an open cube as a (samples, inlines) float32 section."""
    return np.ascontiguousarray(np.asarray(f.xline[f.xlines[index]], np.float32).T)


def read_cube_line(path: str | Path, kind: str, number: int) -> np.ndarray:
    """Inline or crossline ``number`` (its header number) of the cube ``path`` as a (samples,
    traces) float32 section; InputError naming the numbers the cube has."""
    if kind not in ("inline", "crossline"):
        raise InputError(f"kind must be 'inline' or 'crossline', got {kind!r}")
    with open_cube(path) as f:
        numbers = f.ilines if kind == "inline" else f.xlines
        where = np.flatnonzero(np.asarray(numbers) == number)
        if where.size == 0:
            raise InputError(f"{str(path)!r} has no {kind} {number}: its {kind}s are "
                             f"{numbers[0]}..{numbers[-1]} ({len(numbers)} of them)")
        read = read_inline if kind == "inline" else read_crossline
        return read(f, int(where[0]))


def write_segy_cube_like(cube: Any, template: str | Path, out: str | Path) -> Path:
    """Write ``cube`` (inlines, crosslines, samples: an array, or anything with that ``shape``
    whose ``cube[k]`` is inline k) to ``out`` with ``template``'s textual, binary and trace
    headers, as IEEE float32; one inline in memory at a time; under a temporary name, then
    renamed."""
    out = Path(out)
    tmp = out.with_name(f".{out.name}.tmp{os.getpid()}")
    try:
        with segyio.open(str(template), "r") as src:
            if tuple(cube.shape) != (len(src.ilines), len(src.xlines), len(src.samples)):
                raise InputError(f"cube of shape {tuple(cube.shape)} does not fit "
                                 f"{str(template)!r}")
            with _float_copy(src, tmp) as dst:
                for k, il in enumerate(src.ilines):
                    dst.iline[il] = np.ascontiguousarray(cube[k], dtype=np.float32)
        os.replace(tmp, out)
    finally:
        tmp.unlink(missing_ok=True)
    return out
