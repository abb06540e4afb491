"""From an engine's geological states to the arrays of a shard: imaging, noise, time axis, labels.

Every engine hands its snapshots over as :class:`~demseis.generator.engines.State` records;
:func:`render_state` images one state for each of its samples (one imaging call per mode and
option group, all frequencies at once), adds the noise of each sample, converts labels and
impedance to the two-way-time axis of a time-domain sweep, and fills the shard's sample and
parameter arrays. Which arrays, their dtypes and fills come from :mod:`demseis.schema`.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import astuple, dataclass
from typing import Any

import numpy as np

from demseis.errors import InputError
from demseis.generator.config.layout import (array_dtypes, crop_to, grid_of, on_grid, param_codes,
                                             param_dtypes, sample_shape, section_shape,
                                             time_axis_of, trace_spacing, trace_x)
from demseis.generator.config.sampling import Render, RunParams, RunSpec, config_of_run
from demseis.generator.config.settings import Config
from demseis.generator.engines import Engine, EngineRun, State
from demseis.generator.engines.runsetup import property_model_of
from demseis.generator.render.survey import (damage_factor, fill_gaps, fine_depths,
                                             hold_small_steps, labels_at_traces, level_surface,
                                             nearest_columns, reference_points, smooth_velocity,
                                             substeps, surface_window, to_time, velocity_window)
from demseis.labels import pick_faults, sample_facts, throw_samples
from demseis.labels.offsets import (jumps_to_samples, offset_disagreement, offset_faults,
                                    pair_jumps, window_max)
from demseis.registry import FAULT_STYLES, RENDERINGS
from demseis.schema import SAMPLE_ARRAYS, engine_labels
from demseis.seismic import (add_noise, coarse_velocity, imaged_sections, imaging_mode,
                             strata_properties)
from demseis.seismic.processing import Processing, process
from demseis.seismic.wavelet import Wavelet
from demseis.types import Snapshot


@dataclass(frozen=True)
class ShardData:
    """All samples of one run: (S, H, W) arrays, (S,) parameters and the particle snapshots."""

    arrays: dict[str, np.ndarray]
    params: dict[str, np.ndarray]
    snapshots: list[Snapshot]


def empty_shard(cfg: Config, spec: RunSpec, shape: tuple[int, int] | None = None,
                ) -> tuple[dict[str, np.ndarray], dict[str, np.ndarray]]:
    """Zeroed (S, H, W) sample arrays (``shape``, default the store's) and (S,) parameter
    arrays of run ``spec``."""
    S = len(spec.renders)
    shape = sample_shape(cfg) if shape is None else shape
    arrays = {k: np.zeros((S, *shape), dtype=v) for k, v in array_dtypes(cfg).items()}
    params = {k: np.zeros(S, dtype=v) for k, v in param_dtypes(cfg).items()}
    return arrays, params


def renders_by_snapshot(spec: RunSpec) -> list[tuple[int, list[Render]]]:
    """The renders of ``spec`` grouped by snapshot, in snapshot order."""
    by_snap: dict[int, list[Render]] = {}
    for r in spec.renders:
        by_snap.setdefault(r.snapshot, []).append(r)
    return sorted(by_snap.items())


def render_run(cfg: Config, run: EngineRun, engine: Engine) -> ShardData:
    """Every sample of ``run``: the states ``engine`` makes of its rendered snapshots, imaged.

    Where the store's sampling varies from run to run (``Config.sampling``), the run is
    rendered at its own (:func:`config_of_run`), its sections cropped to the store's shape
    (:func:`crop_to`) and its sampling stored with each sample (``dt_s``, 0 in depth, and
    ``trace_spacing_m``)."""
    rcfg = config_of_run(cfg, run.spec.run)
    arrays, params = empty_shard(rcfg, run.spec, section_shape(rcfg))
    groups = renders_by_snapshot(run.spec)
    renders = dict(groups)
    for state in engine.states(rcfg, run, [k for k, _ in groups]):
        render_state(rcfg, run, renders[state.snapshot], state, arrays, params)
    if cfg.sampling:
        shape = sample_shape(cfg)
        arrays = {k: np.ascontiguousarray(crop_to(v, shape)) for k, v in arrays.items()}
        params["dt_s"][:] = rcfg.output.dt_s if rcfg.output.domain == "time" else 0.0
        params["trace_spacing_m"][:] = trace_spacing(rcfg)
    return ShardData(arrays=arrays, params=params, snapshots=list(run.snapshots))


def state_maps(state: State, stored: Mapping[str, Any]) -> dict[str, np.ndarray]:
    """The depth-grid label maps of ``state``: the engine's, then every stored label array
    the schema makes with a producer.

    Raises
    ------
    InputError
        The engine did not make one of the labels every engine must make.
    """
    maps = dict(state.labels)
    missing = [name for name in engine_labels() if name not in maps]
    if missing:
        raise InputError(f"the engine's state of snapshot {state.snapshot} has no "
                         f"{', '.join(missing)} label (every engine makes "
                         f"{', '.join(engine_labels())})")
    for name, spec in SAMPLE_ARRAYS.items():
        if spec.producer is not None and name in stored:
            maps[name] = np.asarray(spec.producer(state), dtype=spec.dtype)
    return maps


def render_state(cfg: Config, run: EngineRun, renders: list[Render], state: State,
                 arrays: dict[str, np.ndarray], params: dict[str, np.ndarray]) -> None:
    """Image, add noise and store the samples ``renders`` of one geological state.

    Fills ``arrays[...][r.sample]`` and ``params[...][r.sample]`` in place.
    """
    grid = grid_of(cfg)
    t_s = time_axis_of(cfg)
    maps = labels_at_traces(cfg, state_maps(state, arrays))
    img = imaging_input(cfg, state, maps, run.spec.params)
    domain = "depth" if t_s is None else "time"
    # one imaging call per (mode, options key), all its frequencies at once; the first render
    # of a group carries the group's mode and options
    wanted: dict[tuple, tuple[Render, set[Wavelet]]] = {}
    for r in renders:
        wanted.setdefault(_imaging_key(r), (r, set()))[1].add(r.wavelet)
    images = {}
    for key, (first, wset) in wanted.items():
        wavelets = sorted(wset, key=astuple)
        # a zero-phase Ricker goes to the imaging mode as its frequency, as it always has
        bank = [w.freq_hz if w.is_plain_ricker else w for w in wavelets]
        secs = imaged_sections(first.imaging, img.vp, img.rho, img.dz_m, bank, domain,
                               t_s=t_s, col_step_m=img.col_step_m,
                               rows_per_cell=img.substeps if domain == "depth" else 1,
                               **first.values)
        images.update({(key, w): sec for w, sec in zip(wavelets, secs)})
    impedance = img.impedance
    vp = img.vp_cell
    style: FaultStyle = FAULT_STYLES.get(cfg.labels.fault_style)
    extra = {}
    uncertain = "fault_uncertain" in arrays
    if (style.offsets and cfg.labels.throw_from == "offset") or uncertain:
        extra[_JUMP] = cell_jumps(cfg, img)
    if t_s is not None:
        fills = {name: SAMPLE_ARRAYS.get(name).fill for name in [*maps, "impedance"]}
        maps = to_time({**maps, **extra, "impedance": impedance, _VP: vp}, img.vp_cell,
                       grid.cell_m, t_s, {**fills, _VP: 0.0, _JUMP: 0.0})
        impedance, vp = maps.pop("impedance"), maps.pop(_VP)
    else:
        maps = {**maps, **extra}
    jump = maps.pop(_JUMP, None)
    maps = style.draw(cfg, maps, vp, jump if cfg.labels.throw_from == "offset" else None)
    if uncertain:
        pair = jumps_to_samples(jump[:, :-1], samples_per_m(cfg, jump.shape, vp), jump.shape)
        maps["fault_uncertain"] = offset_disagreement(
            maps["fault"], pair, min_samples=max(float(cfg.labels.min_throw_samples), 1.0))
    facts = sample_facts(maps)
    rendered = {"impedance": impedance}
    codes = param_codes()
    for r in renders:
        clean = images[(_imaging_key(r), r.wavelet)]
        i = r.sample
        rng = np.random.default_rng(r.seed)
        noisy = add_noise(clean, r.snr_db, r.noise_kind, rng,
                          float(r.values.get("noise_slope", 1.0)))
        arrays["seismic"][i] = process(noisy, Processing.of(r.values), rng, clean)
        for name in arrays:
            if name != "seismic":
                arrays[name][i] = maps[name] if name in maps else rendered[name]
        values = {"run_id": run.spec.run, "sample_in_run": i, **r.values, "noise_seed": r.seed,
                  "snapshot": state.snapshot, **run.info.values, **state.values, **facts}
        for key, value in {**run.spec.params, **values}.items():
            if key in codes:
                value = codes[key].index(value)
            params[key][i] = value


#: the interval-velocity map's key while it is taken to time with the labels
_VP = "_vp_m_s"
#: the reflector-jump map's key while it is taken to time with the labels
_JUMP = "_jump_m"


def cell_jumps(cfg: Config, img: "ImagingInput") -> np.ndarray:
    """(nz, ntr) signed jump (m) of the rock's reference elevation across each pair of
    neighbouring traces (j, j + 1), at column j, on the grid cells
    (:func:`demseis.labels.offsets.pair_jumps` of the cell centres; 0 in the last column and
    where there is no rock).

    Raises
    ------
    InputError
        The state has no reference map (``rendering = "elements"``).
    """
    if img.y0_cell is None:
        raise InputError("labels.throw_from = 'offset' measures the reflectors' offsets on the "
                         "reference map, which [output] rendering = 'elements' has not: set "
                         "rendering = 'strata' or labels.throw_from = 'slip'")
    jumps = pair_jumps(img.y0_cell, width=int(cfg.labels.offset_window_traces))
    return np.nan_to_num(np.pad(jumps, ((0, 0), (0, 1))), nan=0.0)


def output_picks(cfg: Config, maps: Mapping[str, np.ndarray], vp_m_s: np.ndarray,
                 jump_m: np.ndarray | None = None) -> dict[str, np.ndarray]:
    """``maps`` (on the output grid) with their faults drawn as picks
    (:func:`demseis.labels.picks.pick_faults`).

    With ``jump_m`` (:func:`cell_jumps` on the output grid; ``[labels] throw_from =
    "offset"``) the throw of a pixel is the reflectors' offset there in output samples
    (:func:`demseis.labels.offsets.window_max`), and with ``offset_faults`` the visible
    offsets no fault explains become faults first (:func:`demseis.labels.offsets.offset_faults`).
    Otherwise it is the slip's throw at the output grid's sampling: depth cells, or the
    two-way time through ``vp_m_s``."""
    t_s = time_axis_of(cfg)
    if jump_m is not None:
        lab = cfg.labels
        per_m = samples_per_m(cfg, jump_m.shape, vp_m_s)
        if lab.offset_faults:
            maps = offset_faults(dict(maps), jump_m, per_m, trace_spacing(cfg), 1.0 / per_m,
                                 min_samples=max(float(lab.min_throw_samples), 1.0),
                                 min_rows=int(lab.offset_min_rows))
        pair = jumps_to_samples(jump_m[:, :-1], per_m, per_m.shape)
        return pick_faults(maps, window_max(pair), lab.picks())
    if t_s is None:
        throw = throw_samples(maps["slip_m"], maps["dip_deg"], cell_m=grid_of(cfg).cell_m)
    else:
        throw = throw_samples(maps["slip_m"], maps["dip_deg"], vp_m_s=vp_m_s,
                              dt_s=float(cfg.output.dt_s))
    return pick_faults(maps, throw, cfg.labels.picks())


def samples_per_m(cfg: Config, shape: tuple[int, int], vp_m_s: np.ndarray) -> np.ndarray:
    """(H, W) output samples per metre of vertical offset on the output grid: ``1 / cell`` in
    depth, ``2 / (vp dt)`` on a two-way-time axis (``vp_m_s`` the interval velocity there)."""
    if time_axis_of(cfg) is None:
        return np.full(shape, 1.0 / float(grid_of(cfg).cell_m))
    return 2.0 / (np.maximum(vp_m_s, 1.0) * float(cfg.output.dt_s))


@dataclass(frozen=True)
class ImagingInput:
    """What one state's sections are imaged from, at the traces.

    Attributes
    ----------
    vp, rho : (rows, ntr) Vp and density: the grid's cells (``elements``) or the strata
        points (``strata``, ``substeps`` per cell).
    dz_m : their row height; col_step_m : the trace spacing where it is not ``dz_m`` (else None).
    substeps : rows per grid cell (1 for ``elements``).
    vp_cell : (nz, ntr) the interval velocity of each grid cell (labels to time).
    impedance : (nz, ntr) the impedance of each grid cell (the optional stored array).
    y0_cell : (nz, ntr) reference elevation (m) of the rock at each cell centre, NaN where
        there is none (``strata`` only; None for ``elements``).
    """

    vp: np.ndarray
    rho: np.ndarray
    dz_m: float
    col_step_m: float | None
    substeps: int
    vp_cell: np.ndarray
    impedance: np.ndarray
    y0_cell: np.ndarray | None = None


def imaging_input(cfg: Config, state: State, maps: Mapping[str, np.ndarray],
                  params: RunParams) -> ImagingInput:
    """The property columns of ``state`` at the traces, by the sweep's ``[output] rendering``
    (:data:`demseis.registry.RENDERINGS`); ``maps`` are its labels at the traces, ``params`` the
    run's parameters."""
    rendering: Rendering = RENDERINGS.get(cfg.output.rendering)
    return rendering.columns(cfg, state, maps, params)


def _element_columns(cfg: Config, state: State, maps: Mapping[str, np.ndarray],
                     params: RunParams) -> ImagingInput:
    """``elements``: the engine's property grids, at the nearest grid column of each trace."""
    grid = grid_of(cfg)
    vp, rho = state.vp_m_s, state.rho_kg_m3
    col_step = None
    if not on_grid(cfg):
        cols = nearest_columns(cfg)
        vp, rho, col_step = vp[:, cols], rho[:, cols], trace_spacing(cfg)
    return ImagingInput(vp, rho, grid.cell_m, col_step, 1, vp, vp * rho)


def _strata_columns(cfg: Config, state: State, maps: Mapping[str, np.ndarray],
                    params: RunParams) -> ImagingInput:
    """``strata``: a fine stratigraphy looked up through the state's reference map
    (:mod:`demseis.generator.render.survey`).

    Raises
    ------
    InputError
        The engine's state has no reference map or stratigraphy.
    """
    grid = grid_of(cfg)
    if state.reference is None or state.strata is None:
        raise InputError(f"[output] rendering = 'strata' needs the engine's reference map and "
                         f"stratigraphy, and engine {cfg.model.engine!r} gives none (snapshot "
                         f"{state.snapshot}): set [output] rendering = 'elements'")
    n = substeps(cfg)
    z = fine_depths(cfg, grid.nz)
    x0, y0, unit = reference_points(state.reference, trace_x(cfg), z)
    rock = np.isfinite(x0) & np.isfinite(y0)
    whole = bool(rock.all())
    vp, rho = strata_properties(state.strata, x0 if whole else np.where(rock, x0, 0.0),
                                y0 if whole else np.where(rock, y0, 0.0), unit)
    if not whole:                                    # no rock: the nearest rock of the trace
        vp[~rock] = np.nan
        rho[~rock] = np.nan
        level_surface(vp, rho, rock, surface_window(cfg))
        vp, rho = fill_gaps(vp), fill_gaps(rho)
    hold_small_steps(vp, rho)
    change = params.fault_zone_impedance
    if change != 0.0:
        f = np.sqrt(damage_factor(np.repeat(maps["damage"], n, axis=0), change))
        vp, rho = vp * f, rho * f
    floor = property_model_of(cfg, dict(params)).vp_lower_bound_m_s
    vp = np.maximum(vp, floor)
    impedance = (vp * rho).reshape(grid.nz, n, -1).mean(axis=1)
    vp, rho = smooth_velocity(vp, rho, velocity_window(cfg))
    vp_cell = coarse_velocity(vp, n)
    y0_cell = np.where(rock, y0, np.nan).reshape(grid.nz, n, -1)[:, n // 2]
    return ImagingInput(vp, rho, grid.cell_m / n, trace_spacing(cfg), n, vp_cell, impedance,
                        y0_cell)


def _imaging_key(r: Render) -> tuple:
    """Renders sharing this key share one imaging call."""
    return (r.imaging, *imaging_mode(r.imaging).key_of(r.values))


@dataclass(frozen=True)
class Rendering:
    """One ``[output] rendering`` (an entry of :data:`demseis.registry.RENDERINGS`).

    Attributes
    ----------
    columns : ``columns(cfg, state, maps, params) -> ImagingInput``: the property columns
        at the traces (``maps``: the state's labels at the traces; ``params``: the run's).
    reference : it reads the state's ``reference`` map and ``strata`` (an engine must declare
        ``strata = True``; engines compute them only for such a rendering), and it gives
        ``ImagingInput.y0_cell`` (what ``[labels] throw_from = "offset"`` measures).
    """

    columns: Callable[[Config, State, Mapping[str, np.ndarray], RunParams],
                      ImagingInput]
    reference: bool = False


#: the engine's property grids (the paper's mode)
ELEMENTS = Rendering(_element_columns)
#: a fine stratigraphy through the reference map (the default)
STRATA = Rendering(_strata_columns, reference=True)


def rendering_of(cfg: Config) -> Rendering:
    """The :class:`Rendering` that ``cfg``'s ``[output] rendering`` names."""
    return RENDERINGS.get(cfg.output.rendering)


@dataclass(frozen=True)
class FaultStyle:
    """One ``[labels] fault_style`` (an entry of :data:`demseis.registry.FAULT_STYLES`).

    Attributes
    ----------
    draw : ``draw(cfg, maps, vp_m_s, jump_m) -> maps``: the labels on the output grid with
        their fault drawn in this style (``vp_m_s``: interval velocity on that grid;
        ``jump_m``: the reflectors' jumps, :func:`cell_jumps`, or None).
    offsets : it uses ``jump_m`` where ``[labels] throw_from = "offset"`` (they are computed
        only then).
    """

    draw: Callable[[Config, dict[str, np.ndarray], np.ndarray, np.ndarray | None],
                   dict[str, np.ndarray]]
    offsets: bool = False


def _as_traced(cfg: Config, maps: dict[str, np.ndarray], vp_m_s: np.ndarray,
               jump_m: np.ndarray | None) -> dict[str, np.ndarray]:
    return maps


#: the label method's traces as they are
TRACES = FaultStyle(_as_traced)
#: faults drawn as an interpreter picks them (:func:`output_picks`; the default)
PICKS = FaultStyle(output_picks, offsets=True)
