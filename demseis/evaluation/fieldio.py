"""Read a hand-picked fault mask and a section from a file: ``.npy``, ``.png`` or SEG-Y.

What ``demseis score PRED MASK`` reads in place of a store, and what a benchmark on field
sections imports::

    from demseis.evaluation.fieldio import read_mask, read_section
    mask = read_mask("inline_picks.png")        # bool (H, W): True on a picked fault
    section = read_section("inline.sgy")        # float32 (H, W): a trace per column

A section is (samples, traces): rows down the trace, one column per trace, as the store's
``seismic`` arrays and :mod:`demseis.evaluation.segyfile` lay them out.

Which pixels of a mask are faults
---------------------------------
- ``.npy``: every nonzero value (bool, integer or float; NaN or infinity is an error). A 2-D
  array is one mask; a 3-D array (N, H, W) is N masks (:func:`read_masks`).
- SEG-Y (``.sgy`` / ``.segy``): every nonzero sample, a trace per column.
- ``.png``: every pixel whose *value* differs from the image's most common value, the
  background. A pixel's value is its luminance (Pillow's ``L``: 0.299 R + 0.587 G + 0.114 B,
  rounded to 0..255) when it is not fully transparent, and one value "transparent" when its
  alpha is 0 (whatever its colour). So black lines on white, white lines on black, coloured
  lines on a grey or transparent background all read the same. 16-bit and 32-bit grey PNGs
  are compared by their raw values. Anti-aliased lines count with their soft edges (any pixel
  not exactly the background); draw picks without anti-aliasing, or let the scoring
  tolerance absorb them.

A mask without any fault pixel is an error (there is nothing to score recall against).
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
from numpy.typing import NDArray
from PIL import Image, UnidentifiedImageError
from scipy import ndimage

from demseis.errors import InputError
from demseis.evaluation.segyfile import is_segy, read_segy_section

__all__ = ["MASK_SUFFIXES", "as_masks", "is_mask_file", "read_mask", "read_masks", "read_section",
           "resize_sections"]

#: file name endings read as a mask or a section (any case)
MASK_SUFFIXES = (".npy", ".png", ".sgy", ".segy")


def is_mask_file(path: str | Path) -> bool:
    """True when ``path`` names a mask file rather than a store: it is not a directory and its
    name ends in one of :data:`MASK_SUFFIXES` (any case). It need not exist."""
    return not os.path.isdir(path) and str(path).lower().endswith(MASK_SUFFIXES)


def _check_file(path: str | Path, what: str) -> str:
    p = str(path)
    if not p.lower().endswith(MASK_SUFFIXES):
        raise InputError(f"{what} {p!r}: give a .npy, .png, .sgy or .segy file")
    if not os.path.isfile(p):
        raise InputError(f"{what} {p!r} does not exist")
    return p


def _load_npy(path: str, what: str) -> NDArray:
    try:
        arr = np.load(path, allow_pickle=False)
    except Exception as exc:  # noqa: BLE001 - any unreadable file is the same user error
        raise InputError(f"{what} {path!r}: cannot read as .npy "
                         f"({type(exc).__name__}: {exc})") from None
    if not isinstance(arr, np.ndarray) or not (np.issubdtype(arr.dtype, np.number)
                                               or arr.dtype == bool):
        raise InputError(f"{what} {path!r}: expected a numeric array, got dtype "
                         f"{getattr(arr, 'dtype', type(arr).__name__)}")
    return arr


def _open_png(path: str, what: str) -> tuple[NDArray, NDArray | None]:
    """A PNG's luminance (0..255, Pillow's ``L``) and alpha (0..255), or for a 16/32-bit grey
    image its raw values and None."""
    try:
        with Image.open(path) as img:
            img.load()
            if img.mode in ("I", "I;16", "I;16B", "I;16L", "F"):
                return np.asarray(img), None
            rgba = img.convert("RGBA")
    except (UnidentifiedImageError, OSError, ValueError) as exc:
        raise InputError(f"{what} {path!r}: cannot read as PNG ({exc})") from None
    return np.asarray(rgba.convert("RGB").convert("L")), np.asarray(rgba)[..., 3]


def _png_mask(path: str, what: str) -> NDArray[np.bool_]:
    lum, alpha = _open_png(path, what)
    # one value per pixel: its luminance, or 256 ("transparent") where alpha is 0
    values = lum if alpha is None else np.where(alpha == 0, 256, lum.astype(np.int32))
    uniq, count = np.unique(values, return_counts=True)
    return values != uniq[int(np.argmax(count))]


def as_masks(values: NDArray, name: str = "mask") -> NDArray[np.bool_]:
    """A mask array (H, W) or (N, H, W) as bool (N, H, W), True where nonzero.

    InputError (starting with ``name``) for another number of dimensions, a non-numeric dtype,
    NaN or infinite values, or no fault pixel at all.
    """
    arr = np.asarray(values)
    if arr.ndim not in (2, 3) or 0 in arr.shape:
        raise InputError(f"{name}: expected an array (H, W) or (N, H, W), got shape {arr.shape}")
    if not (np.issubdtype(arr.dtype, np.number) or arr.dtype == bool):
        raise InputError(f"{name}: expected numbers (nonzero on a fault), got dtype {arr.dtype}")
    if np.issubdtype(arr.dtype, np.floating) and not np.isfinite(arr).all():
        raise InputError(f"{name} holds NaN or infinite values; a mask is 0 off a fault and "
                         "nonzero on one")
    stack = (arr != 0).reshape((-1, *arr.shape[-2:]))
    if not stack.any():
        raise InputError(f"{name} has no fault pixels (all {stack.shape[1]} x {stack.shape[2]} "
                         "are background); nothing to score against")
    return np.ascontiguousarray(stack)


def read_masks(path: str | Path) -> NDArray[np.bool_]:
    """The fault mask(s) in ``path`` as a bool array (N, H, W); N = 1 but for a 3-D ``.npy``.

    Which pixels are faults: see the module docstring.

    Raises
    ------
    InputError
        The file is missing, of another kind, unreadable, not 2-D (or 3-D for ``.npy``),
        holds NaN or infinite values, or has no fault pixel.
    """
    p = _check_file(path, "mask")
    if is_segy(p):
        values = read_segy_section(p)
    elif p.lower().endswith(".png"):
        values = _png_mask(p, "mask")
    else:
        values = _load_npy(p, "mask")
    return as_masks(values, f"mask {p!r}")


def read_mask(path: str | Path) -> NDArray[np.bool_]:
    """The fault mask in ``path`` as a bool array (H, W), True on a fault.

    ``.npy`` (nonzero; (H, W) or (1, H, W)), ``.png`` (differs from the most common value,
    see the module docstring) or SEG-Y (nonzero, a trace per column). Raises
    :class:`~demseis.errors.InputError` as :func:`read_masks` does, and for a ``.npy`` stack
    of several masks.
    """
    stack = read_masks(path)
    if stack.shape[0] != 1:
        raise InputError(f"mask {str(path)!r} holds {stack.shape[0]} masks (shape "
                         f"{stack.shape}); read_masks reads a stack")
    return stack[0]


def read_section(path: str | Path) -> NDArray[np.float32]:
    """The section in ``path`` as float32 (H, W): a trace per column.

    ``.npy`` ((H, W) or (1, H, W)), SEG-Y (``.sgy`` / ``.segy``), or ``.png`` (a display image:
    its luminance scaled to [0, 1], 0 black; alpha ignored; 16-bit grey to [0, 1] as well).

    Raises
    ------
    InputError
        The file is missing, of another kind, unreadable, not one 2-D section, or holds NaN or
        infinite values.
    """
    p = _check_file(path, "section")
    if is_segy(p):
        sec = read_segy_section(p)
    elif p.lower().endswith(".png"):
        lum, alpha = _open_png(p, "section")
        scale = 255.0 if alpha is not None else (65535.0 if lum.max() <= 65535 else lum.max())
        sec = lum.astype(np.float32) / np.float32(scale)
    else:
        sec = _load_npy(p, "section")
        if sec.ndim == 3 and sec.shape[0] == 1:
            sec = sec[0]
        if sec.ndim != 2 or 0 in sec.shape:
            raise InputError(f"section {p!r}: expected one section (H, W) or (1, H, W), got "
                             f"shape {sec.shape}")
        sec = sec.astype(np.float32)
    if not np.isfinite(sec).all():
        raise InputError(f"section {p!r} holds NaN or infinite values")
    return np.ascontiguousarray(sec, dtype=np.float32)


def read_amplitudes(path: str | Path) -> NDArray[np.float32]:
    """:func:`read_section` as amplitudes: a ``.png`` (a grey display image) less its median
    luminance, the grey of zero amplitude; other files as they are."""
    sec = read_section(path)
    if str(path).lower().endswith(".png"):
        sec = sec - np.float32(np.median(sec))
    return sec


def resize_sections(stack: NDArray, shape: tuple[int, int]) -> NDArray[np.float32]:
    """Sections (N, H, W) resampled onto an (H2, W2) grid: bilinear, pixel centres aligned.

    Output pixel (i, j) takes the value at source coordinates ``((i + 0.5) H / H2 - 0.5,
    (j + 0.5) W / W2 - 0.5)``, interpolated linearly between the four nearest source pixels
    and clamped at the edges (the half-pixel convention of Pillow's and OpenCV's bilinear
    resize). Values are convex combinations of the input, so probabilities stay in [0, 1].
    """
    arr = np.asarray(stack, dtype=np.float32)
    n, h, w = arr.shape
    h2, w2 = int(shape[0]), int(shape[1])
    if (h, w) == (h2, w2):
        return arr
    y = np.clip((np.arange(h2) + 0.5) * h / h2 - 0.5, 0, h - 1)
    x = np.clip((np.arange(w2) + 0.5) * w / w2 - 0.5, 0, w - 1)
    yy, xx = np.meshgrid(y, x, indexing="ij")
    return np.stack([ndimage.map_coordinates(a, [yy, xx], order=1, mode="nearest")
                     for a in arr]).astype(np.float32)
