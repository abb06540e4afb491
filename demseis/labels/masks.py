"""Binary masks on the grid: Guo-Hall thinning, connected pieces and enclosed holes.

The mask operations that both fault-label methods use: the one-cell skeleton of a mask
(:func:`skeletonize`, Numba kernel), dropping small or short 8-connected pieces and filling
small holes.
"""

from __future__ import annotations

import numpy as np
from scipy import ndimage

from demseis.labels import _kernels

#: structuring element of 8-connectivity (side and diagonal neighbours)
EIGHT = np.ones((3, 3), dtype=bool)


def guo_hall_luts() -> tuple[np.ndarray, np.ndarray]:
    """Deletion tables of the two Guo-Hall subiterations over the 256 neighbour codes.

    Bits 0..7 of a code are the neighbours E, NE, N, NW, W, SW, S, SE (x1..x8). A cell is
    deleted when C(p) = sum_i [!x(2i-1) and (x(2i) or x(2i+1))] = 1, 2 <= min(N1, N2) <= 3 and
    (x2 or x3 or !x8) and x1 = 0 (first subiteration) / (x6 or x7 or !x4) and x5 = 0 (second).
    """
    lut1 = np.zeros(256, dtype=np.bool_)
    lut2 = np.zeros(256, dtype=np.bool_)
    for code in range(256):
        b = [(code >> k) & 1 == 1 for k in range(8)]
        c = sum((not b[i]) and (b[i + 1] or b[(i + 2) % 8]) for i in (0, 2, 4, 6))
        n1 = sum(b[k] or b[k - 1] for k in (1, 3, 5, 7))
        n2 = sum(b[k] or b[(k + 1) % 8] for k in (1, 3, 5, 7))
        g12 = c == 1 and 2 <= min(n1, n2) <= 3
        lut1[code] = g12 and not ((b[1] or b[2] or not b[7]) and b[0])
        lut2[code] = g12 and not ((b[5] or b[6] or not b[3]) and b[4])
    return lut1, lut2


_LUT1, _LUT2 = guo_hall_luts()


def skeletonize(mask: np.ndarray) -> np.ndarray:
    """One-cell-wide skeleton of a binary mask (Guo-Hall thinning, Numba kernel)."""
    m = np.ascontiguousarray(np.asarray(mask, dtype=bool).astype(np.uint8))
    return _kernels.guo_hall_thin(m, _LUT1, _LUT2).astype(bool)


def remove_small_components(mask: np.ndarray, min_cells: int) -> np.ndarray:
    """Drop 8-connected components of ``mask`` with fewer than ``min_cells`` cells."""
    mask = np.asarray(mask, dtype=bool)
    if min_cells <= 1 or not mask.any():
        return mask.copy()
    lab, nlab = ndimage.label(mask, structure=EIGHT)
    sizes = np.bincount(lab.ravel(), minlength=nlab + 1)
    keep = sizes >= min_cells
    keep[0] = False
    return keep[lab]


def long_pieces(cells: np.ndarray, min_cells: int) -> np.ndarray:
    """The 8-connected pieces of ``cells`` whose bounding box has a diagonal of at least
    ``min_cells`` cells (a strand is a surface, not the rim of one particle that moved
    against all its neighbours)."""
    lab, _ = ndimage.label(cells, structure=EIGHT)
    keep = np.zeros(int(lab.max()) + 1, dtype=bool)
    for q, sl in enumerate(ndimage.find_objects(lab), start=1):
        keep[q] = np.hypot(sl[0].stop - sl[0].start, sl[1].stop - sl[1].start) >= min_cells
    keep[0] = False
    return keep[lab]


def fill_small_holes(mask: np.ndarray, max_cells: int,
                     within: np.ndarray | None = None) -> np.ndarray:
    """``mask`` with its holes (4-connected regions of non-mask cells enclosed by it) of at
    most ``max_cells`` cells filled; with ``within``, only its cells are filled."""
    mask = np.asarray(mask, dtype=bool)
    if max_cells <= 0 or not mask.any():
        return mask.copy()
    lab, n = ndimage.label(ndimage.binary_fill_holes(mask) & ~mask)
    if not n:
        return mask.copy()
    small = np.bincount(lab.ravel(), minlength=n + 1) <= max_cells
    small[0] = False
    fill = small[lab]
    if within is not None:
        fill &= np.asarray(within, dtype=bool)
    return mask | fill
