"""The DEM engine (``[model] engine = "dem"``): faults grown in the discrete element model.

A run builds a layered assembly (:func:`demseis.dem.build_assembly`) and faults it by moving
its basement (:func:`demseis.dem.simulate`); each particle snapshot becomes a state: rock
properties per element, rasterised to the grid (:mod:`demseis.seismic`), and the labels from
the element displacements (:func:`demseis.labels.label_maps`). For the ``strata`` rendering a
state also carries the reference map of its snapshot (:func:`demseis.dem.reference_map`) and
the run's beds (:func:`dem_strata`).

With ``[model] pack_library = K > 0`` a run does not settle its own pack: it takes one of K
settled packs (:func:`run_pack`), each settled once and cached on disk (:func:`pack_cache_dir`),
and layers, faults and deposits it with its own draws.
"""

from __future__ import annotations

import copy
import dataclasses
import math
import os
from collections.abc import Callable, Iterator, Sequence
from functools import partial
from pathlib import Path

import numpy as np

from demseis.dem import (Material, NormalFault, Pack, build_assembly, settle_pack, simulate,
                         time_step)
from demseis.dem.reference import ReferenceMap, block_reference_map, reference_map
from demseis.dem.strata import layer_materials
from demseis.errors import ConfigError, SimulationError
from demseis.generator.config.layout import grid_of
from demseis.generator.config.params import DistSpec, Fixed, spec_values_hint
from demseis.generator.config.sampling import (SEED_DEM, SEED_LAYERS, SEED_PACK, SEED_PROPERTIES,
                                               RunParams, RunSpec, rng_at)
from demseis.generator.config.settings import Config
from demseis.generator.engines import EngineRun, State
from demseis.generator.engines.physics import check_physics
from demseis.generator.engines.runsetup import (RunInfo, fault_system_of, layer_thicknesses,
                                                material_of, property_model_of, run_info,
                                                run_properties, run_strata)
from demseis.labels import displacement_history, label_maps, strain_history
from demseis.parameters import MATERIAL_FIELDS, PARAMS
from demseis.registry import LABEL_METHODS, RENDERINGS
from demseis.seismic import (LayerProperties, Strata, draw_layer_properties, element_properties,
                             property_grids)
from demseis.types import Snapshot

#: ``--dry-run`` cost model, fitted to the seed-scale run measured by benchmarks/dem_seed.py
#: (11,224 elements: 25.8 s faulting for ~45,900 steps, 15.7 s settling, one core)
DRY_RUN_ELEMENT_STEPS_PER_S = 2.0e7
DRY_RUN_SETTLE_S_PER_ELEMENT = 1.4e-3
DRY_RUN_PACKING = 0.86
#: environment variable naming the pack library's directory (:func:`pack_cache_dir`)
PACK_CACHE_ENV = "DEMSEIS_PACK_CACHE"
#: ``[output] block_smoothing_m > 0``: elements within this many of the largest element radii
#: of a labelled fault (along the section) take no part in the smoothed displacement
#: (:func:`demseis.dem.reference.block_reference_map`, ``band_m``)
BLOCK_BAND_RADII = 2.0
#: the tries of a DEM run, in order, each ``(divisor of wall_speed_m_s, relaxed deposits)``:
#: try 0 is the run as configured; tries 1-2 run the basement at half and a quarter of the wall
#: speed (closer to quasi-static; 2 and 4 times the steps); tries 3-5 repeat 0-2 with relaxed
#: deposits (``simulate(relax_deposits=True)``: no deposit carries its template's overlaps), and
#: are made only with sedimentation. A run stores the index of the try that finished.
TRIES: tuple[tuple[int, bool], ...] = ((1, False), (2, False), (4, False),
                                       (1, True), (2, True), (4, True))


class DemEngine:
    """The discrete element model as an :class:`~demseis.generator.engines.Engine`."""

    particles = True
    strata = True
    #: runs can take their settled pack from a library (``[model] pack_library``)
    packs = True

    def check(self, cfg: Config) -> None:
        """Elements fit the box and the layers, and the DEM's physical sanity rules
        (:func:`demseis.generator.engines.physics.check_physics`) hold."""
        m = cfg.model
        if m.radius_max_m * 8 > min(m.width_m, m.height_m):
            raise ConfigError(
                f"model.radius_max_m = {m.radius_max_m:g} is too large for a "
                f"{m.width_m:g} x {m.height_m:g} m box: at most 1/8 of the smaller side")
        n_layers = spec_values_hint(cfg.sweep.params["n_layers"])
        if n_layers and m.height_m / n_layers[1] < 2 * m.radius_min_m:
            raise ConfigError(
                f"sweep.n_layers up to {n_layers[1]} gives layers thinner than one element "
                f"(height_m / n_layers < 2 * radius_min_m = {2 * m.radius_min_m:g} m)")
        check_physics(cfg)

    def describe(self, cfg: Config) -> tuple[str, float]:
        """"~N elements each" and the seconds one run takes on one core at most, from the
        element count of the box and the steps of the longest run (``--dry-run``)."""
        m = cfg.model
        # radii are log-uniform (demseis.dem.assembly): E[r^2] = (b^2 - a^2) / (2 ln(b / a))
        a, b = m.radius_min_m, m.radius_max_m
        mean_r2 = a * a if b <= a else (b * b - a * a) / (2.0 * math.log(b / a))
        n_elem = DRY_RUN_PACKING * m.width_m * m.height_m / (math.pi * mean_r2)
        throw_hi = spec_values_hint(cfg.sweep.params["throw_m"])[1]
        dip_lo = spec_values_hint(cfg.sweep.params["dip_deg"])[0]
        kn_lo = spec_values_hint(cfg.sweep.params["kn_n_m"])[0]
        rho_hi = spec_values_hint(cfg.sweep.params["density_kg_m3"])[1]
        stretch_lo, stretch_hi = spec_values_hint(cfg.sweep.params["base_stretch"])
        dt = time_step(a, rho_hi, kn_lo)
        path = max(throw_hi / math.sin(math.radians(dip_lo)),
                   max(abs(stretch_lo), abs(stretch_hi)) * m.width_m)
        steps = path / m.wall_speed_m_s / dt
        secs = n_elem * (steps / DRY_RUN_ELEMENT_STEPS_PER_S + DRY_RUN_SETTLE_S_PER_ELEMENT)
        return f"~{n_elem:,.0f} elements each", secs

    def cost(self, cfg: Config, params: RunParams) -> float:
        """Integrator steps to the target throw plus settling: path along dip (or the base's
        stretch, if longer) / wall speed / dt, with the DEM's own time step
        (:func:`demseis.dem.time_step`); the element count is the same for every run of a
        sweep."""
        m = cfg.model
        dt = time_step(m.radius_min_m, params.density_kg_m3, params.kn_n_m)
        path_m = max(params.throw_m / math.sin(math.radians(params.dip_deg)),
                     abs(params.base_stretch) * m.width_m)
        return (path_m / m.wall_speed_m_s + 4.0) / dt

    def simulate(self, cfg: Config, spec: RunSpec,
                 progress: Callable[[float], None] | None = None) -> EngineRun:
        """Build the assembly of run ``spec.run`` and fault it.

        A run that goes unstable (:class:`~demseis.errors.SimulationError`) is run again from
        the same assembly and seeds, try by try (:data:`TRIES`: a slower basement, then relaxed
        deposits); the try that finished is stored as ``dem_attempt``. A try slower than the
        slowest declared wall speed is not made. Only when every try goes unstable is the run's
        error raised, naming each try's cause.
        """
        p = spec.params
        material = material_of(p)
        thick = layer_thicknesses(cfg, p.n_layers, p.layer_thickness_cv,
                                  rng_at(cfg, spec.run, SEED_LAYERS))
        fault = fault_system_of(cfg, p, spec.run)
        info = run_info(cfg, p, spec.run, basement=fault)
        rng = rng_at(cfg, spec.run, SEED_DEM)
        asm = build_assembly(
            cfg.model.width_m, cfg.model.height_m,
            radius_min_m=cfg.model.radius_min_m, radius_max_m=cfg.model.radius_max_m,
            n_layers=p.n_layers, layer_thickness_m=thick, material=material, rng=rng,
            pack=run_pack(cfg, spec.run) if cfg.model.pack_library else None,
        )
        layers = None
        if p.strength_contrast > 1.0:
            model = property_model_of(cfg, p)
            # the same draw as states' (the first layers do not depend on the total)
            lith = draw_layer_properties(p.n_layers, model,
                                         rng_at(cfg, spec.run, SEED_PROPERTIES)).lithology
            layers = layer_materials([model.lithologies[k] for k in lith], material,
                                     p.strength_contrast)
        # uplift (reverse and listric faults, a shortening base) is eroded at the top of the
        # sample grid
        stretch = p.base_stretch
        uplift = stretch < 0 or (not isinstance(fault, NormalFault) and any(
            f.kind != "normal" for f in fault.faults))
        causes = []
        for attempt, (divisor, relax) in enumerate(TRIES):
            if relax and not cfg.model.sedimentation:
                break                      # without deposits these tries repeat the first ones
            speed = fault.speed_m_s / divisor
            if speed < PARAMS["wall_speed_m_s"].lo:
                causes.append(f"no {_try_name(attempt, speed, relax)}: below the slowest wall "
                              f"speed {PARAMS['wall_speed_m_s'].lo:g} m/s")
                continue
            try_rng = copy.deepcopy(rng)   # every try deposits the same sediment draws
            try:
                snaps = simulate(asm, dataclasses.replace(fault, speed_m_s=speed), material,
                                 n_snapshots=cfg.model.n_snapshots,
                                 sedimentation=cfg.model.sedimentation, rng=try_rng,
                                 progress=progress,
                                 erosion_level_m=cfg.model.height_m if uplift else None,
                                 layer_materials=layers, base_stretch=stretch,
                                 relax_deposits=relax)
            except SimulationError as exc:
                causes.append(f"{_try_name(attempt, speed, relax)}: {exc}")
                continue
            info = RunInfo(info.system, {**info.values, "dem_attempt": attempt})
            return EngineRun(spec=spec, info=info, snapshots=tuple(snaps))
        raise SimulationError(f"every try went unstable ({'; '.join(causes)})")

    def states(self, cfg: Config, run: EngineRun, snapshots: Sequence[int]) -> Iterator[State]:
        """Rock properties and labels of each wanted particle snapshot.

        The strain and displacement histories run over every snapshot of the run (cumulative
        strain, and the snapshot each element first appeared in)."""
        snaps = list(run.snapshots)
        grid = grid_of(cfg)
        model = property_model_of(cfg, run.spec.params)
        n_layers_total = max(int(s.layer.max()) for s in snaps) + 1
        layer_props, elem_seed = run_properties(cfg, run.spec.run, model, n_layers_total)
        history = strain_history(snaps, cfg.labels)
        strata = None
        moves = None      # displacement history: the slip-trace labels and the strata need it
        wants_reference = RENDERINGS.get(cfg.output.rendering).reference
        needs_moves = LABEL_METHODS.get(cfg.labels.method).displacement
        if needs_moves or wants_reference:
            moves = displacement_history(snaps)
        if wants_reference:
            strata = dem_strata(cfg, run, snaps, layer_props, moves)
        for k in snapshots:
            snap = snaps[k]
            vp_e, rho_e = element_properties(snap.ids, snap.layer, layer_props, model, elem_seed)
            vp_g, rho_g = property_grids(snap.xy, snap.radius, vp_e, rho_e, snap.layer, grid, model)
            labels = label_maps(snap, history[k], grid, cfg.labels,
                                displacement=moves[k] if needs_moves else None)
            values = {"step": snap.step, "throw_m": snap.throw_m, "n_elements": snap.n,
                      **run.info.throws_at(k, len(snaps))}
            reference = None
            if strata is not None:
                mapper = reference_map
                if cfg.output.block_smoothing_m > 0:
                    mapper = partial(block_reference_map, barrier=labels["fault"],
                                     barrier_grid=grid,
                                     smooth_m=float(cfg.output.block_smoothing_m),
                                     band_m=BLOCK_BAND_RADII * float(cfg.model.radius_max_m))
                reference = partial(_reference, snaps, k, moves[k], grid.top_m, mapper=mapper)
            yield State(snapshot=k, vp_m_s=vp_g, rho_kg_m3=rho_g, labels=labels, values=values,
                        reference=reference, strata=strata)


def pack_cache_dir() -> Path:
    """The pack library's directory: ``$DEMSEIS_PACK_CACHE`` when set, else
    ``$XDG_CACHE_HOME/demseis/packs`` (``~/.cache/demseis/packs``). Packs are named by a hash
    of what they are settled from, so stores and sweeps of the same box share them; the
    directory only saves time (deleting it costs one settling per pack, never other bytes)."""
    env = os.environ.get(PACK_CACHE_ENV, "").strip()
    if env:
        return Path(env).expanduser()
    base = os.environ.get("XDG_CACHE_HOME", "").strip() or os.path.join("~", ".cache")
    return Path(base).expanduser() / "demseis" / "packs"


def pack_index(cfg: Config, run: int) -> int:
    """Which of the ``K = [model] pack_library`` packs run ``run`` takes: each block of K
    consecutive runs (``b K .. b K + K - 1``) takes every pack once, in an order drawn from the
    seed node ``(b K, SEED_PACK)``; so a run's pack depends only on the sweep seed and its
    index, and the packs are used equally."""
    k = cfg.model.pack_library
    if k < 1:
        raise ConfigError(f"model.pack_library = {k}: a run takes a library pack only when it "
                          "is >= 1")
    first = run - run % k
    return int(rng_at(cfg, first, SEED_PACK).permutation(k)[run % k])


def library_material(cfg: Config) -> Material:
    """The material every pack of the library is settled with: each material parameter's
    value where the sweep fixes it, else the middle of what it draws (uniform: the midpoint,
    log-uniform: the geometric midpoint, truncated normal: its mean, a list or choice: the
    first value). Each run then relaxes the pack with its own material before faulting
    (:func:`demseis.dem.simulate`)."""
    values = {}
    for name, key in MATERIAL_FIELDS.items():
        spec = cfg.sweep.params[key]
        if isinstance(spec, Fixed):
            v = spec.value
        elif isinstance(spec, DistSpec) and spec.dist == "uniform":
            v = 0.5 * (spec.low + spec.high)
        elif isinstance(spec, DistSpec) and spec.dist == "loguniform":
            v = math.sqrt(spec.low * spec.high)
        elif isinstance(spec, DistSpec) and spec.dist == "truncnormal":
            v = spec.mean
        else:
            v = spec.values[0]
        values[name] = PARAMS[key].kind(v)
    return Material(**values)


def run_pack(cfg: Config, run: int, cache_dir: str | os.PathLike | None = None) -> Pack:
    """The settled pack of run ``run`` from the library of ``[model] pack_library`` packs:
    pack k (:func:`pack_index`) is :func:`demseis.dem.settle_pack` of the model box and radii
    with :func:`library_material` and seed k, loaded from ``cache_dir`` (default
    :func:`pack_cache_dir`) or settled once and written there (checksummed, atomically)."""
    m = cfg.model
    return settle_pack(m.width_m, m.height_m, radius_min_m=m.radius_min_m,
                       radius_max_m=m.radius_max_m, material=library_material(cfg),
                       rng=pack_index(cfg, run),
                       cache_dir=pack_cache_dir() if cache_dir is None else cache_dir)


def _try_name(attempt: int, speed_m_s: float, relax: bool = False) -> str:
    """How try ``attempt`` of a run is named in its error."""
    if attempt == 0:
        return f"as configured ({speed_m_s:g} m/s)"
    return (f"stabilised try {attempt} (wall speed {speed_m_s:g} m/s"
            + (", relaxed deposits)" if relax else ")"))


def dem_strata(cfg: Config, run: EngineRun, snaps: Sequence[Snapshot], props: LayerProperties,
               moves: Sequence[tuple[np.ndarray, np.ndarray]]) -> Strata:
    """The beds of a DEM run: its pre-kinematic layers (the thicknesses the assembly was
    built with), then each growth layer over the reference y its elements were deposited at
    (``moves``: :func:`demseis.labels.displacement_history` of ``snaps``)."""
    p = run.spec.params
    n = p.n_layers
    H = cfg.model.height_m
    thick = layer_thicknesses(cfg, n, p.layer_thickness_cv,
                              rng_at(cfg, run.spec.run, SEED_LAYERS))
    thick = np.full(n, H / n) if thick is None else thick
    top = np.cumsum(thick)
    top[-1] = H
    bottom = np.concatenate([[0.0], top[:-1]])
    n_total = int(props.vp.size)
    lo = np.full(n_total - n, np.inf)
    hi = np.full(n_total - n, -np.inf)
    for s, (d, _) in zip(snaps, moves):
        grown = s.deposited & (s.layer >= n)
        if not grown.any():
            continue
        g = s.layer[grown].astype(np.int64) - n
        y = s.xy[grown, 1] - d[grown, 1]
        np.minimum.at(lo, g, y - s.radius[grown])
        np.maximum.at(hi, g, y + s.radius[grown])
    empty = ~np.isfinite(lo)
    lo[empty], hi[empty] = H, H + 1.0   # a growth layer no element of which survived
    return run_strata(cfg, p, run.spec.run, np.concatenate([bottom, lo]),
                      np.concatenate([top, hi]), props, n_prekinematic=n)


def _reference(snaps: Sequence[Snapshot], k: int, move: tuple[np.ndarray, np.ndarray],
               top_m: float, x_m: np.ndarray, depth_m: np.ndarray, *,
               mapper: Callable[..., ReferenceMap] = reference_map
               ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """:attr:`State.reference` of snapshot ``k`` (``move``: its displacement since each
    element's first appearance, and that snapshot) by ``mapper``:
    :func:`demseis.dem.reference_map`, or :func:`demseis.dem.reference.block_reference_map`
    with the run's fault label bound (``[output] block_smoothing_m``); a point in a growth
    element is looked up in that element's growth unit."""
    x = np.asarray(x_m, dtype=np.float64)
    pts = np.stack([x.ravel(), top_m - np.asarray(depth_m, dtype=np.float64).ravel()], axis=1)
    ref = mapper(snaps, k, pts, displacement=move)
    unit = np.where(ref.deposited, ref.layer.astype(np.int64), -1).reshape(x.shape)
    return ref.ref_xy[:, 0].reshape(x.shape), ref.ref_xy[:, 1].reshape(x.shape), unit


ENGINE = DemEngine()
