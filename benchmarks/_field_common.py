"""What the field-transfer benchmarks share: reading labelled field sections, resampling,
scoring sections of different shapes, and the accumulated results file.

Used by ``benchmarks/field_benchmark.py`` and ``benchmarks/cross_domain.py`` (both put
``benchmarks/`` on ``sys.path``). The files are read by ``demseis.evaluation.fieldio``; what
the benchmarks add (a display image as an amplitude, a section drawn at another size than its
mask, thinned masks) is here, in one place.

Field files are read from wherever the user keeps them (a cache outside the repository):
nothing here copies them.
"""

from __future__ import annotations

import json
import os
from pathlib import Path

import numpy as np

# ----------------------------------------------------------------------------------- readers

def _check_file(path: str | Path, what: str) -> Path:
    from demseis.errors import InputError
    from demseis.evaluation.fieldio import MASK_SUFFIXES

    p = Path(path)
    if not p.is_file():
        raise InputError(f"{what}: {str(p)!r} is not a file")
    if p.suffix.lower() not in MASK_SUFFIXES:
        raise InputError(f"{what}: {str(p)!r}: expected a .png, .npy, .sgy or .segy file")
    return p


def _read(reader, path: str | Path, what: str):
    """``reader(path)`` with ``what`` (the option) at the head of its InputError."""
    from demseis.errors import InputError

    p = _check_file(path, what)
    try:
        return reader(p)
    except InputError as exc:
        if p.suffix.lower() in (".sgy", ".segy"):
            raise InputError(f"{what}: {str(p)!r} is not a readable SEG-Y file: {exc}") from None
        raise InputError(f"{what}: {exc}") from None


def read_section(path: str | Path, what: str = "--field") -> np.ndarray:
    """A (samples, traces) float32 section (:func:`demseis.evaluation.fieldio.read_section`:
    SEG-Y, ``.npy`` or a display PNG).

    A display image becomes an amplitude: its luminance minus the image's median (the
    background of a grey-scale seismic rendering, which is zero amplitude), scaled to unit
    RMS. The colour map is assumed monotonic in luminance: a red-white-blue rendering does not
    read this way.
    """
    from demseis.evaluation.fieldio import read_section as read

    sec = _read(read, path, what)
    if Path(path).suffix.lower() != ".png":
        return sec
    grey = sec.astype(np.float64) - np.median(sec)
    rms = float(np.sqrt(np.mean(grey ** 2)))
    return (grey / max(rms, 1e-12)).astype(np.float32)


def read_mask(path: str | Path, what: str = "--field") -> np.ndarray:
    """A (samples, traces) bool fault mask (:func:`demseis.evaluation.fieldio.read_mask`:
    ``.npy`` or SEG-Y nonzero, a PNG's pixels that differ from its background)."""
    from demseis.evaluation.fieldio import read_mask as read

    return _read(read, path, what)


def thin(mask: np.ndarray) -> np.ndarray:
    """Hand-drawn lines (several pixels wide) thinned to one pixel.

    scikit-image's ``skeletonize`` when it is installed (the ``dev`` extra); else the centre of
    every horizontal run of mask pixels, which is a one-pixel line for the steep faults of
    seismic sections (each row of a steep line is one short run) but leaves a near-horizontal
    line as wide as it is long.
    """
    m = np.asarray(mask, bool)
    try:
        from skimage.morphology import skeletonize
    except ImportError:
        out = np.zeros_like(m)
        d = np.diff(np.pad(m.astype(np.int8), ((0, 0), (1, 1))), axis=1)
        for r, c0 in zip(*np.nonzero(d == 1)):
            c1 = int(np.flatnonzero(d[r, c0:] == -1)[0]) + c0
            out[r, (c0 + c1 - 1) // 2] = True
        return out
    return skeletonize(m)


def resize(a: np.ndarray, shape: tuple[int, int]) -> np.ndarray:
    """``a`` resampled bilinearly to ``shape``
    (:func:`demseis.evaluation.fieldio.resize_sections`), smoothed first when shrinking so that
    it does not alias."""
    from scipy import ndimage

    from demseis.evaluation.fieldio import resize_sections

    a = np.asarray(a, np.float32)
    f = [s / n for s, n in zip(shape, a.shape)]
    if min(f) < 1:
        a = ndimage.gaussian_filter(a, [max(0.0, (1 / x - 1) / 2) for x in f])
    return resize_sections(a[None], shape)[0]


def read_pair(section: str | Path, mask: str | Path, *, thin_lines: bool,
              what: str = "--field") -> tuple[np.ndarray, np.ndarray]:
    """(section, mask) of one labelled field section, the section on the mask's grid.

    A section of another shape than its mask (a display image drawn at another size, as in
    the tutorial-03 set, whose seismic PNGs are 1.171 times their masks) must cover the same
    extent: it is resampled onto the mask's grid. ``thin_lines``: thin the mask to one-pixel
    lines (:func:`thin`).
    """
    from demseis.errors import InputError

    sec, m = read_section(section, what), read_mask(mask, what)
    if sec.shape != m.shape:
        ratio = [a / b for a, b in zip(sec.shape, m.shape)]
        if Path(section).suffix.lower() != ".png" or abs(ratio[0] / ratio[1] - 1) > 0.02:
            raise InputError(f"{what}: mask {str(mask)!r} has shape {m.shape}, the section "
                             f"{str(section)!r} has (samples, traces) {sec.shape}")
        sec = resize(sec, m.shape)
    return sec, (thin(m) if thin_lines else m)


def field_dir_pairs(d: str | Path) -> list[tuple[str, str, str]]:
    """[(key, section path, mask path)] of the ``seismic_<key>.*`` / ``mask_<key>.*`` pairs
    of folder ``d`` (.npy, .png or SEG-Y), in key order.

    Raises
    ------
    InputError
        The folder holds no such pair.
    """
    from demseis.errors import InputError
    from demseis.evaluation.fieldio import MASK_SUFFIXES

    root = Path(d).expanduser()
    pairs = []
    for sec in sorted(root.glob("seismic_*")):
        if sec.suffix.lower() not in MASK_SUFFIXES:
            continue
        key = sec.stem[len("seismic_"):]
        masks = [m for m in root.glob(f"mask_{key}.*") if m.suffix.lower() in MASK_SUFFIXES]
        if masks:
            pairs.append((key, str(sec), str(masks[0])))
    if not pairs:
        raise InputError(f"--field-dir {d!r}: no seismic_<key> / mask_<key> pairs")
    return pairs


def read_field(pairs: list[str], *,
               thin_lines: bool = False) -> list[tuple[np.ndarray, np.ndarray]]:
    """(section, mask) pairs from ``SECTION:MASK`` arguments (:func:`read_pair`)."""
    from demseis.errors import InputError

    out = []
    for arg in pairs:
        if ":" not in arg:
            raise InputError(f"--field {arg!r}: expected SECTION:MASK")
        section, mask = arg.rsplit(":", 1)
        out.append(read_pair(section, mask, thin_lines=thin_lines))
    return out


# ------------------------------------------------------------------------------- scoring

def score_stack(probs: list[np.ndarray], truth: list[np.ndarray], tolerance: float,
                threshold: float = 0.5):
    """:func:`demseis.evaluation.score` of sections that may differ in shape, pooled: they are
    padded with zeros (no prediction, no label) to one stack, which changes no count.
    ``threshold`` is that of the counts (precision, recall, F1); the sweeps ignore it."""
    from demseis.evaluation import score

    h = max(p.shape[0] for p in probs)
    w = max(p.shape[1] for p in probs)
    pad = lambda a: np.pad(a, ((0, h - a.shape[0]), (0, w - a.shape[1])))  # noqa: E731
    return score(np.stack([pad(np.asarray(p, np.float32)) for p in probs]),
                 np.stack([pad(np.asarray(t, np.uint8)) for t in truth]), threshold=threshold,
                 tolerance_px=tolerance)


# ------------------------------------------------------------------------------- training

def add_training_args(ap, cpu_steps: int, max_eval_help: str) -> None:
    """The budget and split options of both benchmarks (one budget for every cell)."""
    ap.add_argument("--steps", type=int,
                    help=f"optimiser steps (default 3000 CUDA / {cpu_steps} CPU)")
    ap.add_argument("--base", type=int, help="U-Net base width (default 32 CUDA / 16 CPU)")
    ap.add_argument("--crop", type=int, default=96)
    ap.add_argument("--batch", type=int, default=8)
    ap.add_argument("--lr", type=float, default=2e-3)
    ap.add_argument("--threads", type=int, default=2, help="torch CPU threads")
    ap.add_argument("--device", help="cuda / cpu (default: cuda when available)")
    ap.add_argument("--test-fraction", type=float, default=0.25, help="share of runs held out")
    ap.add_argument("--max-eval", type=int, default=48, help=max_eval_help)


def budget(args, cpu_steps: int) -> tuple[bool, str, int, int]:
    """(cuda, device, steps, base): CUDA (mixed precision) when present, 3000 steps at base
    32, else ``cpu_steps`` at base 16, unless the options say otherwise."""
    import torch

    cuda = torch.cuda.is_available() if args.device is None else args.device.startswith("cuda")
    device = args.device or ("cuda" if cuda else "cpu")
    steps = args.steps or (3000 if cuda else cpu_steps)
    return cuda, device, steps, args.base or (32 if cuda else 16)


# ------------------------------------------------------------------------------- results

def load_results(path: Path, benchmark: str) -> dict:
    if path.exists():
        return json.loads(path.read_text())
    return {"benchmark": benchmark, "cells": []}


def save_results(path: Path, results: dict) -> None:
    """Write ``results`` under a temporary name and rename (an interrupted write loses nothing)."""
    tmp = path.with_name(path.name + ".tmp")
    tmp.write_text(json.dumps(results, indent=1))
    os.replace(tmp, path)


def machine(cuda: bool, threads: int) -> str:
    """The device in words: the GPU's name, or the CPU and the torch threads used."""
    import platform

    import torch

    if cuda:
        return torch.cuda.get_device_name(0)
    return f"{platform.processor() or platform.machine()}, {threads} threads"
