"""Synthetic assemblies and kinematic faults for checking labels without running the DEM.

:func:`disk_pack` builds a dense polydisperse disk pack (geometric, not mechanically settled);
:func:`kinematic_fault` displaces element centres across a planar normal fault, either as a
rigid offset of the hanging wall or spread over a shear zone of given width. Both are used by the
tests (analytic strain, mask-on-the-line checks) and by the calibration figure.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from demseis.errors import InputError


def disk_pack(
    width_m: float,
    height_m: float,
    rng: np.random.Generator,
    *,
    radius_min_m: float = 12.5,
    radius_max_m: float = 25.0,
    packing_fraction: float = 0.82,
    relax_iterations: int = 60,
) -> tuple[np.ndarray, np.ndarray]:
    """A dense polydisperse disk pack filling ``[0, width_m] x [0, height_m]``.

    Radii are uniform in ``[radius_min_m, radius_max_m]``; centres start on a jittered
    hexagonal lattice whose spacing gives ``packing_fraction`` and are then pushed apart
    pairwise (half the overlap each way, ``relax_iterations`` sweeps) inside the box, so the
    neighbourhoods are irregular like a DEM pack's, with small residual overlaps.

    Parameters
    ----------
    width_m, height_m : box size (m), each > 4 * radius_max_m.
    rng : random generator (the only source of randomness).
    radius_min_m, radius_max_m : radius range (m).
    packing_fraction : target area fraction sum(pi r^2) / box area, in (0.3, 0.95).
    relax_iterations : overlap-removal sweeps (>= 0).

    Returns
    -------
    xy : (n, 2) float64 centres (m, y up); radius : (n,) float64 radii (m).
    """
    if not (0 < radius_min_m <= radius_max_m):
        raise InputError(f"radius range [{radius_min_m}, {radius_max_m}] invalid; "
                         "need 0 < min <= max")
    if width_m <= 4 * radius_max_m or height_m <= 4 * radius_max_m:
        raise InputError(f"box {width_m} x {height_m} m too small for radius_max_m={radius_max_m}")
    if not (0.3 < packing_fraction < 0.95):
        raise InputError(f"packing_fraction = {packing_fraction}; allowed: (0.3, 0.95)")
    mean_area = np.pi * (radius_min_m**2 + radius_min_m * radius_max_m + radius_max_m**2) / 3.0
    spacing = np.sqrt(mean_area / (packing_fraction * np.sqrt(3.0) / 2.0))
    dy = spacing * np.sqrt(3.0) / 2.0
    rows = int(np.floor((height_m - 2 * radius_min_m) / dy)) + 1
    cols = int(np.floor((width_m - 2 * radius_min_m) / spacing)) + 1
    jj, ii = np.meshgrid(np.arange(cols), np.arange(rows))
    x = radius_min_m + jj * spacing + 0.5 * spacing * (ii % 2)
    y = radius_min_m + ii * dy
    xy = np.column_stack([x.ravel(), y.ravel()]).astype(np.float64)
    xy = xy[(xy[:, 0] <= width_m - radius_min_m)]
    n = xy.shape[0]
    xy += rng.uniform(-0.25, 0.25, size=(n, 2)) * spacing
    radius = rng.uniform(radius_min_m, radius_max_m, size=n)
    for _ in range(int(relax_iterations)):
        tree = cKDTree(xy)
        pairs = tree.query_pairs(2.0 * radius_max_m, output_type="ndarray")
        if pairs.size == 0:
            break
        d = xy[pairs[:, 1]] - xy[pairs[:, 0]]
        dist = np.sqrt((d**2).sum(1))
        overlap = radius[pairs[:, 0]] + radius[pairs[:, 1]] - dist
        hit = overlap > 0
        if not hit.any():
            break
        p, d, dist, overlap = pairs[hit], d[hit], dist[hit], overlap[hit]
        push = (0.5 * overlap / np.maximum(dist, 1e-9))[:, None] * d
        disp = np.zeros_like(xy)
        np.add.at(disp, p[:, 0], -push)
        np.add.at(disp, p[:, 1], push)
        xy += 0.5 * disp
        xy[:, 0] = np.clip(xy[:, 0], radius, width_m - radius)
        xy[:, 1] = np.clip(xy[:, 1], radius, height_m - radius)
    return xy, radius


def fault_signed_distance(xy: np.ndarray, x_m: float, dip_deg: float,
                          dip_direction: str = "right") -> np.ndarray:
    """Signed distance (m) of points from a planar fault, positive in the hanging wall.

    The fault passes through ``(x_m, 0)`` and dips at ``dip_deg`` towards ``dip_direction``
    (``"right"``: the fault trace moves to larger x with depth; hanging wall at larger x).
    """
    xy = np.asarray(xy, dtype=np.float64)
    if dip_direction not in ("right", "left"):
        raise InputError(f"dip_direction = {dip_direction!r}; allowed: 'right' | 'left'")
    if not (0.0 < dip_deg < 90.0):
        raise InputError(f"dip_deg = {dip_deg}; allowed: (0, 90)")
    th = np.radians(dip_deg)
    s = 1.0 if dip_direction == "right" else -1.0
    # unit normal pointing into the hanging wall: (s sin th, cos th)... the fault direction
    # going up-dip is (-s cos th, sin th); rotate clockwise by 90 deg for s = +1.
    nx, ny = s * np.sin(th), np.cos(th)
    return (xy[:, 0] - x_m) * nx + xy[:, 1] * ny


def kinematic_fault(
    xy: np.ndarray,
    *,
    x_m: float,
    dip_deg: float,
    slip_m: float | np.ndarray,
    dip_direction: str = "right",
    zone_width_m: float = 0.0,
) -> np.ndarray:
    """Element centres after kinematic normal-fault slip on a planar fault.

    The hanging wall moves ``slip_m`` down-dip, parallel to the fault; the footwall stays. With
    ``zone_width_m = 0`` the offset is rigid (a displacement step on the plane); with a width w
    the displacement ramps linearly across ``|signed distance| <= w / 2``, i.e. a band of
    homogeneous simple shear gamma = slip / w centred on the plane.

    Parameters
    ----------
    xy : (n, 2) centres (m, y up).
    x_m : where the fault meets y = 0.
    dip_deg : dip in (0, 90) degrees.
    slip_m : down-dip slip (m), >= 0 (a normal fault); a scalar or one value per element
        (slip varying along the fault: give each hanging-wall element the slip of its part
        of the fault).
    dip_direction : ``"right"`` or ``"left"`` (side of the hanging wall).
    zone_width_m : shear-zone width (m), >= 0.

    Returns
    -------
    (n, 2) float64 displaced centres.
    """
    slip = np.asarray(slip_m, dtype=np.float64)
    if np.any(slip < 0) or zone_width_m < 0:
        raise InputError(f"slip_m = {slip_m}, zone_width_m = {zone_width_m}; both must be >= 0")
    xy = np.asarray(xy, dtype=np.float64)
    if slip.ndim == 1 and slip.shape[0] != xy.shape[0]:
        raise InputError(f"slip_m has shape {slip.shape}; expected a scalar or ({xy.shape[0]},)")
    d = fault_signed_distance(xy, x_m, dip_deg, dip_direction)
    th = np.radians(dip_deg)
    s = 1.0 if dip_direction == "right" else -1.0
    down_dip = np.array([s * np.cos(th), -np.sin(th)])
    if zone_width_m > 0:
        frac = np.clip(d / zone_width_m + 0.5, 0.0, 1.0)
    else:
        frac = (d > 0).astype(np.float64)
    return xy + (slip * frac)[:, None] * down_dip[None, :]


def listric_fault(xy: np.ndarray, *, centre_xy: tuple[float, float], radius_m: float,
                  slip_m: float) -> np.ndarray:
    """Element centres after slip on a listric (circular-arc) normal fault.

    The fault is the circle of ``radius_m`` around ``centre_xy``; the hanging wall (the
    points inside the circle) rotates rigidly about the centre by ``slip_m / radius_m``
    radians, so it slides ``slip_m`` along the arc everywhere and stays in contact with it.
    With the centre up and to the right of the fault, the hanging wall is on the right and
    the fault flattens with depth (dip = 90 deg at the centre's height).

    Parameters
    ----------
    xy : (n, 2) centres (m, y up).
    centre_xy : (x, y) of the arc's centre (m).
    radius_m : arc radius (m), > 0.
    slip_m : slip along the arc (m), >= 0; the hanging wall moves down the fault on the
        centre's left.

    Returns
    -------
    (n, 2) float64 displaced centres.
    """
    if radius_m <= 0 or slip_m < 0:
        raise InputError(f"radius_m = {radius_m} must be > 0 and slip_m = {slip_m} >= 0")
    xy = np.asarray(xy, dtype=np.float64)
    c = np.asarray(centre_xy, dtype=np.float64)
    d = xy - c
    inside = np.hypot(d[:, 0], d[:, 1]) < radius_m
    phi = slip_m / radius_m  # counter-clockwise: down the arc left of the centre
    rot = np.array([[np.cos(phi), -np.sin(phi)], [np.sin(phi), np.cos(phi)]])
    out = xy.copy()
    out[inside] = c + d[inside] @ rot.T
    return out
