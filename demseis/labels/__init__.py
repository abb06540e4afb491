"""demseis.labels: strain from element displacements; fault, damage-zone, strain and layer labels.

Scoring predictions against labels lives in :mod:`demseis.evaluation`.

Public API (see docs/labels.md)::

    res = element_strain(reference_xy, current_xy, radii)   # res.gamma_max, .volumetric, .valid
    hist = strain_history(snapshots, config)                 # per snapshot: total, cumulative
    disp = displacement_history(snapshots)                   # per snapshot: (displacement, birth)
    maps = label_maps(snapshot, hist[k], grid, config, displacement=disp[k])
    # fault, fault_id, slip_m, dip_deg, sense, damage, strain, layer
    facts = sample_facts(maps)                               # has_fault, n_faults, max_slip_m
"""

from demseis.labels.config import LabelConfig
from demseis.labels.maps import (
    damage_map,
    fault_mask,
    label_maps,
    mask_thickness_cells,
    rasterise_strain,
    sample_facts,
    thin_and_dilate,
)
from demseis.labels.strain import (
    StrainResult,
    StrainState,
    element_strain,
    neighbour_lists,
    strain_history,
)
from demseis.labels.traces import Traces, displacement_history, slip_traces

__all__ = [
    "LabelConfig",
    "StrainResult",
    "StrainState",
    "Traces",
    "damage_map",
    "displacement_history",
    "element_strain",
    "fault_mask",
    "label_maps",
    "mask_thickness_cells",
    "neighbour_lists",
    "rasterise_strain",
    "sample_facts",
    "slip_traces",
    "strain_history",
    "thin_and_dilate",
]
