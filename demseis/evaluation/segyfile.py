"""Read a 2-D SEG-Y section, and write another section with a SEG-Y file's headers.

Used by ``demseis predict`` (fault probability of a field or synthetic section, written with
the input's textual, binary and trace headers) and by ``demseis score`` (a ``.sgy``
prediction). A section is (samples, traces): one column per trace, rows down the trace, as
the store's ``seismic`` arrays and ``demseis export-segy`` lay them out.
"""

from __future__ import annotations

import os
from pathlib import Path

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
            spec = segyio.tools.metadata(src)
            spec.format = 5
            with segyio.create(str(tmp), spec) as dst:
                dst.text[0] = src.text[0]
                dst.bin = src.bin
                dst.bin.update(format=5)
                for i in range(src.tracecount):
                    dst.header[i] = src.header[i]
                dst.trace = np.ascontiguousarray(sec.T)  # a trace per row
        os.replace(tmp, out)
    finally:
        tmp.unlink(missing_ok=True)
    return out
