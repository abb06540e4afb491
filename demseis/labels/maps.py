"""Label maps of one snapshot on the seismic grid: fault, damage, strain, layer and fault attributes.

Per snapshot, all on the :class:`demseis.types.Grid` the seismic uses, so that the labels are
pixel-aligned with it (:func:`label_maps`):

1. per-element strain -> grid (:func:`~demseis.labels.raster.rasterise_strain`: mean over the
   disks containing each cell centre; cells in the gaps between disks take the value of their
   power-diagram element); cells no element reaches (above the free surface) are "no rock":
   strain 0, layer -1, never fault. The layer map is each cell's element's layer.
2. the fault targets (:mod:`demseis.labels.targets`) by the configured ``method``, an entry
   of :data:`demseis.registry.LABEL_METHODS` (a :class:`LabelMethod`): slip surfaces traced
   in the element displacement (``"slip_trace"``, the default: :mod:`demseis.labels.traces`),
   or thresholds of the strain (``"strain_band"``: :mod:`demseis.labels.strain_band`).

The returned arrays are the engine labels that :mod:`demseis.schema` declares, in its order
and dtypes. :func:`sample_facts` summarises them per sample.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from demseis.errors import InputError
from demseis.labels.config import LabelConfig
from demseis.labels.raster import rasterise_strain
from demseis.labels.strain import StrainState
from demseis.labels.strain_band import strain_band_targets
from demseis.labels.targets import trace_targets
from demseis.labels.traces import slip_traces
from demseis.registry import LABEL_METHODS
from demseis.schema import engine_labels, sample_array
from demseis.types import Grid


def label_maps(snapshot, strain_per_element, grid, config: LabelConfig | None = None,
               displacement: np.ndarray | None = None) -> dict:
    """Fault, damage-zone, strain and layer labels of one snapshot on ``grid``.

    Parameters
    ----------
    snapshot : :class:`demseis.types.Snapshot` (uses ``xy``, ``radius``, ``layer``).
    strain_per_element : (n,) gamma_max aligned with the snapshot's elements (NaN = unknown,
        ignored), or the snapshot's :class:`~demseis.labels.strain.StrainState`, in which case
        ``config.strain_measure`` picks total or cumulative.
    grid : :class:`demseis.types.Grid`, row 0 at the top.
    config : :class:`LabelConfig` (defaults if None).
    displacement : (n, 2) displacement (m) of each element since its first appearance, or the
        tuple (displacement, birth) of :func:`~demseis.labels.slip.displacement_history`
        (birth: snapshot of first appearance, so that deposition surfaces are not taken for
        slip); required by the default ``"slip_trace"`` method.

    Returns
    -------
    dict of the engine labels of :mod:`demseis.schema` (``engine_labels()``), in store order
    and in their schema dtypes, (nz, nx) arrays:
        ``fault`` uint8 0/1; ``damage`` uint8 0 background / 1 damage zone / 2 fault core;
        ``strain`` float32 rasterised gamma_max (unsmoothed; 0 outside the rock);
        ``layer`` int16 layer id of the cell's element (-1 outside the rock);
        ``fault_id`` int16 fault instance 1.. on fault cells (0 elsewhere);
        ``slip_m`` float32 slip (m), ``dip_deg`` float32 dip (degrees) and ``sense`` uint8
        (1 normal, 2 reverse) of the nearest trace cell, on fault cells (0 elsewhere); with
        ``"strain_band"`` fault_id numbers the mask's 8-connected components and slip, dip,
        sense are 0.

    Raises
    ------
    InputError
        Inputs of the wrong shape; no displacement for ``"slip_trace"``; or the schema
        declares an engine label that label_maps does not make.
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
    layer_spec = sample_array("layer")
    layer_map = np.full(grid.shape, layer_spec.fill, dtype=layer_spec.np_dtype)
    layer_map[rock] = layer[owner[rock]].astype(layer_map.dtype)
    method: LabelMethod = LABEL_METHODS.get(cfg.method)
    if method.displacement and displacement is None:
        raise InputError(f"label_maps: the {cfg.method!r} method needs the elements' "
                         "displacement (n, 2); see demseis.labels.displacement_history")
    targets = method.targets(SnapshotRaster(xy, radius, strain, owner, grid), cfg, displacement)
    return _in_store_order({**targets, "strain": strain, "layer": layer_map})


def _in_store_order(maps: dict) -> dict:
    """``maps`` as the engine labels of the schema: in store order, each in its schema dtype
    (the arrays already of that dtype are returned as they are).

    Raises
    ------
    InputError
        A schema engine label is missing from ``maps``, or ``maps`` holds a name that is none.
    """
    names = engine_labels()
    missing = [n for n in names if n not in maps]
    extra = [n for n in maps if n not in names]
    if missing or extra:
        raise InputError(
            "label_maps does not make the engine labels that demseis.schema declares: "
            + "; ".join(s for s in (f"missing {missing}" if missing else "",
                                    f"not declared {extra}" if extra else "") if s)
            + f" (declared: {list(names)}; a label array that label_maps does not make needs a "
            "producer, see demseis.schema.register_array)")
    return {n: np.asarray(maps[n]).astype(sample_array(n).np_dtype, copy=False) for n in names}


def sample_facts(maps: dict) -> dict:
    """Per-sample facts of a label dict: ``has_fault`` (0/1), ``n_faults``, ``max_slip_m``."""
    fid = np.asarray(maps["fault_id"])
    ids = np.unique(fid[fid > 0])
    slip = np.asarray(maps["slip_m"])
    return {"has_fault": int(np.asarray(maps["fault"]).any()), "n_faults": int(ids.size),
            "max_slip_m": float(slip.max()) if slip.size else 0.0}


@dataclass(frozen=True)
class SnapshotRaster:
    """One snapshot's elements and their strain on the label grid (what a label method reads).

    Attributes
    ----------
    xy, radius : (n, 2) element centres (m) and (n,) radii (m).
    strain : (nz, nx) rasterised strain; owner : (nz, nx) element of each cell (-1: no rock).
    grid : the label grid.
    """

    xy: np.ndarray
    radius: np.ndarray
    strain: np.ndarray
    owner: np.ndarray
    grid: Grid

    @property
    def rock(self) -> np.ndarray:
        """(nz, nx) cells some element reaches."""
        return self.owner >= 0


@dataclass(frozen=True)
class LabelMethod:
    """One ``[labels] method`` (an entry of :data:`demseis.registry.LABEL_METHODS`).

    Attributes
    ----------
    targets : ``targets(raster, cfg, displacement) -> dict``: the fault targets (``fault``,
        ``damage``, ``fault_id``, ``slip_m``, ``dip_deg``, ``sense``) of a
        :class:`SnapshotRaster`; ``displacement`` as :func:`label_maps` takes it.
    displacement : it needs the elements' displacement (engines compute it only then).
    """

    targets: Callable[[SnapshotRaster, LabelConfig, Any], dict[str, np.ndarray]]
    displacement: bool = False


def _slip_trace_targets(raster: SnapshotRaster, cfg: LabelConfig,
                        displacement: Any) -> dict[str, np.ndarray]:
    """Slip surfaces traced in the element displacement (:mod:`demseis.labels.traces`)."""
    xy, radius, strain, grid, rock, owner = (raster.xy, raster.radius, raster.strain,
                                             raster.grid, raster.rock, raster.owner)
    n = xy.shape[0]
    birth = None
    if isinstance(displacement, tuple):
        displacement, birth = displacement
    disp = np.asarray(displacement, dtype=np.float64)
    if disp.shape != (n, 2):
        raise InputError(f"displacement has shape {disp.shape}; expected ({n}, 2)")
    ux, _ = rasterise_strain(xy, radius, disp[:, 0], grid)
    uy, _ = rasterise_strain(xy, radius, disp[:, 1], grid)
    cohort = None
    if birth is not None:
        birth = np.asarray(birth)
        if birth.shape != (n,):
            raise InputError(f"birth has shape {birth.shape}; expected ({n},)")
        cohort = np.where(rock, birth[np.maximum(owner, 0)], -1)
    tr = slip_traces(strain, ux, uy, rock, float(grid.cell_m), cfg, cohort)
    return trace_targets(tr, cfg, float(grid.cell_m), rock)


def _strain_band_targets(raster: SnapshotRaster, cfg: LabelConfig,
                         displacement: Any) -> dict[str, np.ndarray]:
    """Thresholds of the strain (:mod:`demseis.labels.strain_band`)."""
    return strain_band_targets(raster.strain, raster.rock, cfg)


#: slip surfaces traced in the element displacement (the default)
SLIP_TRACE = LabelMethod(_slip_trace_targets, displacement=True)
#: thresholds of the strain
STRAIN_BAND = LabelMethod(_strain_band_targets)
