"""From an engine's geological states to the arrays of a shard: imaging, noise, time axis, labels.

Every engine hands its snapshots over as :class:`~demseis.generator.engines.State` records;
:func:`render_state` images one state for each of its samples (one imaging call per mode and
option group, all frequencies at once), adds the noise of each sample, converts labels and
impedance to the two-way-time axis of a time-domain sweep, and fills the shard's sample and
parameter arrays. Which arrays, their dtypes and fills come from :mod:`demseis.schema`.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from demseis.errors import InputError
from demseis.generator.config import Config
from demseis.generator.engines import Engine, EngineRun, State
from demseis.generator.layout import (array_dtypes, grid_of, param_codes, param_dtypes,
                                      sample_shape, time_axis_of)
from demseis.generator.sampling import Render, RunSpec
from demseis.labels import sample_facts
from demseis.schema import SAMPLE_ARRAYS, engine_labels
from demseis.seismic import add_noise, depth_to_time, imaged_sections, imaging_mode
from demseis.types import Snapshot


@dataclass(frozen=True)
class ShardData:
    """All samples of one run: (S, H, W) arrays, (S,) parameters and the particle snapshots."""

    arrays: dict[str, np.ndarray]
    params: dict[str, np.ndarray]
    snapshots: list[Snapshot]


def empty_shard(cfg: Config, spec: RunSpec) -> tuple[dict[str, np.ndarray], dict[str, np.ndarray]]:
    """Zeroed (S, H, W) sample arrays and (S,) parameter arrays of run ``spec``."""
    S = len(spec.renders)
    arrays = {k: np.zeros((S, *sample_shape(cfg)), dtype=v) for k, v in array_dtypes(cfg).items()}
    params = {k: np.zeros(S, dtype=v) for k, v in param_dtypes().items()}
    return arrays, params


def renders_by_snapshot(spec: RunSpec) -> list[tuple[int, list[Render]]]:
    """The renders of ``spec`` grouped by snapshot, in snapshot order."""
    by_snap: dict[int, list[Render]] = {}
    for r in spec.renders:
        by_snap.setdefault(r.snapshot, []).append(r)
    return sorted(by_snap.items())


def render_run(cfg: Config, run: EngineRun, engine: Engine) -> ShardData:
    """Every sample of ``run``: the states ``engine`` makes of its rendered snapshots, imaged."""
    arrays, params = empty_shard(cfg, run.spec)
    groups = renders_by_snapshot(run.spec)
    renders = dict(groups)
    for state in engine.states(cfg, run, [k for k, _ in groups]):
        render_state(cfg, run, renders[state.snapshot], state, arrays, params)
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
    maps = state_maps(state, arrays)
    facts = sample_facts(maps)
    vp_g, rho_g = state.vp_m_s, state.rho_kg_m3
    impedance = vp_g * rho_g
    domain = "depth" if t_s is None else "time"
    # one imaging call per (mode, options key), all its frequencies at once; the first render
    # of a group carries the group's mode and options
    wanted: dict[tuple, tuple[Render, set[float]]] = {}
    for r in renders:
        wanted.setdefault(_imaging_key(r), (r, set()))[1].add(r.freq_hz)
    images = {}
    for key, (first, fset) in wanted.items():
        freqs = sorted(fset)
        secs = imaged_sections(first.imaging, vp_g, rho_g, grid.cell_m, freqs, domain, t_s=t_s,
                               **first.values)
        images.update({(key, f): sec for f, sec in zip(freqs, secs)})
    if t_s is not None:
        for name in maps:
            maps[name] = depth_to_time(maps[name], vp_g, grid.cell_m, t_s, method="nearest",
                                       fill=SAMPLE_ARRAYS.get(name).fill)
        impedance = depth_to_time(impedance, vp_g, grid.cell_m, t_s, method="nearest",
                                  fill=SAMPLE_ARRAYS.get("impedance").fill)
    rendered = {"impedance": impedance}
    codes = param_codes()
    for r in renders:
        clean = images[(_imaging_key(r), r.freq_hz)]
        i = r.sample
        arrays["seismic"][i] = add_noise(clean, r.snr_db, r.noise_kind,
                                         np.random.default_rng(r.seed))
        for name in arrays:
            if name != "seismic":
                arrays[name][i] = maps[name] if name in maps else rendered[name]
        values = {"run_id": run.spec.run, "sample_in_run": i, **r.values, "noise_seed": r.seed,
                  "snapshot": state.snapshot, **run.info.values, **state.values, **facts}
        for key, value in {**run.spec.params, **values}.items():
            if key in codes:
                value = codes[key].index(value)
            params[key][i] = value


def _imaging_key(r: Render) -> tuple:
    """Renders sharing this key share one imaging call."""
    return (r.imaging, *imaging_mode(r.imaging).key_of(r.values))
