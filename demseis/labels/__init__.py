"""demseis.labels: strain from element displacements; fault, damage-zone, strain and layer labels.

Scoring predictions against labels lives in :mod:`demseis.evaluation`. Code outside this
package imports from here, not from its modules.

Public API (see docs/labels.md)::

    res = element_strain(reference_xy, current_xy, radii)   # res.gamma_max, .volumetric, .valid
    hist = strain_history(snapshots, config)                 # per snapshot: total, cumulative
    disp = displacement_history(snapshots)                   # per snapshot: (displacement, birth)
    maps = label_maps(snapshot, hist[k], grid, config, displacement=disp[k])
    # fault, damage, strain, layer, fault_id, slip_m, dip_deg, sense (demseis.schema's
    # engine labels)
    facts = sample_facts(maps)                               # has_fault, n_faults, max_slip_m
    picked = pick_faults(maps, throw_samples(maps["slip_m"], maps["dip_deg"], cell_m=10.0))
    # the fault arrays redrawn as an interpreter picks: one smooth 1-pixel line per fault

Shared Numba helper: :func:`build_cell_list` (a cell list of points, callable from other
stages' kernels).

Shape measures of label masks (diagnostics): :func:`loop_count`, :func:`rung_fraction`,
:func:`skeleton_length_cells`, :func:`mask_thickness_cells`.

Modules: ``maps`` (label_maps), ``raster`` (elements to grid), ``traces`` (the
``"slip_trace"`` method: ``crest``, ``slip``, ``linking``, ``core``, with ``direction``),
``targets`` (per-pixel targets of traces), ``picks`` (the picked
fault target on the output grid), ``strain_band`` (the ``"strain_band"`` method),
``masks`` and ``centreline`` (mask tools), ``measures``, ``strain``, ``config``, ``_kernels``.
"""

from demseis.labels._kernels import build_cell_list
from demseis.labels.config import LabelConfig
from demseis.labels.maps import label_maps, sample_facts
from demseis.labels.measures import (
    loop_count,
    mask_thickness_cells,
    rung_fraction,
    skeleton_length_cells,
)
from demseis.labels.picks import PickConfig, pick_faults, throw_samples
from demseis.labels.raster import rasterise_strain
from demseis.labels.slip import displacement_history
from demseis.labels.strain import (
    StrainResult,
    StrainState,
    element_strain,
    neighbour_lists,
    strain_history,
)
from demseis.labels.strain_band import damage_map, fault_mask, thin_and_dilate
from demseis.labels.traces import Traces, slip_traces

__all__ = [
    "LabelConfig",
    "PickConfig",
    "StrainResult",
    "StrainState",
    "Traces",
    "build_cell_list",
    "damage_map",
    "displacement_history",
    "element_strain",
    "fault_mask",
    "label_maps",
    "loop_count",
    "pick_faults",
    "mask_thickness_cells",
    "neighbour_lists",
    "rasterise_strain",
    "rung_fraction",
    "sample_facts",
    "skeleton_length_cells",
    "slip_traces",
    "strain_history",
    "thin_and_dilate",
    "throw_samples",
]
