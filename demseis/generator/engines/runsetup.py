"""What every engine derives from a run's parameters: its basement fault system, the per-run
values a store holds about it, its layer thicknesses, DEM material and rock-property model.

The engines (:mod:`demseis.generator.engines`) share these so that a DEM run and a kinematic
run with the same parameters have the same faults, layering and rock.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from demseis.dem import BasementFault, FaultSystem, Material, NormalFault
from demseis.dem.basement import draw_fault_system
from demseis.dem.fault import as_system
from demseis.errors import ConfigError
from demseis.generator.config.layout import param_codes
from demseis.generator.config.sampling import (SEED_FAULTS, SEED_PROPERTIES, SEED_STRATA,
                                               RunParams, rng_at, seed_sequence)
from demseis.generator.config.settings import Config
from demseis.parameters import BED_FIELDS, MATERIAL_FIELDS, MAX_BASEMENT_FAULTS, PROPERTY_FIELDS
from demseis.seismic import (BedModel, LayerProperties, PropertyModel, Strata,
                             draw_layer_properties, draw_strata)

#: value of every ``fault<k>_*`` record of a fault a run does not have (the store holds no
#: NaN); kind and direction codes index the ``fault_kind`` and ``dip_direction`` choices.
ABSENT = -1.0


@dataclass(frozen=True)
class RunInfo:
    """The basement of a run and the per-run values stored with each of its samples.

    Attributes
    ----------
    system : the run's basement faults.
    values : ``fault_x_m`` and ``throw_target_m`` (the master fault's x at the base and target
        throw), ``n_basement_faults`` and, for k < ``MAX_BASEMENT_FAULTS``, every
        ``fault<k>_kind``, ``_dip_direction``, ``_x_m``, ``_dip_deg``, ``_throw_target_m`` and
        ``_throw_m`` (``ABSENT`` for a fault the run does not have).
    """

    system: FaultSystem
    values: dict[str, float]

    def throws_at(self, snapshot: int, n_snapshots: int) -> dict[str, float]:
        """``fault<k>_throw_m`` (throw so far) of every fault at snapshot ``snapshot``."""
        throws = self.system.throws_at(snapshot / (n_snapshots - 1))
        return {f"fault{k}_throw_m": float(t) for k, t in enumerate(throws)}

    @property
    def master(self) -> BasementFault | None:
        """The fault whose x and throw are ``fault_x_m`` and ``throw_target_m`` (None for a
        run without basement faults, ``structure="none"``)."""
        return self.system.faults[self.system.master] if self.system.faults else None


def layer_thicknesses(cfg: Config, n_layers: int, cv: float, rng: np.random.Generator) -> np.ndarray | None:
    """Layer thicknesses (bottom to top) summing to the model height; None for equal layers.

    With ``cv > 0`` relative thicknesses are Gamma(1/cv², ·) draws (coefficient of variation
    ``cv``), floored at two minimum element diameters so that every layer holds elements.
    """
    if cv <= 0 or n_layers == 1:
        return None
    w = rng.gamma(1.0 / cv**2, 1.0, size=n_layers)
    h = cfg.model.height_m * w / w.sum()
    floor = min(4.0 * cfg.model.radius_min_m, cfg.model.height_m / n_layers)
    for _ in range(50):
        short = h < floor
        if not short.any():
            break
        deficit = (floor - h[short]).sum()
        h[short] = floor
        h[~short] -= deficit * h[~short] / h[~short].sum()
    return h


def fault_system_of(cfg: Config, params: RunParams, run: int) -> NormalFault | FaultSystem:
    """The basement of a run: a :class:`NormalFault` for ``structure="single"`` and
    ``fault_kind="normal"`` (placed by ``fault_x_frac``), else a :class:`FaultSystem` (without
    faults for ``structure="none"``, which needs ``base_stretch != 0``)."""
    W = cfg.model.width_m
    structure, kind = params.structure, params.fault_kind
    if structure == "none":
        if params.base_stretch == 0.0:
            raise ConfigError("structure = 'none' (no basement fault) needs base_stretch != 0: "
                              "with base_stretch = 0 nothing deforms the model")
        return FaultSystem((), speed_m_s=cfg.model.wall_speed_m_s, structure="none")
    if structure == "single" and kind == "normal":
        return NormalFault(x_m=params.fault_x_frac * W, dip_deg=params.dip_deg,
                           throw_m=params.throw_m,
                           dip_direction=params.dip_direction,
                           speed_m_s=cfg.model.wall_speed_m_s)
    if structure == "single":
        f = BasementFault(params.fault_x_frac * W, params.dip_deg,
                          params.throw_m, params.dip_direction, kind,
                          params.listric_radius_m)
        if kind == "listric":
            f = dataclasses.replace(f, throw_m=min(f.throw_m, f.max_listric_throw_m))
        system = FaultSystem((f,), structure="single")
    else:
        if kind == "listric" and structure != "half_graben":
            kind = "normal"  # a listric fault must bound an end block: only half-grabens
        system = draw_fault_system(rng_at(cfg, run, SEED_FAULTS), W, structure=structure,
                                   n_faults=params.n_faults, kind=kind,
                                   dip_deg=params.dip_deg,
                                   throw_m=params.throw_m,
                                   spacing_frac=params.fault_spacing_frac,
                                   listric_radius_m=params.listric_radius_m,
                                   dip_direction=params.dip_direction)
    return dataclasses.replace(system, speed_m_s=cfg.model.wall_speed_m_s)


def run_info(cfg: Config, params: RunParams, run: int,
             basement: NormalFault | FaultSystem | None = None) -> RunInfo:
    """The basement of run ``run`` and its stored per-run values (see :class:`RunInfo`).

    ``fault_x_frac`` places a single basement fault where it meets the base of the model. The
    fault that grows through the cover is usually steeper than the basement fault (it is not
    imposed), so its trace at the surface lies on the footwall side of that point.
    ``basement``: the run's :func:`fault_system_of`, where the caller has it already.
    """
    system = as_system(basement if basement is not None else fault_system_of(cfg, params, run))
    codes = param_codes()
    m = system.faults[system.master] if system.faults else None
    values: dict[str, float] = {"fault_x_m": m.x_m if m else ABSENT,
                                "throw_target_m": m.throw_m if m else 0.0,
                                "n_basement_faults": len(system.faults)}
    for k in range(MAX_BASEMENT_FAULTS):
        f = system.faults[k] if k < len(system.faults) else None
        values[f"fault{k}_kind"] = codes["fault_kind"].index(f.kind) if f else -1
        values[f"fault{k}_dip_direction"] = (codes["dip_direction"].index(f.dip_direction)
                                             if f else -1)
        values[f"fault{k}_x_m"] = f.x_m if f else ABSENT
        values[f"fault{k}_dip_deg"] = f.dip_deg if f else ABSENT
        values[f"fault{k}_throw_target_m"] = f.throw_m if f else ABSENT
        values[f"fault{k}_throw_m"] = ABSENT
    return RunInfo(system=system, values=values)


def material_of(params: RunParams) -> Material:
    """The DEM material of a run."""
    return Material(**{field: params[key] for field, key in MATERIAL_FIELDS.items()})


def property_model_of(cfg: Config, params: RunParams) -> PropertyModel:
    """The rock-property model of a run (scalar fields from the run's parameters)."""
    scalar = {name: params[name] for name in PROPERTY_FIELDS}
    return PropertyModel(**cfg.properties, **scalar)


def run_properties(cfg: Config, run: int, model: PropertyModel,
                   n_layers_total: int) -> tuple[LayerProperties, int]:
    """The per-layer rock properties of run ``run`` and its per-element scatter seed.

    Both come from the run's ``SEED_PROPERTIES`` node, so every snapshot (and a re-render or a
    preview) gets the same rock.
    """
    layer_props = draw_layer_properties(n_layers_total, model, rng_at(cfg, run, SEED_PROPERTIES))
    elem_seed = int(seed_sequence(cfg, run, SEED_PROPERTIES).generate_state(2, dtype=np.uint64)[1])
    return layer_props, elem_seed


def bed_model_of(params: RunParams) -> BedModel:
    """The bed model of a run (:class:`demseis.seismic.BedModel`) from its parameters."""
    return BedModel(**{name: float(params[name]) for name in BED_FIELDS})


def run_strata(cfg: Config, params: RunParams, run: int, unit_bottom_m: np.ndarray,
               unit_top_m: np.ndarray, props: LayerProperties,
               n_prekinematic: int | None = None) -> Strata:
    """The beds of run ``run`` (``strata`` rendering): its mechanical layers (and growth
    layers, after the first ``n_prekinematic`` units) ``unit_bottom_m .. unit_top_m`` in
    reference y, each split into beds around the layer's rock ``props``; drawn from the run's
    ``SEED_STRATA`` node, so every snapshot and every engine state of the run gets the same
    beds."""
    return draw_strata(np.asarray(unit_bottom_m, dtype=np.float64),
                       np.asarray(unit_top_m, dtype=np.float64), props, cfg.model.width_m,
                       bed_model_of(params), rng_at(cfg, run, SEED_STRATA),
                       n_prekinematic=n_prekinematic)
