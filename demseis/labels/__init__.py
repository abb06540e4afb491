"""demseis.labels: strain from element displacements; fault, damage-zone, strain and layer labels.

Public API (see docs/labels.md)::

    res = element_strain(reference_xy, current_xy, radii)   # res.gamma_max, .volumetric, .valid
    hist = strain_history(snapshots, config)                 # per snapshot: total, cumulative
    maps = label_maps(snapshot, hist[k], grid, config)       # fault, damage, strain, layer
    result = score(pred, truth, threshold=0.5, tolerance_px=0)  # precision, recall, f1, iou
"""

from demseis.labels.baseline import SemblanceBaseline
from demseis.labels.config import LabelConfig
from demseis.labels.maps import (
    damage_map,
    fault_mask,
    label_maps,
    mask_thickness_cells,
    rasterise_strain,
    thin_and_dilate,
)
from demseis.labels.scoring import ScoreResult, score
from demseis.labels.strain import (
    StrainResult,
    StrainState,
    element_strain,
    neighbour_lists,
    strain_history,
)

__all__ = [
    "LabelConfig",
    "ScoreResult",
    "SemblanceBaseline",
    "score",
    "StrainResult",
    "StrainState",
    "damage_map",
    "element_strain",
    "fault_mask",
    "label_maps",
    "mask_thickness_cells",
    "neighbour_lists",
    "rasterise_strain",
    "strain_history",
    "thin_and_dilate",
]
