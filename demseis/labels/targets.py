"""Per-pixel fault targets: the fault mask, damage classes and fault attributes of a section.

:func:`trace_targets` draws them from the slip traces of the ``"slip_trace"`` method
(:class:`~demseis.labels.traces.Traces`); the ``"strain_band"`` method makes its own
(:mod:`demseis.labels.strain_band`). Dtypes are those :mod:`demseis.schema` declares.
"""

from __future__ import annotations

import numpy as np
from scipy import ndimage

from demseis.labels.config import LabelConfig
from demseis.schema import sample_array

#: attributes of the nearest trace cell carried to the fault cells: fields of
#: :class:`~demseis.labels.traces.Traces` and labels of the same names
TRACE_ATTRIBUTES = ("slip_m", "dip_deg", "sense")

#: ``damage`` class of the fault core (1: damage zone, 0: background)
DAMAGE_CORE = 2


def no_trace_attributes(shape: tuple[int, int]) -> dict:
    """The ``TRACE_ATTRIBUTES`` of a section with no trace: every one 0, in its schema dtype."""
    return {n: np.zeros(shape, dtype=_dtype(n)) for n in TRACE_ATTRIBUTES}


def _dtype(name: str) -> np.dtype:
    return sample_array(name).np_dtype


def trace_targets(traces, config: LabelConfig, cell_m: float,
                  rock: np.ndarray | None = None) -> dict:
    """Per-pixel targets of :class:`~demseis.labels.traces.Traces`.

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
    if trace.any():
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
    else:  # no fault: every target 0
        near_r = near_c = np.zeros(shape, dtype=np.intp)
        fault, damage, core = (np.zeros(shape, dtype=bool) for _ in range(3))
    if rock is not None:
        fault &= rock
        core &= rock
        damage &= rock
    dmg = damage.astype(_dtype("damage"))
    dmg[core] = DAMAGE_CORE

    def on_fault(name: str, a: np.ndarray) -> np.ndarray:
        return np.where(fault, a[near_r, near_c], 0).astype(_dtype(name))

    return {"fault": fault.astype(_dtype("fault")), "damage": dmg,
            "fault_id": on_fault("fault_id", traces.instance),
            **{n: on_fault(n, getattr(traces, n)) for n in TRACE_ATTRIBUTES}}
