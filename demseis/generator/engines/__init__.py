"""Engines: what turns a run's parameters into the geological states that are imaged and labelled.

An engine is any object with the :class:`Engine` protocol. The table
:data:`demseis.registry.ENGINES` maps the ``[model] engine`` values to engines; the choices of
that parameter are its names, and nothing outside an engine tests an engine's name. Built in:

- ``"dem"`` (:mod:`demseis.generator.engines.dem`): faults grow in the discrete element
  model; its particle snapshots are kept in the store, so a run can be re-rendered and
  relabelled without running it again;
- ``"kinematic"`` (:mod:`demseis.generator.engines.kinematic`): layers displaced geometrically
  along the run's basement faults, FaultSeg-style; no particles.
- ``"planar"`` (:mod:`demseis.generator.engines.planar`): the published FaultSeg recipe as a
  control (random reflectivity, folds, planar shear, planar faults); no particles.

The path from an engine to a store (:func:`demseis.generator.sweep.pipeline.run_shard`)::

    engine = get_engine(cfg.model.engine)
    run = engine.simulate(cfg, spec)                      # EngineRun
    for state in engine.states(cfg, run, snapshots):      # State per snapshot to render
        ...                                               # imaging, noise, time axis, arrays

A new engine is one registration (``ENGINES.register("name", engine)``), after which
``[model] engine = "name"`` is a valid config.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import dataclass
from typing import Any, Protocol, runtime_checkable

import numpy as np

from demseis.errors import InputError
from demseis.generator.config.sampling import RunParams, RunSpec
from demseis.generator.config.settings import Config
from demseis.generator.engines.runsetup import RunInfo, run_info
from demseis.registry import ENGINES
from demseis.types import Snapshot


@dataclass(frozen=True)
class State:
    """One geological state of a run (one snapshot), ready to image, label and store.

    Attributes
    ----------
    snapshot : snapshot index (0 = the undeformed reference).
    vp_m_s, rho_kg_m3 : (nz, nx) float64 Vp and density on the sweep's depth grid
        (:func:`demseis.generator.config.layout.grid_of`), row 0 at the top.
    labels : (nz, nx) depth-grid map of every label the engine makes
        (:func:`demseis.schema.engine_labels`: ``fault``, ``damage``, ``strain``, ``layer``,
        ``fault_id``, ``slip_m``, ``dip_deg``, ``sense``), with the schema's dtypes.
    values : per-sample values of this state stored in the ``params`` table: ``step``, ``throw_m``
        (the master fault's throw so far), ``n_elements`` and ``fault<k>_throw_m``.
    reference : where the rock of each point came from, for the ``strata`` rendering (None
        where the sweep renders ``elements``): ``reference(x_m, depth_m) -> (x0_m, y0_m,
        unit)`` for arrays of points (x right, depth below the grid top) gives their reference
        coordinates (the undeformed position, or where the rock was deposited; y up, 0 at
        the base of the model; NaN where there is no rock) and the stratigraphic unit to look
        them up in (-1: the pre-kinematic unit at ``y0_m``; k >= 0: growth unit k).
        It is continuous inside rock that moved together and jumps across slip surfaces.
    strata : the run's stratigraphy (:class:`demseis.seismic.Strata`) for ``reference``.
    """

    snapshot: int
    vp_m_s: np.ndarray
    rho_kg_m3: np.ndarray
    labels: Mapping[str, np.ndarray]
    values: Mapping[str, float]
    reference: Callable[[np.ndarray, np.ndarray],
                        tuple[np.ndarray, np.ndarray, np.ndarray]] | None = None
    strata: Any = None


@dataclass(frozen=True)
class EngineRun:
    """What :meth:`Engine.simulate` hands to :meth:`Engine.states` and to the store.

    Attributes
    ----------
    spec : the run and its renders.
    info : the run's basement faults and stored per-run values.
    snapshots : particle snapshots, stored with the run's shard (empty for an engine without
        particles).
    """

    spec: RunSpec
    info: RunInfo
    snapshots: tuple[Snapshot, ...] = ()


@runtime_checkable
class Engine(Protocol):
    """The protocol of an engine (see the module docstring).

    Attributes
    ----------
    particles : whether the engine's runs have particle snapshots (stored, and needed by
        ``demseis render``, ``relabel`` and ``preview``).
    strata : (optional, default False) whether its states carry ``reference`` and ``strata``,
        which ``[output] rendering = "strata"`` (the default) needs; a config asking for it
        from an engine without is refused at load.
    packs : (optional, default False) whether its runs take their settled pack from the
        library of ``[model] pack_library`` packs; an engine without ignores the key (and a
        store's config does not record it).
    parameters : (optional, default none) its own run-level ``[sweep]`` parameters, a tuple
        of :class:`demseis.parameters.Param` (numbers or booleans); each run draws them after
        the declared ones and ``spec.params`` carries them
        (:func:`demseis.generator.config.settings.engine_parameters`).
    """

    particles: bool

    def check(self, cfg: Config) -> None:
        """Refuse a config this engine cannot run, with a :class:`~demseis.errors.ConfigError`
        naming the keys (rules that combine several parameters; each one's range is checked
        before)."""

    def cost(self, cfg: Config, params: RunParams) -> float:
        """Relative cost of a run with run-level ``params`` (a sweep starts the costliest
        runs first); any unit, compared only between runs of one config."""

    def describe(self, cfg: Config) -> tuple[str, float]:
        """What one run is, for ``generate --dry-run`` (e.g. ``"~2,000 elements each"``), and
        the most seconds it takes on one core."""

    def simulate(self, cfg: Config, spec: RunSpec,
                 progress: Callable[[float], None] | None = None) -> EngineRun:
        """Run the engine for ``spec`` (``progress`` gets the fraction done, if given)."""

    def states(self, cfg: Config, run: EngineRun, snapshots: Sequence[int]) -> Iterator[State]:
        """The states of the snapshots ``snapshots`` (increasing) of ``run``, in that order."""


def get_engine(name: str) -> Engine:
    """The engine registered as ``name`` (an InputError listing the engines if none)."""
    return ENGINES.get(name)


def require_particles(cfg: Config, what: str) -> None:
    """Refuse ``what`` (a command that needs particle snapshots) for an engine without them.

    Raises
    ------
    InputError
        The config's engine keeps no particle snapshots.
    """
    if not get_engine(cfg.model.engine).particles:
        raise InputError(f"{what} needs particle snapshots, and this config/store's engine "
                         f"([model] engine = {cfg.model.engine!r}) has none: run `demseis "
                         "generate` with the settings you want instead")


def run_from_particles(cfg: Config, spec: RunSpec, snapshots: Sequence[Snapshot],
                       dem_attempt: int = 0) -> EngineRun:
    """The :class:`EngineRun` of stored particle snapshots (re-rendering, relabelling);
    ``dem_attempt``: the try of the DEM that made them (the source store's value)."""
    require_particles(cfg, "re-rendering")
    info = run_info(cfg, spec.params, spec.run)
    info = dataclasses.replace(info, values={**info.values, "dem_attempt": int(dem_attempt)})
    return EngineRun(spec=spec, info=info, snapshots=tuple(snapshots))


__all__ = ["ENGINES", "Engine", "EngineRun", "State", "get_engine", "require_particles",
           "run_from_particles"]
