"""Label maps on the seismic grid: fault mask, damage-zone classes, strain target, layer ids.

Pipeline (per snapshot), all on the :class:`demseis.types.Grid` the seismic uses, so the
labels are pixel-aligned with it:

1. per-element strain -> grid with :func:`demseis.seismic.raster.rasterise` (mean over the disks
   containing each cell centre); cells in the gaps between disks take the value of their
   power-diagram element (least d^2 - r^2 within 1.5 r); cells no element reaches (above the
   free surface) are "no rock": strain 0, layer -1, never fault.
2. optional Gaussian smoothing (``smooth_sigma_cells``) of the strain used for thresholding.
3. fault = strain >= ``fault_threshold``; 8-connected components smaller than
   ``min_component_cells`` dropped; with ``thickness_cells`` = t >= 1 small holes are filled,
   the mask is thinned to a one-cell skeleton (Guo-Hall), short side branches are pruned, each
   branch is moving-averaged along its length (``centreline_window_cells``) and the result is
   re-grown to the cells within t/2 of that centre line.
4. damage = 0 background, 1 strain >= ``damage_threshold`` (small components dropped),
   2 fault core (the fault mask).

Steps 2-4 are the legacy ``"strain_band"`` method; the default ``"slip_trace"`` method traces
slip surfaces (:mod:`demseis.labels.traces`, targets by :func:`trace_targets`).
"""

from __future__ import annotations

import numpy as np
from scipy import ndimage

from demseis.errors import InputError
from demseis.labels import _kernels
from demseis.labels.config import LabelConfig
from demseis.labels.strain import StrainState

#: A cell belongs to the rock when it lies within this multiple of an element's radius.
ROCK_REACH = 1.5
_EIGHT = np.ones((3, 3), dtype=bool)


def label_maps(snapshot, strain_per_element, grid, config: LabelConfig | None = None,
               displacement: np.ndarray | None = None) -> dict:
    """Fault, damage-zone, strain and layer labels of one snapshot on ``grid``.

    Parameters
    ----------
    snapshot : :class:`demseis.dem.types.Snapshot` (uses ``xy``, ``radius``, ``layer``).
    strain_per_element : (n,) gamma_max aligned with the snapshot's elements (NaN = unknown,
        ignored), or the snapshot's :class:`~demseis.labels.strain.StrainState`, in which case
        ``config.strain_measure`` picks total or cumulative.
    grid : :class:`demseis.types.Grid`, row 0 at the top.
    config : :class:`LabelConfig` (defaults if None).
    displacement : (n, 2) displacement (m) of each element since its first appearance, or the
        tuple (displacement, birth) of :func:`demseis.labels.traces.displacement_history`
        (birth: snapshot of first appearance, so that deposition surfaces are not taken for
        slip); required by the default ``"slip_trace"`` method.

    Returns
    -------
    dict with (nz, nx) arrays:
        ``fault`` uint8 0/1; ``damage`` uint8 0 background / 1 damage zone / 2 fault core;
        ``strain`` float32 rasterised gamma_max (unsmoothed; 0 outside the rock);
        ``layer`` int16 layer id of the cell's element (-1 outside the rock);
        ``fault_id`` int16 fault instance 1.. on fault cells (0 elsewhere);
        ``slip_m`` float32 slip (m), ``dip_deg`` float32 dip (degrees) and ``sense`` uint8
        (1 normal, 2 reverse) of the nearest trace cell, on fault cells (0 elsewhere); with
        ``"strain_band"`` fault_id numbers the mask's 8-connected components and slip, dip,
        sense are 0.
    """
    cfg = (config or LabelConfig()).validate()
    xy = np.asarray(snapshot.xy, dtype=np.float64)
    radius = np.asarray(snapshot.radius, dtype=np.float64)
    layer = np.asarray(snapshot.layer)
    n = xy.shape[0]
    if isinstance(strain_per_element, StrainState):
        if not np.array_equal(strain_per_element.ids, np.asarray(snapshot.ids)):
            raise InputError(
                f"strain_per_element is the StrainState of snapshot {strain_per_element.index}; "
                f"its element ids do not match those of snapshot {getattr(snapshot, 'index', '?')}"
            )
        strain_e = strain_per_element.measure(cfg.strain_measure)
    else:
        strain_e = np.asarray(strain_per_element, dtype=np.float64)
    if strain_e.shape != (n,):
        raise InputError(
            f"strain_per_element has shape {strain_e.shape}; expected ({n},) like the snapshot"
        )
    if layer.shape != (n,):
        raise InputError(f"snapshot.layer has shape {layer.shape}; expected ({n},)")
    strain, owner = rasterise_strain(xy, radius, strain_e, grid)
    rock = owner >= 0
    layer_map = np.full(grid.shape, -1, dtype=np.int16)
    layer_map[rock] = layer[owner[rock]].astype(np.int16)
    if cfg.method == "slip_trace":
        if displacement is None:
            raise InputError("label_maps: the 'slip_trace' method needs the elements' "
                             "displacement (n, 2); see demseis.labels.traces.displacement_history")
        birth = None
        if isinstance(displacement, tuple):
            displacement, birth = displacement
        disp = np.asarray(displacement, dtype=np.float64)
        if disp.shape != (n, 2):
            raise InputError(f"displacement has shape {disp.shape}; expected ({n}, 2)")
        from demseis.labels.traces import slip_traces

        ux, _ = rasterise_strain(xy, radius, disp[:, 0], grid)
        uy, _ = rasterise_strain(xy, radius, disp[:, 1], grid)
        cohort = None
        if birth is not None:
            birth = np.asarray(birth)
            if birth.shape != (n,):
                raise InputError(f"birth has shape {birth.shape}; expected ({n},)")
            cohort = np.where(rock, birth[np.maximum(owner, 0)], -1)
        tr = slip_traces(strain, ux, uy, rock, float(grid.cell_m), cfg, cohort)
        out = trace_targets(tr, cfg, float(grid.cell_m), rock)
    else:
        smoothed = _smoothed(strain, cfg.smooth_sigma_cells, rock)
        fault = fault_mask(strain, cfg, rock=rock, smoothed=smoothed)
        damage = damage_map(strain, fault, cfg, rock=rock, smoothed=smoothed)
        fid, _ = ndimage.label(fault, structure=_EIGHT)
        zeros = np.zeros(grid.shape, dtype=np.float32)
        out = {"fault": fault, "damage": damage, "fault_id": fid.astype(np.int16),
               "slip_m": zeros, "dip_deg": zeros.copy(),
               "sense": np.zeros(grid.shape, dtype=np.uint8)}
    return {"fault": out["fault"], "damage": out["damage"], "strain": strain.astype(np.float32),
            "layer": layer_map, "fault_id": out["fault_id"], "slip_m": out["slip_m"],
            "dip_deg": out["dip_deg"], "sense": out["sense"]}


def trace_targets(traces, config: LabelConfig, cell_m: float,
                  rock: np.ndarray | None = None) -> dict:
    """Per-pixel targets of :class:`demseis.labels.traces.Traces`.

    The fault mask is the cells whose centre lies within ``thickness_cells / 2`` of a trace
    cell (the trace itself for t <= 1; t = 0 is treated as 1); ``fault_id``, ``slip_m``,
    ``dip_deg`` and ``sense`` are those of the nearest trace cell, on mask cells. The damage
    zone (class 1) is the cells within half the local damage width of the trace, the width
    being ``min(damage_width_ratio * slip, damage_max_width_m)`` of the nearest trace cell;
    class 2, the fault core, is the fault mask and the shear band's core around the traces
    (``traces.core``: the band's width at half maximum, with ``core_halfwidth_cells`` > 0).
    With a band core the damage zone is measured from the nearest cell of the trace and band
    core instead of the trace (with the width of that cell's nearest trace cell), so that it
    surrounds the fault core.
    """
    trace = np.asarray(traces.trace, dtype=bool)
    shape = trace.shape
    if not trace.any():
        z8 = np.zeros(shape, dtype=np.uint8)
        zf = np.zeros(shape, dtype=np.float32)
        return {"fault": z8, "damage": z8.copy(), "fault_id": np.zeros(shape, np.int16),
                "slip_m": zf, "dip_deg": zf.copy(), "sense": z8.copy()}
    dist, idx = ndimage.distance_transform_edt(~trace, return_indices=True)
    near_r, near_c = idx[0], idx[1]
    fault = dist <= max(0.5 * float(config.thickness_cells), 0.5)
    slip_near = traces.slip_m[near_r, near_c].astype(np.float64)
    width_m = np.minimum(config.damage_width_ratio * slip_near, config.damage_max_width_m)
    band = traces.core
    if band is None:
        damage = dist <= 0.5 * width_m / float(cell_m)
        core = fault.copy()
    else:
        # the damage zone surrounds the fault core: its half-width is measured from the
        # nearest core cell, with the width of that cell's nearest trace cell
        band = np.asarray(band, dtype=bool)  # the trace cells and the band's core
        dist_b, idx_b = ndimage.distance_transform_edt(~band, return_indices=True)
        damage = dist_b <= 0.5 * width_m[idx_b[0], idx_b[1]] / float(cell_m)
        core = fault | band
    if rock is not None:
        fault &= rock
        core &= rock
        damage &= rock
    dmg = damage.astype(np.uint8)
    dmg[core] = 2

    def on_fault(a: np.ndarray, dtype) -> np.ndarray:
        return np.where(fault, a[near_r, near_c], 0).astype(dtype)

    return {"fault": fault.astype(np.uint8), "damage": dmg,
            "fault_id": on_fault(traces.instance, np.int16),
            "slip_m": on_fault(traces.slip_m, np.float32),
            "dip_deg": on_fault(traces.dip_deg, np.float32),
            "sense": on_fault(traces.sense, np.uint8)}


def sample_facts(maps: dict) -> dict:
    """Per-sample facts of a label dict: ``has_fault`` (0/1), ``n_faults``, ``max_slip_m``."""
    fid = np.asarray(maps["fault_id"])
    ids = np.unique(fid[fid > 0])
    slip = np.asarray(maps["slip_m"])
    return {"has_fault": int(np.asarray(maps["fault"]).any()), "n_faults": int(ids.size),
            "max_slip_m": float(slip.max()) if slip.size else 0.0}


def rasterise_strain(xy: np.ndarray, radius: np.ndarray, values: np.ndarray,
                     grid) -> tuple[np.ndarray, np.ndarray]:
    """Per-element values on ``grid``, gaps filled, and the owning element of every cell.

    Parameters
    ----------
    xy : (n, 2) centres (m, y up); radius : (n,) radii (m); values : (n,) float, NaN = unknown.
    grid : target grid.

    Returns
    -------
    field : (nz, nx) float64. Mean of the known values of the disks containing the cell centre
        (:func:`demseis.seismic.raster.rasterise`); where there is none, the value of the
        cell's power-diagram element if known, else of the nearest filled cell; 0 where no
        element reaches the cell (outside the rock).
    owner : (nz, nx) int64 power-diagram element of each cell (-1 outside the rock).
    """
    from demseis.seismic import rasterise

    xy = np.asarray(xy, dtype=np.float64)
    radius = np.asarray(radius, dtype=np.float64)
    values = np.asarray(values, dtype=np.float64)
    known = np.isfinite(values)
    owner = np.empty(grid.shape, dtype=np.int64)
    _kernels.power_nearest(np.ascontiguousarray(xy[:, 0]), np.ascontiguousarray(xy[:, 1]),
                           radius, ROCK_REACH, float(grid.x0_m), float(grid.top_m),
                           float(grid.cell_m), grid.nz, grid.nx, owner)
    rock = owner >= 0
    if known.any():
        field, _ = rasterise(xy[known], radius[known], values[known], grid)
    else:
        field = np.full(grid.shape, np.nan)
    gap = ~np.isfinite(field) & rock
    from_owner = values[owner[gap]]
    field[gap] = from_owner
    field[~rock] = np.nan
    missing = ~np.isfinite(field) & rock
    if missing.any():
        have = np.isfinite(field)
        if have.any():
            idx = ndimage.distance_transform_edt(~have, return_distances=False,
                                                 return_indices=True)
            field[missing] = field[idx[0][missing], idx[1][missing]]
        else:
            field[missing] = 0.0
    field[~rock] = 0.0
    return field, owner


def fault_mask(strain: np.ndarray, config: LabelConfig | None = None,
               rock: np.ndarray | None = None, smoothed: np.ndarray | None = None) -> np.ndarray:
    """Binary fault mask from a rasterised strain field.

    Parameters
    ----------
    strain : (nz, nx) float gamma_max on the grid.
    config : thresholds, smoothing, minimum component size and thickness control.
    rock : (nz, nx) bool, cells inside the rock (default: all); the mask is 0 elsewhere.
    smoothed : the strain already smoothed with ``config.smooth_sigma_cells`` (optional).

    Returns
    -------
    (nz, nx) uint8, 1 = fault.
    """
    cfg = (config or LabelConfig()).validate()
    mask = _above(strain, cfg.fault_threshold, cfg, rock, smoothed)
    if cfg.thickness_cells > 0:
        mask = thin_and_dilate(mask, cfg.thickness_cells, cfg.centreline_window_cells,
                               cfg.centreline_window_cells)
        if rock is not None:
            mask &= rock
    return mask.astype(np.uint8)


def damage_map(strain: np.ndarray, fault: np.ndarray, config: LabelConfig | None = None,
               rock: np.ndarray | None = None, smoothed: np.ndarray | None = None) -> np.ndarray:
    """Three-class map: 0 background, 1 damage zone (strain >= damage_threshold), 2 fault core.

    Parameters
    ----------
    strain : (nz, nx) gamma_max on the grid.
    fault : (nz, nx) fault mask (nonzero = fault core), e.g. from :func:`fault_mask`.
    config : ``damage_threshold``, ``smooth_sigma_cells``, ``min_component_cells``.
    rock : (nz, nx) bool cells inside the rock (default: all).
    smoothed : the strain already smoothed with ``config.smooth_sigma_cells`` (optional).
    """
    cfg = (config or LabelConfig()).validate()
    dz = _above(strain, cfg.damage_threshold, cfg, rock, smoothed)
    out = dz.astype(np.uint8)
    out[np.asarray(fault) != 0] = 2
    return out


def _above(strain: np.ndarray, threshold: float, cfg: LabelConfig, rock: np.ndarray | None,
           smoothed: np.ndarray | None) -> np.ndarray:
    """Cells of the (smoothed) strain at or above ``threshold``, inside the rock, without
    components smaller than ``cfg.min_component_cells``: the start of both label maps."""
    s = _smoothed(strain, cfg.smooth_sigma_cells, rock) if smoothed is None else smoothed
    mask = s >= threshold
    if rock is not None:
        mask &= rock
    return remove_small_components(mask, cfg.min_component_cells)


def _smoothed(strain: np.ndarray, sigma: float, rock: np.ndarray | None) -> np.ndarray:
    s = np.asarray(strain, dtype=np.float64)
    if sigma <= 0:
        return s
    if rock is None:
        return ndimage.gaussian_filter(s, sigma, mode="nearest")
    # normalised convolution: smooth only over rock cells so the free surface does not dilute
    w = rock.astype(np.float64)
    num = ndimage.gaussian_filter(np.where(rock, s, 0.0), sigma, mode="nearest")
    den = ndimage.gaussian_filter(w, sigma, mode="nearest")
    with np.errstate(invalid="ignore", divide="ignore"):
        out = np.where(den > 1e-6, num / den, 0.0)
    return out


def remove_small_components(mask: np.ndarray, min_cells: int) -> np.ndarray:
    """Drop 8-connected components of ``mask`` with fewer than ``min_cells`` cells."""
    mask = np.asarray(mask, dtype=bool)
    if min_cells <= 1 or not mask.any():
        return mask.copy()
    lab, nlab = ndimage.label(mask, structure=_EIGHT)
    sizes = np.bincount(lab.ravel(), minlength=nlab + 1)
    keep = sizes >= min_cells
    keep[0] = False
    return keep[lab]


def thin_and_dilate(mask: np.ndarray, thickness_cells: float, window_cells: int = 1,
                    prune_cells: int = 0) -> np.ndarray:
    """Thin ``mask`` to a centre line, then keep the cells within ``thickness_cells / 2`` of it.

    Steps: Guo-Hall skeleton; spurs of at most ``prune_cells`` cells (end point to junction)
    removed; branch coordinates moving-averaged over ``window_cells`` cells along the branch
    (see :mod:`demseis.labels.centreline`); band of cells whose centre lies within
    ``thickness_cells / 2`` of the centre line (``thickness_cells <= 1``: the line itself).
    The mask is extended by edge replication first so that bands leaving through the grid edge keep
    their centre line up to the edge (thinning would otherwise shorten them by half a width).

    Parameters
    ----------
    mask : (nz, nx) bool.
    thickness_cells : target thickness t (cells, perpendicular to the band).
    window_cells : along-line smoothing length (cells), 1 = none.
    prune_cells : longest spur removed (cells), 0 = none.

    Returns
    -------
    (nz, nx) bool.
    """
    from demseis.labels.centreline import prune_spurs, smooth_skeleton

    mask = np.asarray(mask, dtype=bool)
    if not mask.any():
        return mask.copy()
    # the margin must exceed the half-width of the widest band reaching the edge
    dist = ndimage.distance_transform_edt(mask)
    pad = int(np.ceil(dist.max())) + 2 + int(window_cells) // 2
    padded = np.pad(mask, pad, mode="edge")
    # holes enclosed by the band (a low-strain grain inside a shear band) would become loops of
    # the skeleton; fill those up to window_cells^2 / 2 cells
    padded = fill_small_holes(padded, max(int(window_cells) ** 2 // 2, 8))
    skel = _skeleton(padded)
    if prune_cells > 0:
        skel = prune_spurs(skel, int(prune_cells))
    if window_cells > 1:
        skel = smooth_skeleton(skel, int(window_cells))
    if thickness_cells > 1.0 and skel.any():
        skel = ndimage.distance_transform_edt(~skel) <= 0.5 * thickness_cells
    return skel[pad:-pad, pad:-pad]


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


def _skeleton(mask: np.ndarray) -> np.ndarray:
    return skeletonize(mask)


def fill_small_holes(mask: np.ndarray, max_cells: int) -> np.ndarray:
    """Fill the holes of ``mask`` (4-connected background enclosed by it) of at most
    ``max_cells`` cells."""
    mask = np.asarray(mask, dtype=bool)
    holes = ndimage.binary_fill_holes(mask) & ~mask
    if not holes.any():
        return mask.copy()
    lab, nlab = ndimage.label(holes)
    sizes = np.bincount(lab.ravel(), minlength=nlab + 1)
    small = sizes <= max_cells
    small[0] = False
    return mask | small[lab]


def mask_thickness_cells(mask: np.ndarray) -> float:
    """Mean thickness of a banded mask in cells: area / centre-line length.

    The centre line is the Guo-Hall skeleton; its length sums the links between 8-connected
    skeleton cells (1 for side neighbours, sqrt 2 for diagonal ones, each link once). Returns
    NaN for an empty mask.
    """
    mask = np.asarray(mask, dtype=bool)
    if not mask.any():
        return float("nan")
    dist = ndimage.distance_transform_edt(mask)
    pad = int(np.ceil(dist.max())) + 2
    skel = _skeleton(np.pad(mask, pad, mode="edge"))[pad:-pad, pad:-pad]
    length = skeleton_length_cells(skel)
    if length <= 0:
        return float(mask.sum())
    return float(mask.sum()) / length


def skeleton_length_cells(skel: np.ndarray) -> float:
    """Length (cells) of a one-cell-wide skeleton: sum of its 8-neighbour links, each once.

    Side links are counted only where they do not close a diagonal short-cut (a 2x2 L of
    three cells counts two side links, not a side and a diagonal).
    """
    s = np.asarray(skel, dtype=bool)
    side = (s[:, 1:] & s[:, :-1]).sum() + (s[1:, :] & s[:-1, :]).sum()
    # diagonals that are not bridged by a side path through a third cell
    d1 = s[1:, 1:] & s[:-1, :-1] & ~s[:-1, 1:] & ~s[1:, :-1]
    d2 = s[1:, :-1] & s[:-1, 1:] & ~s[:-1, :-1] & ~s[1:, 1:]
    return float(side) + np.sqrt(2.0) * float(d1.sum() + d2.sum())
