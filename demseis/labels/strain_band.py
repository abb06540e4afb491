"""Fault labels of the ``"strain_band"`` method: thresholds of the rasterised strain.

The alternative to the default ``"slip_trace"`` method (:mod:`demseis.labels.traces`), on the
strain that :func:`demseis.labels.raster.rasterise_strain` puts on the grid:

1. optional Gaussian smoothing (``smooth_sigma_cells``) of the strain used for thresholding,
   normalised over the rock cells.
2. fault = strain >= ``fault_threshold``; 8-connected components smaller than
   ``min_component_cells`` dropped; with ``thickness_cells`` = t >= 1 small holes are filled,
   the mask is thinned to a one-cell skeleton (Guo-Hall), short side branches are pruned, each
   branch is moving-averaged along its length (``centreline_window_cells``) and the result is
   re-grown to the cells within t/2 of that centre line (:func:`thin_and_dilate`).
3. damage = 0 background, 1 strain >= ``damage_threshold`` (small components dropped),
   2 fault core (the fault mask).
4. fault ids number the mask's 8-connected components; slip, dip and sense are 0.
"""

from __future__ import annotations

import numpy as np
from scipy import ndimage

from demseis.labels.centreline import prune_spurs, smooth_skeleton
from demseis.labels.config import LabelConfig
from demseis.labels.masks import EIGHT, fill_small_holes, remove_small_components, skeletonize
from demseis.labels.targets import no_trace_attributes
from demseis.schema import sample_array


def strain_band_targets(strain: np.ndarray, rock: np.ndarray, config: LabelConfig) -> dict:
    """The fault targets of the ``"strain_band"`` method (steps 1-4 of the module docstring).

    Parameters
    ----------
    strain : (nz, nx) rasterised gamma_max. rock : (nz, nx) bool cells inside the rock.
    config : a validated :class:`LabelConfig`.

    Returns
    -------
    dict of (nz, nx) arrays: ``fault`` and ``damage`` uint8, ``fault_id`` the 8-connected
    components of the fault mask; the ``TRACE_ATTRIBUTES`` of :mod:`demseis.labels.targets`
    (slip, dip, sense) 0.
    """
    smoothed = _smoothed(strain, config.smooth_sigma_cells, rock)
    fault = fault_mask(strain, config, rock=rock, smoothed=smoothed)
    damage = damage_map(strain, fault, config, rock=rock, smoothed=smoothed)
    fid, _ = ndimage.label(fault, structure=EIGHT)
    return {"fault": fault, "damage": damage,
            "fault_id": fid.astype(sample_array("fault_id").np_dtype),
            **no_trace_attributes(strain.shape)}


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
    skel = skeletonize(padded)
    if prune_cells > 0:
        skel = prune_spurs(skel, int(prune_cells))
    if window_cells > 1:
        skel = smooth_skeleton(skel, int(window_cells))
    if thickness_cells > 1.0 and skel.any():
        skel = ndimage.distance_transform_edt(~skel) <= 0.5 * thickness_cells
    return skel[pad:-pad, pad:-pad]
