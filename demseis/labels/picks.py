"""Fault labels as an interpreter picks them: one smooth one-pixel polyline per fault.

The engines' fault labels are traces on the model's depth grid: a DEM fault zone slips on
several strands side by side, and taken to the output traces and time samples those become
webs and short pieces. An interpreter draws a fault as one line along the sharp offset of
the reflectors, where the offset is visible at the section's sampling. :func:`pick_faults`
redraws the labels that way on the OUTPUT grid (after the traces and the time axis):

1. every fault instance ``k`` (``fault_id == k``) is taken as a point cloud in pixel space
   (row, column); its principal axis ``e`` (the eigenvector of the larger eigenvalue of the
   pixels' covariance) and the normal ``m`` give each pixel an abscissa ``t`` and an offset
   ``n``;
2. per one-pixel bin of ``t`` the line's offset is the slip-weighted mean ``n`` of the
   instance's pixels in the bin (parallel strands of one fault zone collapse to one line,
   nearest the strand that slips most), its throw the mean throw (in output samples) of
   those pixels, its slip, dip and sense their means (sense: the majority);
3. bins without pixels up to ``max_gap_px`` long are bridged by linear interpolation; longer
   gaps, and bins whose throw is below ``min_throw_samples``, split the line into pieces;
4. each piece's offsets are smoothed along ``t`` by a Gaussian of ``smooth_px`` (ends
   reflected), pieces shorter than ``min_length_px`` bins are dropped;
5. each piece is drawn as a digital line through its points (one pixel per step along the
   longer axis, then the corner pixels whose neighbours along the line touch are removed:
   :func:`demseis.labels._kernels.thin_path`), so it is one pixel wide, 8-connected, and has
   no loops or rungs;
6. faults are drawn in id order (id 1 is the largest); a pixel taken by an earlier fault
   stays its. Ids are renumbered 1.. in that order over the faults that kept a piece.

``fault``, ``fault_id``, ``slip_m``, ``dip_deg`` (the fault's true dip, degrees) and ``sense``
are replaced; every other map (``damage``, ``strain``, ``layer``) is kept as it is. The throw of
a pixel is ``slip_m * sin(dip_deg)``.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from demseis.errors import InputError
from demseis.labels import _kernels as _k

#: the maps :func:`pick_faults` replaces
PICKED = ("fault", "fault_id", "slip_m", "dip_deg", "sense")


@dataclass(frozen=True)
class PickConfig:
    """How faults are picked (the ``[labels]`` keys of the same names).

    Attributes
    ----------
    min_throw_samples : smallest throw, in output samples (time samples or depth cells), for a
        fault to be drawn there.
    smooth_px : Gaussian sigma (pixels along the fault) of the line's offsets; 0 = none.
    max_gap_px : gaps of the fault's pixels up to this many bins are bridged.
    min_length_px : pieces shorter than this many bins are dropped.
    """

    min_throw_samples: float = 1.0
    smooth_px: float = 2.0
    max_gap_px: int = 4
    min_length_px: int = 5


def throw_samples(slip_m: np.ndarray, dip_deg: np.ndarray, *, cell_m: float | None = None,
                  vp_m_s: np.ndarray | None = None, dt_s: float | None = None) -> np.ndarray:
    """Throw of every pixel in output samples: ``slip sin(dip) / cell_m`` on a depth grid, or
    the two-way time of the throw ``2 slip sin(dip) / vp`` over ``dt_s`` on a time axis."""
    throw_m = np.asarray(slip_m, dtype=np.float64) * np.sin(np.radians(np.asarray(dip_deg,
                                                                                  np.float64)))
    if vp_m_s is None:
        if cell_m is None:
            raise InputError("throw_samples needs cell_m (depth) or vp_m_s and dt_s (time)")
        return throw_m / float(cell_m)
    vp = np.asarray(vp_m_s, dtype=np.float64)
    with np.errstate(divide="ignore", invalid="ignore"):
        out = 2.0 * throw_m / (np.where(vp > 0, vp, np.inf) * float(dt_s))
    return out


def _smooth(values: np.ndarray, sigma: float) -> np.ndarray:
    """Gaussian smoothing of a 1-D series with reflected ends."""
    if sigma <= 0 or values.size < 2:
        return values
    half = int(np.ceil(3 * sigma))
    x = np.arange(-half, half + 1)
    w = np.exp(-0.5 * (x / sigma) ** 2)
    w /= w.sum()
    padded = np.pad(values, half, mode="reflect" if values.size > half else "edge")
    return np.convolve(padded, w, mode="valid")


def _pieces(ok: np.ndarray, min_len: int) -> list[tuple[int, int]]:
    """[start, stop) runs of True in ``ok`` at least ``min_len`` long."""
    if not ok.any():
        return []
    d = np.diff(np.concatenate([[0], ok.astype(np.int8), [0]]))
    starts, stops = np.flatnonzero(d == 1), np.flatnonzero(d == -1)
    return [(int(a), int(b)) for a, b in zip(starts, stops) if b - a >= min_len]


def fault_polylines(rows: np.ndarray, cols: np.ndarray, weight: np.ndarray,
                    throw: np.ndarray, cfg: PickConfig,
                    values: Mapping[str, np.ndarray] | None = None,
                    ) -> tuple[list[np.ndarray], dict[str, np.ndarray]]:
    """The pieces of one fault's line from its pixels (module docstring, steps 1-4).

    Parameters
    ----------
    rows, cols : (n,) pixel coordinates of the fault's pixels.
    weight : (n,) weight of each pixel in the line's position (its slip; > 0).
    throw : (n,) throw of each pixel in output samples.
    values : optional (n,) per-pixel values to average per bin (slip, dip, ...).

    Returns
    -------
    lines : list of (m, 3) float64 arrays: per piece, the points (row, col) in order along
        the fault and the bin index (column 2) of each point.
    attrs : per name of ``values``, the (bins,) mean of its pixels per bin; a bin without
        pixels takes the nearest bin's.
    """
    r = np.asarray(rows, dtype=np.float64)
    c = np.asarray(cols, dtype=np.float64)
    if r.size < 2:
        return [], {}
    r0, c0 = r.mean(), c.mean()
    _, vecs = np.linalg.eigh(np.cov(np.vstack([r - r0, c - c0])))
    e = vecs[:, 1]                                    # principal axis (row, col)
    if e[0] < 0 or (e[0] == 0 and e[1] < 0):          # a fixed orientation: downwards
        e = -e
    m = np.array([-e[1], e[0]])
    t = (r - r0) * e[0] + (c - c0) * e[1]
    n = (r - r0) * m[0] + (c - c0) * m[1]
    tmin = t.min()
    b = np.rint(t - tmin).astype(np.int64)
    nb = int(b.max()) + 1
    w = np.maximum(np.asarray(weight, dtype=np.float64), 1e-12)
    count = np.bincount(b, minlength=nb)
    has = count > 0
    idx = np.flatnonzero(has)

    def per_bin(v: np.ndarray, wts: np.ndarray | None = None) -> np.ndarray:
        out = np.zeros(nb)
        if wts is None:
            out[has] = np.bincount(b, weights=v, minlength=nb)[has] / count[has]
        else:
            out[has] = (np.bincount(b, weights=wts * v, minlength=nb)[has]
                        / np.bincount(b, weights=wts, minlength=nb)[has])
        return out

    n_bin = per_bin(n, w)
    th_bin = per_bin(np.asarray(throw, np.float64))
    attrs = {}
    if values:
        k = np.arange(nb)
        after = np.clip(np.searchsorted(idx, k), 0, idx.size - 1)
        before = np.clip(after - 1, 0, idx.size - 1)
        near = np.where(np.abs(idx[before] - k) <= np.abs(idx[after] - k), idx[before],
                        idx[after])
        attrs = {name: per_bin(np.asarray(v, np.float64))[near] for name, v in values.items()}
    # bridge short gaps (offsets and throws interpolated), split at long ones
    fill = np.zeros(nb, dtype=bool)
    gaps = np.diff(idx) - 1
    for j in np.flatnonzero((gaps > 0) & (gaps <= cfg.max_gap_px)):
        fill[idx[j] + 1: idx[j + 1]] = True
    if fill.any():
        n_bin[fill] = np.interp(np.flatnonzero(fill), idx, n_bin[has])
        th_bin[fill] = np.interp(np.flatnonzero(fill), idx, th_bin[has])
    ok = (has | fill) & (th_bin >= cfg.min_throw_samples)
    lines = []
    for a, z in _pieces(ok, max(int(cfg.min_length_px), 1)):
        off = _smooth(n_bin[a:z], cfg.smooth_px)
        tt = np.arange(a, z) + tmin
        pr = r0 + tt * e[0] + off * m[0]
        pc = c0 + tt * e[1] + off * m[1]
        lines.append(np.column_stack([pr, pc, np.arange(a, z, dtype=np.float64)]))
    return lines, attrs


def draw_path(points: np.ndarray, shape: tuple[int, int]) -> tuple[np.ndarray, np.ndarray,
                                                                   np.ndarray]:
    """Pixels of the digital line through ``points`` ((m, 2+) row, col; float), one pixel wide
    and 8-connected, clipped to ``shape``.

    Returns ``(rows, cols, k)``: the pixels in order and, for each, the index of the point it
    was drawn from (the nearer end of its segment).
    """
    p = np.asarray(points[:, :2], dtype=np.float64)
    if p.shape[0] == 1:
        rr, cc, kk = np.rint(p[:, 0]), np.rint(p[:, 1]), np.zeros(1)
    else:
        d = np.diff(p, axis=0)
        steps = np.maximum(np.ceil(np.abs(d).max(axis=1)), 1).astype(np.int64)
        seg = np.repeat(np.arange(d.shape[0]), steps)
        frac = (np.arange(steps.sum()) - np.repeat(np.cumsum(steps) - steps, steps)) \
            / np.repeat(steps, steps)
        rr = np.concatenate([p[seg, 0] + frac * d[seg, 0], p[-1:, 0]])
        cc = np.concatenate([p[seg, 1] + frac * d[seg, 1], p[-1:, 1]])
        kk = np.concatenate([seg + (frac >= 0.5), [p.shape[0] - 1]])
        rr, cc = np.rint(rr), np.rint(cc)
    rr = rr.astype(np.int64)
    cc = cc.astype(np.int64)
    kk = np.asarray(kk, dtype=np.int64)
    keep = _k.thin_path(rr, cc)
    rr, cc, kk = rr[keep], cc[keep], kk[keep]
    inside = (rr >= 0) & (rr < shape[0]) & (cc >= 0) & (cc < shape[1])
    return rr[inside], cc[inside], kk[inside]


def pick_faults(maps: Mapping[str, np.ndarray], throw_px: np.ndarray,
                cfg: PickConfig = PickConfig()) -> dict[str, np.ndarray]:
    """The label maps with the fault arrays redrawn as picks (module docstring).

    Parameters
    ----------
    maps : label maps on the output grid (``fault``, ``fault_id``, ``slip_m``, ``dip_deg``,
        ``sense`` and any others), (H, W) each.
    throw_px : (H, W) throw of every pixel in output samples (:func:`throw_samples`).
    cfg : the picking settings.

    Returns
    -------
    A new dict: the same keys and dtypes, the :data:`PICKED` maps new arrays, the others the
    arrays of ``maps`` themselves.
    """
    fid = np.asarray(maps["fault_id"])
    fault = np.asarray(maps["fault"]) > 0
    shape = fid.shape
    out = {name: (np.zeros(shape, dtype=np.asarray(m).dtype) if name in PICKED else m)
           for name, m in maps.items()}
    slip = np.asarray(maps["slip_m"], dtype=np.float64)
    dip = np.asarray(maps["dip_deg"], dtype=np.float64)
    sense = np.asarray(maps["sense"], dtype=np.float64)
    throw = np.nan_to_num(np.asarray(throw_px, dtype=np.float64), nan=0.0, posinf=0.0)
    on = fault & (fid > 0)
    ids = np.unique(fid[on])
    new_id = 0
    for k in ids:
        rr, cc = np.nonzero(on & (fid == k))
        lines, attrs = fault_polylines(rr, cc, slip[rr, cc], throw[rr, cc], cfg,
                                       {"slip_m": slip[rr, cc], "dip_deg": dip[rr, cc],
                                        "sense": sense[rr, cc]})
        drew = False
        for pts in lines:
            pr, pc, pk = draw_path(pts, shape)
            free = out["fault"][pr, pc] == 0
            pr, pc, pk = pr[free], pc[free], pk[free]
            if pr.size == 0:
                continue
            if not drew:
                new_id += 1
                drew = True
            b = pts[pk, 2].astype(np.int64)
            out["fault"][pr, pc] = 1
            out["fault_id"][pr, pc] = new_id
            out["slip_m"][pr, pc] = attrs["slip_m"][b]
            out["dip_deg"][pr, pc] = attrs["dip_deg"][b]
            out["sense"][pr, pc] = np.where(attrs["sense"][b] > 1.5, 2, 1)
    return out
