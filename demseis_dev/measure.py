"""Measures of a faulted assembly taken from its particles (no labels needed).

- :func:`horizon_profile` / :func:`horizon_step`: how sharply a horizon steps across a fault
  (localised fault vs drape monocline);
- :func:`displacement_jump`: the displacement of the hanging-wall side minus the footwall side
  of a fault, and its slip sense;
- :func:`section_length`: the horizontal extent of the pre-kinematic section (shortening or
  lengthening);
- :func:`step_line` / :func:`unit_dips` / :func:`strong_weak_dips`: the dip of a fault within
  each unit of layers, fitted in reference coordinates as the line that best splits the
  displacement field (refraction through a strong-weak alternation).
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


def step_line(ref_xy: np.ndarray, disp: np.ndarray, dip_direction: str = "right", *,
              ramp_m: float = 50.0, edge_m: float = 100.0) -> tuple[float, float, float]:
    """The straight line that best splits a displacement field into two rigid sides.

    The elements are taken in their reference positions ``ref_xy``; each one's displacement
    is scaled to ``s`` = 0 on the footwall side and 1 on the hanging-wall side by projecting it
    onto the jump between the median displacement of the elements within ``edge_m`` of the
    window's footwall end and of its hanging-wall end (the window is the span of the elements'
    x). The model is a ramp of horizontal width ``ramp_m`` centred on a line of dip ``d``:
    ``s = clip(h / ramp_m + 1/2, 0, 1)`` with ``h`` the horizontal distance from the line
    towards the hanging wall; the dip and position with the least sum of squared misfits win
    (dips 10..170 deg on a 1 deg grid, then 0.1 deg around the best; positions on a
    ``ramp_m / 10`` grid). A discrete fault gives its plane (the ramp centres the line in the
    gap between the two sides' elements); a fault zone or a monocline the middle of the band
    where the displacement changes.

    Parameters
    ----------
    ref_xy : (n, 2) reference centres (m, y up) of the elements of one unit near one fault.
    disp : (n, 2) their displacements (m) from the reference to the current state.
    dip_direction : side of the hanging wall, ``"right"`` or ``"left"``.
    ramp_m : horizontal width of the model's ramp (m), > 0 (about an element diameter).
    edge_m : width of the two end strips that define the footwall and hanging-wall motion.

    Returns
    -------
    (dip_deg, x_m, misfit): the best dip (degrees from horizontal towards the hanging wall;
    above 90 the line leans back over the hanging wall), where the line crosses the middle
    height of the elements, and the misfit relative to that of no step at all (0 = the ramp
    explains the displacement, 1 = no step found).
    """
    if dip_direction not in ("right", "left"):
        raise InputError(f"dip_direction={dip_direction!r}; allowed 'right' or 'left'")
    if not (ramp_m > 0 and edge_m > 0):
        raise InputError(f"need ramp_m > 0 and edge_m > 0, got {ramp_m}, {edge_m}")
    ref_xy = np.asarray(ref_xy, dtype=np.float64)
    disp = np.asarray(disp, dtype=np.float64)
    if ref_xy.ndim != 2 or ref_xy.shape[1] != 2 or disp.shape != ref_xy.shape:
        raise InputError(f"ref_xy {ref_xy.shape} and disp {disp.shape} must both be (n, 2)")
    a = 1.0 if dip_direction == "right" else -1.0
    x, y = ref_xy[:, 0], ref_xy[:, 1]
    ax = a * x
    fw = ax <= ax.min() + edge_m
    hw = ax >= ax.max() - edge_m
    if fw.sum() < 3 or hw.sum() < 3 or ref_xy.shape[0] < 10:
        raise InputError(f"too few elements to fit a step ({ref_xy.shape[0]} in all, "
                         f"{int(fw.sum())} footwall, {int(hw.sum())} hanging wall)")
    u_fw = np.median(disp[fw], axis=0)
    jump = np.median(disp[hw], axis=0) - u_fw
    j2 = float(jump @ jump)
    if not j2 > 0:
        raise InputError("no displacement jump between the two ends of the window")
    s = (disp - u_fw) @ jump / j2
    y_rel = y - 0.5 * (y.min() + y.max())

    def fit(dips: np.ndarray, step_m: float) -> tuple[float, float, float]:
        best = (np.inf, 0.0, 0.0)
        for dip in dips:
            cot = math.cos(math.radians(dip)) / math.sin(math.radians(dip))
            p = ax + y_rel * cot  # = a x + ... ; the line is p = thr, hanging wall p > thr
            thr = np.arange(p.min(), p.max() + step_m, step_m)
            model = np.clip((p[:, None] - thr[None, :]) / ramp_m + 0.5, 0.0, 1.0)
            cost = np.sum((s[:, None] - model) ** 2, axis=0)
            k = int(np.argmin(cost))
            if cost[k] < best[0]:
                best = (float(cost[k]), float(dip), float(thr[k]))
        return best

    _, dip0, _ = fit(np.arange(10.0, 170.5, 1.0), ramp_m / 5)
    cost, dip, thr = fit(np.arange(dip0 - 1.0, dip0 + 1.05, 0.1), ramp_m / 10)
    null = min(float(np.sum(s**2)), float(np.sum((1.0 - s) ** 2)))
    return dip, a * thr, cost / null if null > 0 else 0.0


def unit_dips(ref: Snapshot, cur: Snapshot, units: list[tuple[int, ...]], x_m: float, *,
              dip_direction: str = "right", footwall_m: float = 500.0,
              hanging_wall_m: float = 300.0, edge_m: float = 100.0
              ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Dip of one fault within each unit of layers, traced upwards from the basement.

    Units are taken bottom to top. Each unit's elements (original elements of its layers,
    in their ``ref`` positions) within a window from ``footwall_m`` on the footwall side to
    ``hanging_wall_m`` on the hanging-wall side of the fault's position at the unit's base
    are split by :func:`step_line`; the line's x at the unit's top is where the next unit's
    window is centred. The first unit starts at ``x_m`` (where the fault leaves the basement,
    in reference coordinates). Measured in the reference state, each unit's dip is that of the
    surface along which its own material was split, whatever the later offset.

    Returns
    -------
    dip_deg, x_mid_m, misfit : (len(units),) float64 per unit (see :func:`step_line`); NaN
    where a unit has too few elements in its window.
    """
    a = 1.0 if dip_direction == "right" else -1.0
    i_ref, i_cur = _common(ref, cur)
    p = ref.xy[i_ref]
    d = cur.xy[i_cur] - p
    lay = ref.layer[i_ref]
    out = np.full((3, len(units)), np.nan)
    x_at = float(x_m)
    for q, unit in enumerate(units):
        in_unit = np.isin(lay, np.asarray(unit))
        if not in_unit.any():
            continue
        y0, y1 = p[in_unit, 1].min(), p[in_unit, 1].max()
        # the fault leans towards the footwall going up: look mostly on that side
        off = a * (p[:, 0] - x_at)
        sel = in_unit & (off >= -footwall_m) & (off <= hanging_wall_m)
        try:
            dip, x_mid, mis = step_line(p[sel], d[sel], dip_direction, edge_m=edge_m)
        except InputError:
            continue
        out[:, q] = dip, x_mid, mis
        cot = math.cos(math.radians(dip)) / math.sin(math.radians(dip))
        x_at = x_mid - a * (y1 - 0.5 * (y0 + y1)) * cot
    return out[0], out[1], out[2]


def strong_weak_dips(ref: Snapshot, cur: Snapshot, units: list[tuple[int, ...]],
                     strong: np.ndarray, x_m: float, *, dip_direction: str = "right"
                     ) -> tuple[float, float, np.ndarray]:
    """Mean fault dip in the strong and in the weak units (refraction), from :func:`unit_dips`.

    A unit's dip is its line's angle folded to 0..90 deg (a segment leaning back over the
    hanging wall at 100 deg dips 80 deg the other way); units without a fit are skipped.

    Parameters
    ----------
    ref, cur : reference and current snapshots of one run.
    units : layer indices of each unit, bottom to top.
    strong : (len(units),) bool, the competent units.
    x_m, dip_direction : as in :func:`unit_dips`.

    Returns
    -------
    (mean dip of the strong units, mean dip of the weak units, per-unit angles 0..180 deg).
    """
    strong = np.asarray(strong, dtype=bool)
    if strong.shape != (len(units),):
        raise InputError(f"strong has shape {strong.shape}; expected ({len(units)},)")
    angle, _, _ = unit_dips(ref, cur, units, x_m, dip_direction=dip_direction)
    dip = 90.0 - np.abs(90.0 - angle)
    ok = np.isfinite(dip)
    if not (ok & strong).any() or not (ok & ~strong).any():
        raise InputError("no strong or no weak unit has a fitted fault")
    return float(dip[ok & strong].mean()), float(dip[ok & ~strong].mean()), angle
