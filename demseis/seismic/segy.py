"""Write a 2-D section as SEG-Y (used by ``demseis export-segy`` through
:func:`demseis.datasets.read.export_segy`, which reads the store).

Layout of the file: one trace per grid column (trace j at x = x0 + (j + 0.5) cell), samples
down the rows, IEEE float32 (format 5), SEG-Y rev 1 headers written by segyio.

Depth sections (the default store content) follow the usual convention for depth SEG-Y: the
sample-interval fields (binary header ``Interval``, trace header ``TRACE_SAMPLE_INTERVAL``)
hold the depth step in millimetres (cell_m * 1000), so readers that assume microseconds show
"milliseconds" that are metres (segyio's ``f.samples`` are then depths in m below the grid top,
starting at the first cell centre, cell_m / 2). Time sections (store attr ``grid.domain ==
"time"`` with ``grid.dt_s``) store the true interval in microseconds. The textual header says
which. Coordinates: ``CDP_X``/``SourceX``/``GroupX`` hold the column x in metres with
``SourceGroupScalar = -100`` (centimetre precision), ``CDP_Y``/``SourceY``/``GroupY`` are 0,
``CDP`` and ``CROSSLINE_3D`` are the 1-based column, ``INLINE_3D`` is 1, and
``ReceiverGroupElevation`` is the grid-top elevation (m, scalar ``ElevationScalar = -100``).
"""

from __future__ import annotations

import os
import textwrap
from pathlib import Path

import numpy as np
import segyio

from demseis.errors import InputError


def write_segy(section: np.ndarray, out: str | Path, *, x0_m: float, cell_m: float,
               top_m: float, domain: str = "depth", dt_s: float | None = None,
               overwrite: bool = False, note: str = "",
               trace_spacing_m: float | None = None) -> Path:
    """Write a (ns, nx) float32 section to ``out`` (see the module docstring for the headers).

    ``trace_spacing_m``: the distance between traces where it is not the cell (a store
    sampled like a survey).

    The file is written next to ``out`` under a temporary name and renamed, so an existing file
    is never left half-written; it is replaced only with ``overwrite=True``.
    """
    out = Path(out)
    sec = np.ascontiguousarray(section, dtype=np.float32)
    if sec.ndim != 2:
        raise InputError(f"section must be 2-D (samples, traces), got shape {sec.shape}")
    if out.exists() and not overwrite:
        raise InputError(f"--out {str(out)!r} exists; pass --overwrite to replace it")
    if not out.parent.exists():
        raise InputError(f"--out directory {str(out.parent)!r} does not exist")
    ns, nx = sec.shape
    if domain == "time":
        if dt_s is None or not dt_s > 0:
            raise InputError(f"a time-domain section needs dt_s > 0, got {dt_s!r}")
        interval = int(round(dt_s * 1e6))
        first = 0
        text_domain = f"TIME DOMAIN. SAMPLE INTERVAL {dt_s * 1e3:g} MS (FIELD IN MICROSECONDS)"
    else:
        interval = int(round(cell_m * 1000.0))
        first = int(round(0.5 * cell_m))
        text_domain = (f"DEPTH DOMAIN. SAMPLE INTERVAL {cell_m:g} M STORED AS MM IN THE "
                       "MICROSECOND FIELD")
    if not 0 < interval < 65536:
        raise InputError(f"sample interval {interval} does not fit the 16-bit SEG-Y field")
    spec = segyio.spec()
    spec.format = 5
    spec.samples = list(range(ns))
    spec.tracecount = nx
    dx = cell_m if trace_spacing_m is None else float(trace_spacing_m)
    xs = x0_m + (np.arange(nx) + 0.5) * dx
    traces = np.ascontiguousarray(sec.T)
    tmp = out.with_name(out.name + ".tmp")
    lines = [
        "DEMSEIS SYNTHETIC SECTION (1-D CONVOLUTIONAL MODEL, ZERO-PHASE RICKER)",
        text_domain,
        (f"TRACES = GRID COLUMNS, X0 {x0_m:g} M, CELL {cell_m:g} M, GRID TOP ELEVATION {top_m:g} M"
         if trace_spacing_m is None else
         f"TRACES {dx:g} M APART, X0 {x0_m:g} M, CELL {cell_m:g} M, TOP ELEVATION {top_m:g} M"),
        "X IN CDP_X/SOURCEX/GROUPX (SCALAR -100)",
        "CDP = CROSSLINE = COLUMN + 1, INLINE = 1",
        note.upper()[:76],
    ]
    # a card is "C" + 2-digit number + space + 76 characters: longer lines would overflow
    lines = [part for line in lines for part in (textwrap.wrap(line, 76) or [""])]
    try:
        with segyio.create(str(tmp), spec) as f:
            f.text[0] = segyio.tools.create_text_header(
                {i + 1: line for i, line in enumerate(lines) if line})
            f.bin.update({segyio.BinField.Interval: interval, segyio.BinField.Samples: ns,
                          segyio.BinField.Format: 5, segyio.BinField.MeasurementSystem: 1})
            for j in range(nx):
                xcm = int(round(xs[j] * 100.0))
                f.header[j] = {
                    segyio.TraceField.TRACE_SEQUENCE_LINE: j + 1,
                    segyio.TraceField.TRACE_SEQUENCE_FILE: j + 1,
                    segyio.TraceField.FieldRecord: 1,
                    segyio.TraceField.TraceNumber: j + 1,
                    segyio.TraceField.CDP: j + 1,
                    segyio.TraceField.INLINE_3D: 1,
                    segyio.TraceField.CROSSLINE_3D: j + 1,
                    segyio.TraceField.SourceGroupScalar: -100,
                    segyio.TraceField.ElevationScalar: -100,
                    segyio.TraceField.CDP_X: xcm,
                    segyio.TraceField.CDP_Y: 0,
                    segyio.TraceField.SourceX: xcm,
                    segyio.TraceField.GroupX: xcm,
                    segyio.TraceField.ReceiverGroupElevation: int(round(top_m * 100.0)),
                    segyio.TraceField.TRACE_SAMPLE_COUNT: ns,
                    segyio.TraceField.TRACE_SAMPLE_INTERVAL: interval,
                    segyio.TraceField.DelayRecordingTime: first,
                    segyio.TraceField.CoordinateUnits: 1,
                }
                f.trace[j] = traces[j]
        os.replace(tmp, out)
    finally:
        if tmp.exists():
            tmp.unlink()
    return out

