"""demseis.labels: strain from element displacements; fault, damage-zone, strain and layer labels.

Scoring predictions against labels lives in :mod:`demseis.evaluation`.

Public API (see docs/labels.md)::

    res = element_strain(reference_xy, current_xy, radii)   # res.gamma_max, .volumetric, .valid
    hist = strain_history(snapshots, config)                 # per snapshot: total, cumulative
    maps = label_maps(snapshot, hist[k], grid, config)       # fault, damage, strain, layer
"""

from demseis.labels.config import LabelConfig
from demseis.labels.maps import (
    damage_map,
    fault_mask,
    label_maps,
    mask_thickness_cells,
    rasterise_strain,
    thin_and_dilate,
)
from demseis.labels.strain import (
    StrainResult,
    StrainState,
    element_strain,
    neighbour_lists,
    strain_history,
)

__all__ = [
    "LabelConfig",
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
