"""Configuration of the labels stage (the ``[labels]`` table of a sweep config maps 1:1 onto it)."""

from __future__ import annotations

import math
import numbers
from dataclasses import dataclass, fields
from typing import Any

from demseis.errors import ConfigError, InputError
from demseis.labels.picks import PickConfig
from demseis.registry import FAULT_STYLES, LABEL_METHODS, Registry

STRAIN_MEASURES = ("total", "cumulative")
NEIGHBOUR_METHODS = ("radius", "knn")
THROW_SOURCES = ("slip", "offset")


@dataclass(frozen=True)
class LabelConfig:
    """How per-element strain becomes fault, damage-zone, strain and layer labels.

    All strains are dimensionless maximum shear strains
    ``gamma_max = (lambda1 - lambda2) / (2 sqrt(lambda1 lambda2))``; lengths in grid cells
    refer to the grid the labels are drawn on (10 m cells by default).

    Attributes
    ----------
    strain_measure : ``"total"`` (finite strain of each snapshot against the element's first
        appearance) or ``"cumulative"`` (sum of the incremental gamma_max between consecutive
        snapshots: it keeps strain that later deformation undid or rotated away; for steady
        simple shear it is a little below the total since gamma sqrt(1 + gamma^2/4) is convex).
        Which one drives the masks.
    neighbour_method : ``"radius"`` (neighbours j of i with ``|X_j - X_i| <= neighbour_radius_factor
        * (r_i + r_j)`` in the reference state) or ``"knn"`` (the ``neighbour_k`` nearest centres).
    neighbour_radius_factor : multiple of the summed radii, in (0.5, 5]. 1.0 catches touching
        disks only; the default 1.5 also takes the near part of the second shell (~10 neighbours).
    neighbour_k : number of nearest neighbours for ``"knn"``, in [3, 64].
    min_neighbours : elements with fewer neighbours are flagged invalid (strain NaN), in [2, 64].
    fault_threshold : gamma_max at or above which a cell is fault (core), in (0, 100].
    damage_threshold : gamma_max at or above which a cell is damage zone, in (0, fault_threshold].
    min_component_cells : 8-connected fault components with fewer cells (before thinning) are
        dropped; damage-zone components smaller than this are dropped too, in [0, 1e6].
    smooth_sigma_cells : Gaussian sigma (cells) applied to the rasterised strain before
        thresholding, in [0, 20]; 0 = none. The regression target is not smoothed.
    thickness_cells : fault-mask thickness control, in [0, 50]. 0 keeps the thresholded mask
        as it is; a value t >= 1 thins the mask to its one-cell skeleton and dilates it to a
        band of about t cells measured perpendicular to the fault (cells whose centre lies
        within t/2 of the skeleton).
    centreline_window_cells : with ``thickness_cells >= 1``: the skeleton's branches are
        moving-averaged over this many cells along their length (removes the element-scale
        stepping of the band edges; ~4 element diameters at 10 m cells) and side branches
        (end point to junction) up to this length are pruned, in [1, 201]; 1 = raw skeleton.
        Used by both fault methods.
    method : ``"slip_trace"`` (default: crest of localised shear kept where the displacement
        jumps across it, with instance ids, slip, dip and sense; :mod:`demseis.labels.traces`)
        or ``"strain_band"`` (the thresholded strain band's centre line, the labels of
        demseis <= 0.1; ``fault_threshold`` and ``damage_threshold`` apply only to it).
    min_slip_m : slip_trace: smallest displacement jump (m) across a crest cell for it to be
        fault, in (0, 1e4]; None (default) = one grid cell.
    ridge_threshold : slip_trace: smallest shear strain of a crest cell (engineering shear
        strain of the smoothed element displacement on the grid), in (0, 100].
    ridge_sigma_cells : slip_trace: Gaussian sigma (cells) of the displacement smoothing
        before its shear strain is taken, in [0, 20].
    strand_sigma_cells : slip_trace: Gaussian sigma (cells) of a second, finer crest search
        for the other slip surfaces of a wide shear zone (a granular band of the DEM slips on
        several particle boundaries side by side): crests of the displacement smoothed this
        little, more than 2 cells from a trace, whose jump over 1-2 cells either side is at
        least ``min_slip_m``, are traces too (strands); in [0, 20], 0 = none.
    slip_offset_cells : slip_trace: the jump is the largest of u(+k) - u(-k) along the normal
        for k = 2..this (cells), in [2, 20].
    min_trace_cells : slip_trace: crest / trace pieces with fewer cells are dropped, in [1, 1e6].
    link_angle_deg : slip_trace: branches meeting at a junction are one fault when their
        directions are within this angle of a straight line, in [0, 90].
    link_gap_cells : slip_trace: gaps of up to about this many cells between crest pieces are
        bridged (the crest is grown by a disk of this diameter before thinning), in [0, 50].
    min_dip_deg : slip_trace: crest cells whose direction (fitted over 9 x 9 cells) dips less
        than this are not fault, in [0, 90]: bedding-parallel slip (flexural slip, slumping
        at the free surface) is not what the labels are for; 0 keeps every dip.
    core_halfwidth_cells : slip_trace: the fault core (``damage`` class 2) is the fault mask
        and the core of the shear band around each trace (its width at half maximum of the
        finely smoothed shear, where the band is at least 5 cells wide), up to this many cells
        either side, in [0, 10]; 0 = the fault mask alone. The ``fault`` mask is not changed:
        a line learns better (docs/labels.md).
    damage_width_ratio : slip_trace: damage-zone total width as a multiple of the local slip,
        in [0, 100] (see docs/labels.md for the published data behind the default).
    damage_max_width_m : slip_trace: upper bound of the damage-zone total width (m), in [0, 1e5].
    fault_style : how the stored ``fault`` target is drawn: ``"picks"`` (default: as an
        interpreter picks, one smooth one-pixel polyline per fault on the output grid, only
        where its throw is at least ``min_throw_samples``; :mod:`demseis.labels.picks`) or
        ``"traces"`` (the method's traces taken to the output grid as they are, grown to
        ``thickness_cells``).
    min_throw_samples : picks: smallest throw, in output samples (time samples, or depth cells
        of a depth-domain store), where a fault is drawn, in [0, 100].
    pick_smooth_px : picks: Gaussian sigma (pixels along the fault) of the line, in [0, 20].
    pick_max_gap_px : picks: gaps of a fault's pixels up to this many pixels are bridged, in
        [0, 100].
    pick_min_length_px : picks: pieces of a line shorter than this (pixels along the fault) are
        dropped, in [1, 10000].
    throw_from : picks: what a pixel's throw is: ``"slip"`` (the fault's slip times the sine of
        its dip, at the output sampling) or ``"offset"`` (the offset of the reflectors across
        it, measured on the reference map at the output grid: what the section shows;
        :mod:`demseis.labels.offsets`; needs ``[output] rendering = "strata"``).
    offset_window_traces : picks with ``throw_from = "offset"``: the odd number of
        neighbouring trace pairs an offset is measured over, in [1, 9].
    offset_faults : picks with ``throw_from = "offset"``: visible offsets (at least
        ``min_throw_samples``, and 1) that no fault label explains become faults
        (:func:`demseis.labels.offsets.offset_faults`), so every offset the section shows
        has a label.
    offset_min_rows : with ``offset_faults``: the fewest output rows such a fault spans, in
        [2, 1000].
    """

    strain_measure: str = "cumulative"
    neighbour_method: str = "radius"
    neighbour_radius_factor: float = 1.5
    neighbour_k: int = 10
    min_neighbours: int = 3
    fault_threshold: float = 0.5
    damage_threshold: float = 0.3
    min_component_cells: int = 30
    smooth_sigma_cells: float = 1.0
    thickness_cells: float = 1.0
    centreline_window_cells: int = 15
    method: str = "slip_trace"
    min_slip_m: float | None = None
    ridge_threshold: float = 0.15
    ridge_sigma_cells: float = 2.0
    strand_sigma_cells: float = 0.7
    slip_offset_cells: int = 3
    min_trace_cells: int = 15
    link_angle_deg: float = 35.0
    link_gap_cells: int = 0
    min_dip_deg: float = 15.0
    core_halfwidth_cells: int = 5
    damage_width_ratio: float = 1.0
    damage_max_width_m: float = 200.0
    fault_style: str = "picks"
    min_throw_samples: float = 1.0
    pick_smooth_px: float = 2.0
    pick_max_gap_px: int = 4
    pick_min_length_px: int = 5
    throw_from: str = "slip"
    offset_window_traces: int = 3
    offset_faults: bool = False
    offset_min_rows: int = 10

    def validate(self) -> "LabelConfig":
        """Check every field; returns ``self`` so it chains.

        Raises
        ------
        demseis.errors.ConfigError
            Naming the field, its value and the allowed range or choices.
        """
        _choice("strain_measure", self.strain_measure, STRAIN_MEASURES)
        _choice("neighbour_method", self.neighbour_method, NEIGHBOUR_METHODS)
        _number("neighbour_radius_factor", self.neighbour_radius_factor, 0.5, 5.0, lo_open=True)
        _integer("neighbour_k", self.neighbour_k, 3, 64)
        _integer("min_neighbours", self.min_neighbours, 2, 64)
        if self.neighbour_method == "knn" and self.min_neighbours > self.neighbour_k:
            raise ConfigError(
                f"labels.min_neighbours = {self.min_neighbours} exceeds labels.neighbour_k = "
                f"{self.neighbour_k}; allowed: min_neighbours <= neighbour_k"
            )
        _number("fault_threshold", self.fault_threshold, 0.0, 100.0, lo_open=True)
        _number("damage_threshold", self.damage_threshold, 0.0, float(self.fault_threshold),
                lo_open=True)
        _integer("min_component_cells", self.min_component_cells, 0, 1_000_000)
        _number("smooth_sigma_cells", self.smooth_sigma_cells, 0.0, 20.0)
        _number("thickness_cells", self.thickness_cells, 0.0, 50.0)
        _integer("centreline_window_cells", self.centreline_window_cells, 1, 201)
        _choice("method", self.method, LABEL_METHODS)
        if self.min_slip_m is not None:
            _number("min_slip_m", self.min_slip_m, 0.0, 1e4, lo_open=True)
        _number("ridge_threshold", self.ridge_threshold, 0.0, 100.0, lo_open=True)
        _number("ridge_sigma_cells", self.ridge_sigma_cells, 0.0, 20.0)
        _number("strand_sigma_cells", self.strand_sigma_cells, 0.0, 20.0)
        _integer("slip_offset_cells", self.slip_offset_cells, 2, 20)
        _integer("min_trace_cells", self.min_trace_cells, 1, 1_000_000)
        _number("link_angle_deg", self.link_angle_deg, 0.0, 90.0)
        _integer("link_gap_cells", self.link_gap_cells, 0, 50)
        _number("min_dip_deg", self.min_dip_deg, 0.0, 90.0)
        _integer("core_halfwidth_cells", self.core_halfwidth_cells, 0, 10)
        _number("damage_width_ratio", self.damage_width_ratio, 0.0, 100.0)
        _number("damage_max_width_m", self.damage_max_width_m, 0.0, 1e5)
        _choice("fault_style", self.fault_style, FAULT_STYLES)
        _number("min_throw_samples", self.min_throw_samples, 0.0, 100.0)
        _number("pick_smooth_px", self.pick_smooth_px, 0.0, 20.0)
        _integer("pick_max_gap_px", self.pick_max_gap_px, 0, 100)
        _integer("pick_min_length_px", self.pick_min_length_px, 1, 10_000)
        _choice("throw_from", self.throw_from, THROW_SOURCES)
        _integer("offset_window_traces", self.offset_window_traces, 1, 9)
        if self.offset_window_traces % 2 != 1:
            raise ConfigError(f"labels.offset_window_traces = {self.offset_window_traces} is "
                              "even; allowed: an odd number in [1, 9]")
        if not isinstance(self.offset_faults, bool):
            raise ConfigError(f"labels.offset_faults = {self.offset_faults!r}; allowed: true | "
                              "false")
        _integer("offset_min_rows", self.offset_min_rows, 2, 1000)
        if self.offset_faults and self.throw_from != "offset":
            raise ConfigError("labels.offset_faults = true needs labels.throw_from = 'offset' "
                              "(it measures the offsets on the reference map)")
        return self

    def picks(self) -> PickConfig:
        """The :class:`demseis.labels.picks.PickConfig` of these settings."""
        return PickConfig(min_throw_samples=float(self.min_throw_samples),
                          smooth_px=float(self.pick_smooth_px),
                          max_gap_px=int(self.pick_max_gap_px),
                          min_length_px=int(self.pick_min_length_px))

    def min_slip_for(self, cell_m: float) -> float:
        """``min_slip_m``, or one grid cell (``cell_m``) when it is not set."""
        return float(cell_m) if self.min_slip_m is None else float(self.min_slip_m)

    @classmethod
    def from_mapping(cls, table: dict[str, Any]) -> "LabelConfig":
        """Build from a ``[labels]`` TOML table; unknown keys and bad values raise ConfigError."""
        if not isinstance(table, dict):
            raise ConfigError(f"[labels] must be a table, got {type(table).__name__}")
        known = {f.name for f in fields(cls)}
        unknown = sorted(set(table) - known)
        if unknown:
            raise ConfigError(
                f"unknown key(s) in [labels]: {', '.join(unknown)}; "
                f"allowed: {', '.join(sorted(known))}"
            )
        return cls(**table).validate()


def _choice(name: str, value: Any, choices: tuple[str, ...] | Registry) -> None:
    try:
        ok = isinstance(value, str) and value in choices
    except InputError as exc:  # a "module:attribute" name that does not import
        raise ConfigError(f"labels.{name} = {value!r}: {exc}") from None
    if not ok:
        raise ConfigError(f"labels.{name} = {value!r}; allowed: {' | '.join(map(repr, choices))}")


def _number(name: str, value: Any, lo: float, hi: float, lo_open: bool = False) -> None:
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise ConfigError(f"labels.{name} = {value!r} is not a number; allowed: "
                          f"{'(' if lo_open else '['}{lo}, {hi}]")
    v = float(value)
    bad = (not math.isfinite(v)) or v > hi or (v <= lo if lo_open else v < lo)
    if bad:
        raise ConfigError(f"labels.{name} = {value!r} out of range; allowed: "
                          f"{'(' if lo_open else '['}{lo}, {hi}]")


def _integer(name: str, value: Any, lo: int, hi: int) -> None:
    if isinstance(value, bool) or not isinstance(value, numbers.Integral):
        raise ConfigError(f"labels.{name} = {value!r} is not an integer; allowed: [{lo}, {hi}]")
    if value < lo or value > hi:
        raise ConfigError(f"labels.{name} = {value!r} out of range; allowed: [{lo}, {hi}]")
