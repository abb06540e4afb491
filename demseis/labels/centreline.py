"""Centre lines of banded masks: spur pruning and along-strike smoothing of a skeleton.

The skeleton of a thresholded strain band follows the band's edges, which in a
granular assembly are stepped at the scale of the elements (3-4 cells at 10 m for 12.5-25 m
radii). Averaging the skeleton's coordinates along its own length over a window of a few
element diameters removes that stepping while keeping the trace where the strain is.
"""

from __future__ import annotations

import numpy as np
from scipy import ndimage

_EIGHT = np.ones((3, 3), dtype=bool)
_OFFS = [(-1, -1), (-1, 0), (-1, 1), (0, -1), (0, 1), (1, -1), (1, 0), (1, 1)]


# the 8 neighbours in circular order N, NE, E, SE, S, SW, W, NW
_RING = [(-1, 0), (-1, 1), (0, 1), (1, 1), (1, 0), (1, -1), (0, -1), (-1, -1)]


def crossing_number(skel: np.ndarray) -> np.ndarray:
    """Number of background-to-foreground transitions around each foreground cell.

    1 = end point, 2 = a cell inside a line (also on a staircase corner, where a plain
    neighbour count would say 3), >= 3 = a junction. 0 on background and isolated cells.
    """
    s = np.pad(np.asarray(skel, dtype=bool), 1)
    nz, nx = skel.shape
    ring = [s[1 + di:1 + di + nz, 1 + dj:1 + dj + nx] for di, dj in _RING]
    cn = np.zeros((nz, nx), dtype=np.int32)
    for q in range(8):
        cn += (~ring[q] & ring[(q + 1) % 8]).astype(np.int32)
    return cn * np.asarray(skel, dtype=bool)


def _crossing_in(pixels: set, p: tuple[int, int]) -> int:
    ring = [(p[0] + di, p[1] + dj) in pixels for di, dj in _RING]
    return sum((not ring[q]) and ring[(q + 1) % 8] for q in range(8))


def _trace(pixels: set, start: tuple[int, int]) -> list[tuple[int, int]]:
    """Walk a simple 8-connected path of ``pixels`` from ``start`` (side steps preferred)."""
    path = [start]
    seen = {start}
    cur = start
    while True:
        nxt = None
        for di, dj in sorted(_OFFS, key=lambda o: abs(o[0]) + abs(o[1])):
            p = (cur[0] + di, cur[1] + dj)
            if p in pixels and p not in seen:
                nxt = p
                break
        if nxt is None:
            return path
        path.append(nxt)
        seen.add(nxt)
        cur = nxt


def prune_spurs(skel: np.ndarray, max_len: int) -> np.ndarray:
    """Remove branches of at most ``max_len`` cells that run from an end point to a junction.

    Isolated paths (no junction) are kept whatever their length. Where every branch of a
    junction but one is such a short end branch, the junction is the fork that thinning leaves
    at the end of a line (the two corners of the band's end): the longest of the short branches
    is kept there, so the line still reaches the end of its band; the others are removed.
    """
    skel = np.asarray(skel, dtype=bool).copy()
    if max_len <= 0 or not skel.any():
        return skel
    cn = crossing_number(skel)
    junction = cn >= 3
    body = skel & ~ndimage.binary_dilation(junction, structure=_EIGHT)
    lab, nlab = ndimage.label(body, structure=_EIGHT)
    if nlab == 0:
        return skel
    sizes = np.bincount(lab.ravel(), minlength=nlab + 1)
    near_j = ndimage.binary_dilation(junction, structure=_EIGHT, iterations=2)
    jlab, _ = ndimage.label(near_j, structure=_EIGHT)
    ends = (cn == 1) & skel
    has_end = np.zeros(nlab + 1, dtype=bool)
    has_end[np.unique(lab[ends & (lab > 0)])] = True
    short_end = has_end & (sizes <= max_len)
    short_end[0] = False
    # branches touching each junction zone: pairs (junction zone, branch)
    both = (jlab > 0) & (lab > 0)
    pairs = np.unique(np.column_stack([jlab[both], lab[both]]), axis=0)
    drop = np.zeros(nlab + 1, dtype=bool)
    for jz in np.unique(pairs[:, 0]) if pairs.size else []:
        br = pairs[pairs[:, 0] == jz, 1]
        cand = br[short_end[br]]
        if cand.size == 0:
            continue
        if cand.size == br.size - 1 and br.size >= 2:
            cand = cand[np.argsort(sizes[cand], kind="stable")][:-1]  # keep the longest
        drop[cand] = True
    skel[drop[lab]] = False
    return skel


def smooth_skeleton(skel: np.ndarray, window_cells: int) -> np.ndarray:
    """Redraw every junction-free branch of ``skel`` with its coordinates moving-averaged.

    Parameters
    ----------
    skel : (nz, nx) bool one-cell-wide skeleton.
    window_cells : moving-average length along the branch (cells); the window shrinks
        symmetrically near branch ends, so end points stay put. <= 1 returns a copy.

    Returns
    -------
    (nz, nx) bool smoothed centre line (junction cells kept as they are).
    """
    skel = np.asarray(skel, dtype=bool)
    if window_cells <= 1 or not skel.any():
        return skel.copy()
    half = int(window_cells) // 2
    nz, nx = skel.shape
    junction = crossing_number(skel) >= 3
    body = skel & ~junction
    out = junction.copy()
    lab, _ = ndimage.label(body, structure=_EIGHT)
    objs = ndimage.find_objects(lab)
    for k, sl in enumerate(objs, start=1):
        if sl is None:
            continue
        sub = lab[sl] == k
        ii, jj = np.nonzero(sub)
        ii = ii + sl[0].start
        jj = jj + sl[1].start
        pixels = set(zip(ii.tolist(), jj.tolist()))
        # an end of the branch: crossing number <= 1 inside the branch (else a cycle)
        start = None
        for p in sorted(pixels):
            if _crossing_in(pixels, p) <= 1:
                start = p
                break
        if start is None:
            start = min(pixels)
        path = np.array(_trace(pixels, start), dtype=np.float64)
        rest = pixels - set(map(tuple, path.astype(int).tolist()))
        m = path.shape[0]
        if m >= 3:
            c = np.vstack([np.zeros((1, 2)), np.cumsum(path, axis=0)])
            idx = np.arange(m)
            h = np.minimum(np.minimum(idx, m - 1 - idx), half)
            sm = (c[idx + h + 1] - c[idx - h]) / (2 * h + 1)[:, None]
        else:
            sm = path
        # draw the polyline densely
        seg = np.diff(sm, axis=0)
        steps = np.maximum(np.ceil(np.abs(seg).max(axis=1) * 2).astype(int), 1) if m > 1 else []
        pts = [sm[:1]]
        for q in range(m - 1):
            t = (np.arange(1, steps[q] + 1) / steps[q])[:, None]
            pts.append(sm[q] + t * seg[q])
        pts = np.rint(np.vstack(pts)).astype(int)
        pts[:, 0] = np.clip(pts[:, 0], 0, nz - 1)
        pts[:, 1] = np.clip(pts[:, 1], 0, nx - 1)
        out[pts[:, 0], pts[:, 1]] = True
        for p in rest:  # pixels the walk did not reach (tiny side loops): keep
            out[p] = True
    return out

