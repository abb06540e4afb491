"""Toy inputs for tests, benchmarks and figure scripts: disk packs and one kinematic normal fault.

Nothing here is mechanics: faulting is geometry. One planar normal fault model serves every toy:
:func:`fault_signed_distance` says which side of the plane a point is on, and
:func:`kinematic_fault` moves the hanging wall down-dip (rigidly, or spread over a shear zone).

- :func:`disk_pack`: a dense polydisperse disk pack (geometric, not mechanically settled);
- :func:`refracted_fault`: a fault whose dip changes from layer to layer (refraction imposed);
- :func:`faulted_sequence`: :class:`~demseis.types.Snapshot` s of a layered pack cut by the fault
  at increasing throw, with growth layers filling the accommodation (a stand-in for a DEM run);
- :func:`faulted_section`: a seismic-like image (sparse reflectivity convolved with a Ricker
  pulse) offset across the fault, and its fault-trace truth mask.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from demseis.errors import InputError
from demseis.types import Snapshot


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


def down_dip_vector(dip_deg: float, dip_direction: str = "right") -> np.ndarray:
    """(2,) unit vector (x, y up) pointing down the dip of the fault of :func:`kinematic_fault`."""
    th = np.radians(dip_deg)
    s = 1.0 if dip_direction == "right" else -1.0
    return np.array([s * np.cos(th), -np.sin(th)])


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
    down_dip = down_dip_vector(dip_deg, dip_direction)
    if zone_width_m > 0:
        frac = np.clip(d / zone_width_m + 0.5, 0.0, 1.0)
    else:
        frac = (d > 0).astype(np.float64)
    return xy + (slip * frac)[:, None] * down_dip[None, :]


def refracted_fault(xy: np.ndarray, *, x_m: float, y_edges_m: np.ndarray,
                    dips_deg: np.ndarray, throw_m: float, zone_width_m: float = 0.0
                    ) -> np.ndarray:
    """Element centres after a vertical throw on a right-dipping fault that refracts.

    The fault leaves ``(x_m, y_edges_m[0])`` and crosses the band ``[y_edges_m[k],
    y_edges_m[k + 1]]`` at ``dips_deg[k]`` (a piecewise-straight trace, steeper in some layers
    than in others). Every point on its hanging-wall side (larger x) moves down by ``throw_m``;
    with ``zone_width_m`` the motion ramps linearly over that horizontal width centred on the
    trace. Vertical motion fits any trace shape, so nothing overlaps or opens.

    Returns
    -------
    (n, 2) float64 displaced centres (points above or below the bands keep the end dips).
    """
    edges = np.asarray(y_edges_m, dtype=np.float64)
    dips = np.asarray(dips_deg, dtype=np.float64)
    if edges.ndim != 1 or dips.shape != (edges.size - 1,) or np.any(np.diff(edges) <= 0):
        raise InputError("y_edges_m must increase and dips_deg have one value per band")
    if np.any((dips <= 0) | (dips >= 180)) or throw_m < 0 or zone_width_m < 0:
        raise InputError("dips in (0, 180), throw_m >= 0 and zone_width_m >= 0 required")
    cot = 1.0 / np.tan(np.radians(dips))
    x_edges = x_m - np.concatenate([[0.0], np.cumsum(np.diff(edges) * cot)])
    xy = np.asarray(xy, dtype=np.float64)
    y = xy[:, 1]
    k = np.clip(np.searchsorted(edges, y, side="right") - 1, 0, dips.size - 1)
    x_trace = x_edges[k] - (y - edges[k]) * cot[k]
    d = xy[:, 0] - x_trace
    frac = (np.clip(d / zone_width_m + 0.5, 0.0, 1.0) if zone_width_m > 0
            else (d > 0).astype(np.float64))
    out = xy.copy()
    out[:, 1] -= throw_m * frac
    return out


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


def _hex_points(x0: float, x1: float, y0: float, y1: float, spacing: float,
                rng: np.random.Generator) -> np.ndarray:
    dy = spacing * np.sqrt(3.0) / 2.0
    rows = int(np.floor((y1 - y0) / dy))
    pts = []
    for r in range(rows):
        y = y0 + (r + 0.5) * dy
        off = 0.5 * spacing if r % 2 else 0.0
        xs = np.arange(x0 + 0.25 * spacing + off, x1, spacing)
        pts.append(np.column_stack([xs, np.full(xs.size, y)]))
    p = np.concatenate(pts) if pts else np.zeros((0, 2))
    return p + rng.uniform(-0.08, 0.08, p.shape) * spacing


def layered_pack(width_m: float = 5000.0, height_m: float = 2770.0, n_layers: int = 48,
                 radius_min_m: float = 12.5, radius_max_m: float = 25.0,
                 rng: np.random.Generator | None = None) -> Snapshot:
    """An undeformed pack: hexagonal lattice (spacing 2.04 x mean radius), jittered, radii
    uniform, layers of equal thickness numbered from the base (0) up (about the seed-scale
    density: 10,900 disks over 5 km x 2.77 km)."""
    rng = np.random.default_rng(0) if rng is None else rng
    spacing = 2.04 * 0.5 * (radius_min_m + radius_max_m)
    xy = _hex_points(0.0, width_m, 0.0, height_m, spacing, rng)
    radius = rng.uniform(radius_min_m, radius_max_m, xy.shape[0])
    layer = np.minimum((xy[:, 1] / height_m * n_layers).astype(np.int64), n_layers - 1)
    n = xy.shape[0]
    return Snapshot(0, 0, 0.0, np.arange(n, dtype=np.int64), xy, radius,
                    layer.astype(np.int16), np.zeros(n, dtype=bool))


def faulted_sequence(width_m: float = 5000.0, height_m: float = 2770.0, n_layers: int = 48,
                     throw_m: float = 450.0, dip_deg: float = 60.0, x_fault_m: float | None = None,
                     n_snapshots: int = 6, radius_min_m: float = 12.5, radius_max_m: float = 25.0,
                     rng: np.random.Generator | None = None) -> list[Snapshot]:
    """Snapshots of a pack cut by a right-dipping normal fault at throws ``k/(n-1) throw_m``.

    The fault passes through ``(x_fault_m, 0)`` (default 0.6 width) and dips right at
    ``dip_deg`` (it reaches the surface at ``x_fault_m - height_m / tan(dip)``); at every
    increment the hanging wall (decided once, in the undeformed state, with
    :func:`fault_signed_distance`; growth strata included) moves down-dip by the throw increment
    (:func:`down_dip_vector`, as :func:`kinematic_fault` moves it), and the accommodation below
    the initial surface is filled with a new growth layer (index ``n_layers + k - 1``, ``deposited=True``, new ids).
    """
    rng = np.random.default_rng(0) if rng is None else rng
    x_fault_m = 0.6 * width_m if x_fault_m is None else x_fault_m
    base = layered_pack(width_m, height_m, n_layers, radius_min_m, radius_max_m, rng)
    sin = np.sin(np.radians(dip_deg))
    spacing = 2.04 * 0.5 * (radius_min_m + radius_max_m)
    ids, xy, radius, layer, dep = (base.ids, base.xy.copy(), base.radius, base.layer,
                                   base.deposited)
    hanging = fault_signed_distance(xy, x_fault_m, dip_deg) > 0
    snaps = [Snapshot(0, 0, 0.0, ids, xy.copy(), radius, layer, dep)]
    done = 0.0
    next_id = int(ids.max()) + 1
    for k in range(1, n_snapshots):
        target = k / (n_snapshots - 1) * throw_m
        d = target - done
        done = target
        xy[hanging] += (d / sin) * down_dip_vector(dip_deg)
        # fill the hanging-wall accommodation between the subsided surface and the datum
        # (the column below moved down by d, so the new space is the top d of the box)
        new = _hex_points(0.0, width_m, height_m - d, height_m, spacing, rng)
        new = new[fault_signed_distance(new, x_fault_m + 0.5 * spacing, dip_deg) > 0]
        m = new.shape[0]
        if m:
            ids = np.concatenate([ids, np.arange(next_id, next_id + m, dtype=np.int64)])
            next_id += m
            xy = np.concatenate([xy, new])
            radius = np.concatenate([radius, rng.uniform(radius_min_m, radius_max_m, m)])
            layer = np.concatenate([layer, np.full(m, n_layers + k - 1, dtype=np.int16)])
            dep = np.concatenate([dep, np.ones(m, dtype=bool)])
            hanging = np.concatenate([hanging, np.ones(m, dtype=bool)])
        snaps.append(Snapshot(k, 0, target, ids, xy.copy(), radius, layer, dep))
    return snaps


def ricker_pulse(f_hz: float, dt_s: float, n: int) -> np.ndarray:
    """(n,) zero-phase Ricker wavelet of peak frequency ``f_hz`` sampled at ``dt_s``, centred."""
    t = (np.arange(n) - n // 2) * dt_s
    a = (np.pi * f_hz * t) ** 2
    return (1 - 2 * a) * np.exp(-a)


def faulted_section(nz: int = 96, nx: int = 96, throw: float = 6.0, dip_deg: float = 70.0,
                    noise: float = 0.0, seed: int = 0, fault: bool = True,
                    regional: float = 0.1) -> tuple[np.ndarray, np.ndarray]:
    """A toy seismic section cut by the planar normal fault, and its truth mask.

    Sparse random reflectivity convolved with a 25 Hz Ricker (4 ms samples), gently dipping
    (``regional`` samples per trace, sub-sample interpolation), cut by a right-dipping fault
    through the centre of the image whose hanging wall (decided by
    :func:`fault_signed_distance`, in pixel units with y up) is shifted down by ``throw``
    samples. ``noise`` adds white noise of that fraction of the section's standard deviation.
    Truth: pixels within 1 px (horizontally) of the fault trace.

    Returns
    -------
    section : (nz, nx) float32; truth : (nz, nx) uint8.
    """
    rng = np.random.default_rng(seed)
    refl = rng.normal(0, 1, 2 * nz) * (rng.random(2 * nz) < 0.3)
    trace = np.convolve(refl, ricker_pulse(25.0, 0.004, 41), mode="same")
    z = np.arange(nz)[:, None]
    x = np.arange(nx)[None, :]
    fx = nx / 2 + (z - nz / 2) / np.tan(np.radians(dip_deg))
    pts = np.column_stack([np.broadcast_to(x, (nz, nx)).ravel(),
                           np.broadcast_to(nz / 2 - z, (nz, nx)).ravel()]).astype(np.float64)
    hanging = (fault_signed_distance(pts, nx / 2, dip_deg) > 0).reshape(nz, nx)
    shift = regional * x + (throw if fault else 0.0) * hanging
    s = np.interp(z + nz // 2 - shift, np.arange(2 * nz), trace)
    if noise:
        s = s + rng.normal(0, noise * s.std(), s.shape)
    truth = (np.abs(x - fx) <= 1.0) & fault
    return s.astype(np.float32), truth.astype(np.uint8)
