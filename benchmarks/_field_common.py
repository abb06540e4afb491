"""What the field-transfer benchmarks share: reading labelled field sections, resampling,
scoring sections of different shapes, and the accumulated results file.

Used by ``benchmarks/field_benchmark.py`` and ``benchmarks/cross_domain.py`` (both put
``benchmarks/`` on ``sys.path``). The readers are the benchmark's own, in one place
(:func:`read_section`, :func:`read_mask`), so that a package reader
(``demseis.evaluation.fieldio``) can replace them.

Field files are read from wherever the user keeps them (a cache outside the repository):
nothing here copies them.
"""

from __future__ import annotations

import json
import os
from pathlib import Path

import numpy as np

#: the suffixes read as images, NumPy arrays and SEG-Y
PNG, NPY, SEGY = (".png",), (".npy",), (".sgy", ".segy")


# ---------------------------------------------------------------- readers (swap for fieldio)

def _check_file(path: str | Path, what: str) -> Path:
    from demseis.errors import InputError

    p = Path(path)
    if not p.is_file():
        raise InputError(f"{what}: {str(p)!r} is not a file")
    if p.suffix.lower() not in PNG + NPY + SEGY:
        raise InputError(f"{what}: {str(p)!r}: expected a .png, .npy, .sgy or .segy file")
    return p


def _image(path: Path) -> np.ndarray:
    """An image file as an (H, W, C) uint8 array (C = 1 for grey images)."""
    from PIL import Image

    with Image.open(path) as im:
        a = np.asarray(im)
    return a[..., None] if a.ndim == 2 else a


def _array2d(path: Path, what: str) -> np.ndarray:
    from demseis.errors import InputError

    a = np.load(path)
    if a.ndim != 2:
        raise InputError(f"{what}: {str(path)!r} holds shape {a.shape}, expected (samples, "
                         "traces)")
    return a


def read_section(path: str | Path, what: str = "--field") -> np.ndarray:
    """A (samples, traces) float32 section from a SEG-Y file (one trace per column), a 2-D
    ``.npy`` array, or a grey-scale display image (PNG).

    A display image becomes an amplitude: its grey level (the mean of the colour channels)
    minus the image's median grey (the background of a grey-scale seismic rendering, which is
    zero amplitude), scaled to unit RMS. The colour map is assumed monotonic in grey: a
    red-white-blue rendering does not read this way.
    """
    from demseis.errors import InputError
    from demseis.evaluation.segyfile import read_segy_section

    p = _check_file(path, what)
    suffix = p.suffix.lower()
    if suffix in SEGY:
        try:
            return read_segy_section(p)
        except InputError as exc:
            raise InputError(f"{what}: {str(p)!r} is not a readable SEG-Y file: {exc}") from None
    if suffix in NPY:
        return _array2d(p, what).astype(np.float32)
    rgb = _image(p).astype(np.float64)
    grey = rgb[..., :3].mean(axis=-1) if rgb.shape[-1] >= 3 else rgb[..., 0]
    grey -= np.median(grey)
    rms = float(np.sqrt(np.mean(grey ** 2)))
    return (grey / max(rms, 1e-12)).astype(np.float32)


def read_mask(path: str | Path, what: str = "--field") -> np.ndarray:
    """A (samples, traces) bool fault mask: ``.npy`` (> 0 is fault), SEG-Y (> 0.5), or an
    image of dark lines on a light or transparent background (a pixel is fault where its
    opacity times darkness exceeds one half)."""
    from demseis.errors import InputError
    from demseis.evaluation.segyfile import read_segy_section

    p = _check_file(path, what)
    suffix = p.suffix.lower()
    if suffix in NPY:
        return _array2d(p, what) > 0
    if suffix in SEGY:
        return read_segy_section(p) > 0.5
    a = _image(p).astype(np.float64) / 255.0
    colour, alpha = (a[..., :-1], a[..., -1]) if a.shape[-1] in (2, 4) else (a, 1.0)
    return alpha * (1.0 - colour.mean(axis=-1)) > 0.5


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


def resize(a: np.ndarray, shape: tuple[int, int], order: int = 1) -> np.ndarray:
    """``a`` resampled to ``shape`` (bilinear for order 1), the corner pixels' centres kept
    at the corners' centres; smoothed first when shrinking, so that it does not alias."""
    from scipy import ndimage

    a = np.asarray(a, np.float64)
    if a.shape == tuple(shape):
        return a.astype(np.float32)
    f = [s / n for s, n in zip(shape, a.shape)]
    if min(f) < 1 and order > 0:
        a = ndimage.gaussian_filter(a, [max(0.0, (1 / x - 1) / 2) for x in f])
    rows = np.linspace(0, a.shape[0] - 1, shape[0])
    cols = np.linspace(0, a.shape[1] - 1, shape[1])
    rr, cc = np.meshgrid(rows, cols, indexing="ij")
    return ndimage.map_coordinates(a, [rr, cc], order=order, mode="nearest").astype(np.float32)


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
        if Path(section).suffix.lower() not in PNG or abs(ratio[0] / ratio[1] - 1) > 0.02:
            raise InputError(f"{what}: mask {str(mask)!r} has shape {m.shape}, the section "
                             f"{str(section)!r} has (samples, traces) {sec.shape}")
        sec = resize(sec, m.shape)
    return sec, (thin(m) if thin_lines else m)


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

def score_stack(probs: list[np.ndarray], truth: list[np.ndarray], tolerance: float):
    """:func:`demseis.evaluation.score` of sections that may differ in shape, pooled: they are
    padded with zeros (no prediction, no label) to one stack, which changes no count."""
    from demseis.evaluation import score

    h = max(p.shape[0] for p in probs)
    w = max(p.shape[1] for p in probs)
    pad = lambda a: np.pad(a, ((0, h - a.shape[0]), (0, w - a.shape[1])))  # noqa: E731
    return score(np.stack([pad(np.asarray(p, np.float32)) for p in probs]),
                 np.stack([pad(np.asarray(t, np.uint8)) for t in truth]), threshold=0.5,
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
