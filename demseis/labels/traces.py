"""Slip surfaces as traced objects: crest of localised shear, linked into faults, kept where they slip.

A fault label should mark where the section shows an offset. The continuum strain of the
element displacements (:mod:`demseis.labels.strain`) is high in a band around every slip
surface, but also where the rock only bends (a monocline above a blind tip) and in the broad
wedge of a large-throw fault. Thresholding and thinning that band (the ``"strain_band"``
method, :mod:`demseis.labels.strain_band`) turns such blobs into networks with loops and
horizontal "rungs". Here instead (the ``"slip_trace"`` method, :func:`slip_traces`):

1. **Crest** (:mod:`demseis.labels.crest`). The rasterised strain is smoothed
   (``ridge_sigma_cells``) and its Hessian gives the local band normal (eigenvector of the
   most negative curvature). Non-maximum suppression keeps the cells that are not below their
   neighbours one cell away on both sides along that normal (a ridge, Canny-style) where the
   strain is at least ``ridge_threshold``; the crest is thinned to one cell (Guo-Hall),
   components shorter than ``min_trace_cells`` dropped, short spurs pruned and every branch
   moving-averaged along its length (``centreline_window_cells``), as for the strain-band
   centre line.
2. **Slip** (:mod:`demseis.labels.slip`). At every crest cell the trace's local direction is
   fitted over a 9 x 9 window (:mod:`demseis.labels.direction`), and the element displacement
   (rasterised like the strain) is sampled ``k`` cells away on both sides along the normal,
   k = 2..``slip_offset_cells``; the largest |u(+k) - u(-k)| is the displacement jump (slip,
   m), averaged along the trace over 5 x 5 cells. A crest cell is fault only where that slip
   is at least ``min_slip_m`` and its dip at least ``min_dip_deg``.
2b. **Strands.** A DEM shear zone slips on several grain boundaries side by side; steps 1-2
   are repeated on the displacement smoothed by only ``strand_sigma_cells``: crests of that
   field more than STRAND_SEPARATION_CELLS from a trace, spanning STRAND_SPAN_CELLS or more,
   whose jump over 1-2 cells is at least ``min_slip_m`` and persists 3-4 cells out, are traces
   too (strands); the dip test is repeated on the union, and a strand within
   STRAND_ZONE_CELLS of a trace takes its fault id.
3. **Faults** (:mod:`demseis.labels.linking`). The kept cells are linked into traces: the
   skeleton is cut at its junctions, and at each junction the two branches that continue each
   other (directions within ``link_angle_deg`` of a straight line) are joined; the others
   (splays, antithetics, the second of two crossing faults) start their own fault. Instance
   ids are 1.. by size.
4. **Attributes.** Dip (degrees from horizontal, from the fitted direction), sense of slip (1
   normal: the upper block moved down the fault relative to the lower; 2 reverse), slip.
5. **Fault core** (:mod:`demseis.labels.core`). Around each trace, the shear band's width at
   half maximum of the shear smoothed by CORE_SIGMA_CELLS, up to ``core_halfwidth_cells``
   either side, where the band is at least 5 cells wide (:func:`~demseis.labels.core.band_core`):
   ``damage`` class 2 in the targets (:mod:`demseis.labels.targets`). A sharp slip surface's
   core is its trace; the ``fault`` mask stays the trace.

All of it is on the grid of the seismic (row 0 at the top, square cells).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import ndimage

from demseis.errors import InputError
from demseis.labels.config import LabelConfig
from demseis.labels.core import CORE_SIGMA_CELLS, band_core
from demseis.labels.crest import centre_on_jump, crest_cells, project_on_local_line, shear_field
from demseis.labels.direction import dip_of, local_direction
from demseis.labels.linking import LINK_GAP_CELLS, strand_instances, trace_instances
from demseis.labels.masks import long_pieces, remove_small_components
from demseis.labels.slip import displacement_jump, slipping_cells


#: sense-of-slip codes of the ``sense`` target
SENSE_NONE, SENSE_NORMAL, SENSE_REVERSE = 0, 1, 2

#: strands (the finer crest search) closer than this (cells) to a trace are that trace's crest
STRAND_SEPARATION_CELLS = 2.0

#: strands (and their crest pieces) spanning fewer cells (bounding-box diagonal) are dropped
STRAND_SPAN_CELLS = 11.0


@dataclass(frozen=True)
class Traces:
    """Fault traces of one section (all (nz, nx), one-cell-wide lines).

    Attributes
    ----------
    trace : bool, labelled trace cells (slip >= min_slip_m).
    instance : int32, fault id 1..n on trace cells, 0 elsewhere.
    slip_m : float32, displacement jump across the trace (m), 0 off the trace.
    dip_deg : float32, dip of the trace (degrees from horizontal, 0..90), 0 off the trace.
    sense : uint8, 1 normal / 2 reverse on trace cells, 0 elsewhere.
    crest : bool, every crest cell before the slip test (for diagnostics).
    crest_slip_m : float32, slip measured on every crest cell (NaN where not measurable).
    core : bool or None, the shear band's core around the traces (the trace cells and the
        band's width at half maximum of the fine shear around them: :func:`~demseis.labels.core.band_core`);
        None when ``core_halfwidth_cells`` is 0.
    """

    trace: np.ndarray
    instance: np.ndarray
    slip_m: np.ndarray
    dip_deg: np.ndarray
    sense: np.ndarray
    crest: np.ndarray
    crest_slip_m: np.ndarray
    core: np.ndarray | None = None

    @property
    def n_faults(self) -> int:
        """Number of fault instances."""
        return int(self.instance.max()) if self.instance.size else 0


def slip_traces(strain: np.ndarray, disp_x_m: np.ndarray, disp_y_m: np.ndarray,
                rock: np.ndarray, cell_m: float, config: LabelConfig | None = None,
                cohort: np.ndarray | None = None) -> Traces:
    """Fault traces of one section from its rasterised strain and displacement.

    Parameters
    ----------
    strain : (nz, nx) gamma_max on the grid (0 outside the rock).
    disp_x_m, disp_y_m : (nz, nx) element displacement since first appearance (m, x right,
        y up), rasterised like the strain.
    rock : (nz, nx) bool, cells inside the rock.
    cell_m : grid cell size (m); ``min_slip_m`` defaults to one cell.
    config : :class:`LabelConfig` (defaults if None).
    cohort : (nz, nx) int, first-appearance snapshot of each cell's element (None: one cohort).

    Returns
    -------
    :class:`Traces`.
    """
    cfg = (config or LabelConfig()).validate()
    strain = np.asarray(strain, dtype=np.float64)
    rock = np.asarray(rock, dtype=bool)
    shape = strain.shape
    for name, a in (("disp_x_m", disp_x_m), ("disp_y_m", disp_y_m), ("rock", rock)):
        if np.shape(a) != shape:
            raise InputError(f"{name} has shape {np.shape(a)}; expected {shape} like strain")
    min_slip = cfg.min_slip_for(cell_m)
    # voids inside the assembly (an opened gap along a fault) are rock for the tracing
    solid = rock
    rock = ndimage.binary_fill_holes(rock)
    if cohort is not None:
        cohort = np.asarray(cohort)
        idx = ndimage.distance_transform_edt(cohort < 0, return_distances=False,
                                             return_indices=True)
        cohort = np.where(rock, cohort[idx[0], idx[1]], -1)
    field = shear_field(disp_x_m, disp_y_m, rock, cell_m, cfg.ridge_sigma_cells, cohort)
    crest = crest_cells(field, rock, cfg)
    if crest.any():
        shift = centre_on_jump(crest, disp_x_m, disp_y_m, rock, cfg.slip_offset_cells)
        crest = project_on_local_line(crest, shift, int(cfg.centreline_window_cells)) & rock
        crest = remove_small_components(crest, cfg.min_trace_cells)
    crest_slip = np.full(shape, np.nan, dtype=np.float32)
    trace, slip = slipping_cells(crest, disp_x_m, disp_y_m, rock, cohort, 2, cfg.slip_offset_cells,
                            min_slip, cfg)
    crest_slip[crest] = slip[crest]
    strand = np.zeros(shape, dtype=bool)
    fine = None
    if cfg.strand_sigma_cells > 0 and trace.any():
        # the other slip surfaces of a wide shear zone: crests of the finer field more than
        # STRAND_SEPARATION_CELLS from a trace (the trace's own crest is there too)
        fine = shear_field(disp_x_m, disp_y_m, rock, cell_m, cfg.strand_sigma_cells, cohort)
        fcrest = crest_cells(fine, rock, cfg)
        fcrest &= ndimage.distance_transform_edt(~trace) > STRAND_SEPARATION_CELLS
        fcrest = long_pieces(fcrest, STRAND_SPAN_CELLS)
        f_dir = local_direction(fcrest)
        strand, fslip = slipping_cells(fcrest, disp_x_m, disp_y_m, rock, cohort, 1, 2, min_slip, cfg,
                                  f_dir)
        # the two sides of a surface are blocks: the jump persists 3-4 cells out (around a
        # grain that moved against all its neighbours it does not)
        far, _ = slipping_cells(fcrest, disp_x_m, disp_y_m, rock, cohort, 3, 4, min_slip, cfg, f_dir)
        strand &= far
        strand = long_pieces(strand, STRAND_SPAN_CELLS)
        crest_slip[fcrest] = fslip[fcrest]
        crest = crest | fcrest
        slip = np.where(strand, fslip, slip)
        trace = trace | strand
        for _ in range(3 if cfg.min_dip_deg > 0 else 0):
            # the direction of a strand next to a trace is the pair's: test the dip again, of
            # what is labelled (trace_targets leaves out the voids)
            shown = trace & solid
            t_r, t_c = local_direction(shown)
            flat = shown & (dip_of(t_r, t_c) < cfg.min_dip_deg)
            if not flat.any():
                break
            trace &= ~flat
        trace = remove_small_components(trace, cfg.min_trace_cells)
        strand &= trace
    if not trace.any():
        return Traces(trace=np.zeros(shape, bool), instance=np.zeros(shape, np.int32),
                      slip_m=np.zeros(shape, np.float32), dip_deg=np.zeros(shape, np.float32),
                      sense=np.zeros(shape, np.uint8), crest=crest, crest_slip_m=crest_slip)
    inst = trace_instances(trace & ~strand, cfg.link_angle_deg, LINK_GAP_CELLS)
    if strand.any():
        inst = strand_instances(inst, strand, cfg.link_angle_deg)
    t_r, t_c = local_direction(trace)
    dip = dip_of(t_r, t_c)
    # sense: jump (upper side minus lower side) against the down-dip direction
    jump = displacement_jump(trace & ~strand, t_r, t_c, disp_x_m, disp_y_m, rock, cfg.slip_offset_cells,
                 cohort)
    if strand.any():
        js = displacement_jump(strand, t_r, t_c, disp_x_m, disp_y_m, rock, 2, cohort, k_min=1)
        jump = np.where(strand[..., None], js, jump)
    down_r, down_c = np.abs(t_r), np.where(t_r >= 0, t_c, -t_c)
    along = jump[..., 1] * down_r + jump[..., 2] * down_c
    sense = np.where(along >= 0, SENSE_NORMAL, SENSE_REVERSE).astype(np.uint8)
    z = ~trace
    slip_out = np.where(trace, slip, 0.0).astype(np.float32)
    dip_out = np.where(z, 0.0, dip).astype(np.float32)
    sense[z] = SENSE_NONE
    core = None
    if cfg.core_halfwidth_cells > 0:
        if fine is None or cfg.strand_sigma_cells != CORE_SIGMA_CELLS:
            fine = shear_field(disp_x_m, disp_y_m, rock, cell_m, CORE_SIGMA_CELLS, cohort)
        core = band_core(trace, t_r, t_c, fine, solid, cohort, int(cfg.core_halfwidth_cells))
    return Traces(trace=trace, instance=inst, slip_m=slip_out, dip_deg=dip_out, sense=sense,
                  crest=crest, crest_slip_m=crest_slip, core=core)
