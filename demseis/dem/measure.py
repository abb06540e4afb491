"""Measures of a faulted assembly taken from its particles (no labels needed).

- :func:`horizon_profile` / :func:`horizon_step`: how sharply a horizon steps across a fault
  (localised fault vs drape monocline);
- :func:`displacement_jump`: the displacement of the hanging-wall side minus the footwall side
  of a fault, and its slip sense;
- :func:`section_length`: the horizontal extent of the pre-kinematic section (shortening or
  lengthening).
"""

from __future__ import annotations

import math

import numpy as np

from demseis.errors import InputError
from demseis.types import Snapshot


def horizon_profile(snap: Snapshot, layers: int | tuple[int, ...], x_edges: np.ndarray
                    ) -> np.ndarray:
    """Elevation of a horizon per column: median centre height of its elements.

    Parameters
    ----------
    snap : Snapshot.
    layers : layer index (or indices) that make the horizon.
    x_edges : (m + 1,) column edges (m).

    Returns
    -------
    (m,) float64 elevation (m), NaN in columns without an element of the horizon.
    """
    sel = np.isin(snap.layer, np.atleast_1d(layers))
    x, y = snap.xy[sel, 0], snap.xy[sel, 1]
    col = np.searchsorted(x_edges, x, side="right") - 1
    out = np.full(x_edges.size - 1, np.nan)
    for c in np.unique(col[(col >= 0) & (col < out.size)]):
        out[c] = np.median(y[col == c])
    return out


def _window_drops(snap: Snapshot, layers, x_m: float, dip_direction: str, window_m: float,
                  search_m: float, bin_m: float):
    """(window centres, drops, footwall-side and hanging-wall-side elevations) of every
    ``window_m`` window whose centre lies within ``search_m`` of ``x_m`` (drops may be NaN)."""
    if dip_direction not in ("right", "left"):
        raise InputError(f"dip_direction={dip_direction!r}; allowed 'right' or 'left'")
    if not (window_m > 0 and bin_m > 0 and window_m >= bin_m):
        raise InputError(f"need window_m >= bin_m > 0, got {window_m}, {bin_m}")
    lo = x_m - search_m - window_m
    n = int(math.ceil((2 * search_m + 2 * window_m) / bin_m))
    edges = lo + bin_m * np.arange(n + 1)
    h = horizon_profile(snap, layers, edges)
    k = int(round(window_m / bin_m))
    a, b = h[:-k], h[k:]
    drop = a - b if dip_direction == "right" else b - a
    centre = 0.5 * (edges[:-1] + edges[1:])
    mid = 0.5 * (centre[:-k] + centre[k:])
    near = np.abs(mid - x_m) <= search_m
    return mid[near], drop[near], a[near], b[near]


def horizon_step(snap: Snapshot, layers: int | tuple[int, ...], x_m: float, *,
                 dip_direction: str = "right", window_m: float = 100.0,
                 search_m: float = 600.0, bin_m: float = 25.0) -> float:
    """Largest drop of a horizon across any ``window_m``-wide window near a fault (m).

    The horizon is sampled in ``bin_m`` columns (:func:`horizon_profile`); for every window
    whose centre lies within ``search_m`` of ``x_m`` the drop is the elevation on the footwall
    side minus the elevation ``window_m`` farther towards the hanging wall (``dip_direction``:
    ``"right"``, the hanging wall at larger x, or ``"left"``). A fault that offsets the horizon
    gives a drop near the throw; a monocline spreads it over its width and gives
    ``throw * window / width``.

    Returns
    -------
    float: the largest drop (m, > 0 down towards the hanging wall); NaN if no window has data
    on both sides.
    """
    _, drop, _, _ = _window_drops(snap, layers, x_m, dip_direction, window_m, search_m, bin_m)
    ok = np.isfinite(drop)
    return float(np.max(drop[ok])) if ok.any() else float("nan")


def fault_crossings(snap: Snapshot, layers, x_m: float, *, dip_direction: str = "right",
                    window_m: float = 100.0, search_m: float = 600.0, bin_m: float = 25.0
                    ) -> tuple[np.ndarray, np.ndarray]:
    """Where a fault crosses each horizon: centre of its ``window_m`` window of largest drop.

    For every layer in ``layers`` (each one horizon), the windows of :func:`horizon_step`
    whose drop is within 1% of the largest (a clean step gives the same drop in every window
    that straddles it): their mean centre.

    Returns
    -------
    x, y : (len(layers),) float64 the window centre and the horizon's mean elevation at the
    window's two ends (m); NaN where a horizon has no window with data on both sides.
    """
    layers = list(layers)
    xs = np.full(len(layers), np.nan)
    ys = np.full(len(layers), np.nan)
    for q, layer in enumerate(layers):
        mid, drop, a, b = _window_drops(snap, layer, x_m, dip_direction, window_m, search_m,
                                        bin_m)
        ok = np.isfinite(drop)
        if ok.any():
            top = np.max(drop[ok])
            best = ok & (drop >= top - 0.01 * abs(top))  # ties: a clean step spans windows
            xs[q] = float(np.mean(mid[best]))
            ys[q] = float(np.mean(0.5 * (a[best] + b[best])))
    return xs, ys


def _common(ref: Snapshot, cur: Snapshot) -> tuple[np.ndarray, np.ndarray]:
    """Positions of the ids present in both snapshots (ids are sorted in each)."""
    common, i_ref, i_cur = np.intersect1d(ref.ids, cur.ids, assume_unique=True,
                                          return_indices=True)
    return i_ref, i_cur


def displacement_jump(ref: Snapshot, cur: Snapshot, x_m: float, dip_deg: float,
                      dip_direction: str, y_range_m: tuple[float, float], *,
                      gap_m: float = 75.0, width_m: float = 200.0) -> np.ndarray:
    """Median displacement of the hanging-wall side minus the footwall side of a fault.

    Elements are taken in their reference positions (``ref``) with ``y`` in ``y_range_m``;
    the fault is the plane through ``(x_m, 0)`` with the given dip, so at height y it lies at
    ``x_m - a y / tan(dip)`` (a = +1 dipping right). The two sides are the bands between
    ``gap_m`` and ``gap_m + width_m`` from that line, measured horizontally.

    Returns
    -------
    (2,) float64 jump (m): hanging wall minus footwall displacement from ``ref`` to ``cur``.
    Its component along the hanging wall's down-dip direction is > 0 for normal slip and
    < 0 for reverse slip (:func:`slip_sense`).
    """
    a = 1.0 if dip_direction == "right" else -1.0
    i_ref, i_cur = _common(ref, cur)
    p = ref.xy[i_ref]
    d = cur.xy[i_cur] - p
    inb = (p[:, 1] >= y_range_m[0]) & (p[:, 1] <= y_range_m[1])
    xf = x_m - a * p[:, 1] / math.tan(math.radians(dip_deg))
    off = a * (p[:, 0] - xf)  # > 0 on the hanging-wall side
    hw = inb & (off > gap_m) & (off < gap_m + width_m)
    fw = inb & (-off > gap_m) & (-off < gap_m + width_m)
    if hw.sum() < 3 or fw.sum() < 3:
        raise InputError(f"too few elements beside the fault at x={x_m} m in y {y_range_m}")
    return np.median(d[hw], axis=0) - np.median(d[fw], axis=0)


def slip_sense(jump: np.ndarray, dip_deg: float, dip_direction: str) -> float:
    """Component of a hanging-wall-minus-footwall jump along the down-dip direction (m):
    > 0 normal, < 0 reverse."""
    a = 1.0 if dip_direction == "right" else -1.0
    d = math.radians(dip_deg)
    return float(jump[0] * a * math.cos(d) - jump[1] * math.sin(d))


def section_length(snap: Snapshot, y_max_m: float, n_original: int | None = None) -> float:
    """Horizontal extent (m) of the elements centred below ``y_max_m``: max x - min x.

    ``n_original``: only ids below it count (the pre-kinematic elements).
    """
    sel = snap.xy[:, 1] < y_max_m
    if n_original is not None:
        sel &= snap.ids < n_original
    x = snap.xy[sel, 0]
    if x.size == 0:
        raise InputError(f"no element below y={y_max_m} m")
    return float(x.max() - x.min())
