"""``demseis render`` and ``demseis relabel``: new sections from a store's particle snapshots, without the DEM."""

from __future__ import annotations

import math
import time
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from demseis import interrupts
from demseis.datasets import (finalize_store, open_store, read_done_params, read_particles,
                              record_failures, shard_status, write_shard, writer_lock)
from demseis.errors import ConfigError, StoreError
from demseis.generator.config.sampling import SAMPLE_KEYS, plan_run, run_params
from demseis.generator.config.settings import Config, stored_config
from demseis.generator.engines import EngineRun, get_engine, require_particles, run_from_particles
from demseis.generator.render.section import render_run
from demseis.generator.sweep.driver import SweepSummary, _progress_bar, prepare_store
from demseis.labels import LabelConfig


def _copied(source_cfg: dict[str, Any]) -> dict[str, Any]:
    """A copy of a stored config whose tables can be replaced without touching the source."""
    return {k: (dict(v) if isinstance(v, dict) else v) for k, v in source_cfg.items()}


#: the config tables whose keys a re-render may change (besides the sample-level ``[sweep]``
#: keys): what the rendering and the labelling read, never what the DEM ran with
LOOK_TABLES = ("output", "labels")
#: run-level ``[sweep]`` keys that only the rendering reads (no engine does): a re-render may
#: change them as long as every stored run keeps its other run-level values
RENDER_RUN_KEYS = ("fault_zone_impedance",)


def _is_look_key(table: str, key: str) -> bool:
    """Whether ``[table] key`` is drawn at render time (a re-render may change it): those of
    :data:`LOOK_TABLES`, the sample-level ``[sweep]`` keys, :data:`RENDER_RUN_KEYS` and
    ``renders_per_snapshot``."""
    return table in LOOK_TABLES or (table == "sweep" and (
        key in SAMPLE_KEYS or key in RENDER_RUN_KEYS or key == "renders_per_snapshot"))


def _check_runs_kept(before: Config, after: Config) -> None:
    """Raise :class:`ConfigError` where ``after`` draws a stored run's run-level values (those
    an engine reads) otherwise than ``before``: a list of a :data:`RENDER_RUN_KEYS` key is
    crossed with the other lists, and a distribution of one is drawn from the runs' stream."""
    moved: set[str] = set()
    for run in range(before.sweep.n_runs):
        old, new = dict(run_params(before, run)), dict(run_params(after, run))
        moved |= {k for k in old if k not in RENDER_RUN_KEYS and old[k] != new.get(k)}
    if moved:
        raise ConfigError(
            f"{', '.join(f'[sweep] {k}' for k in RENDER_RUN_KEYS)} as given would change the "
            f"stored runs' {', '.join(sorted(moved))} (its values are drawn with theirs): give "
            "it one value, or run the sweep again with demseis generate")


def look_config(source_cfg: dict[str, Any], look: Mapping[str, Any]) -> Config:
    """The source config with the rendering keys of ``look`` replaced: the same runs drawn
    another way.

    ``look`` is a config mapping (a TOML read as a dict). Its ``[output]`` and ``[labels]``
    keys, its sample-level ``[sweep]`` keys (:data:`SAMPLE_KEYS`: wavelet, frequency, noise,
    processing), the run-level keys only the rendering reads (:data:`RENDER_RUN_KEYS`, so long
    as the runs' other values stay as drawn) and ``renders_per_snapshot`` replace the source's;
    every other key must equal the source's value (so a whole config, the store's own or one
    written by ``demseis fit`` from the same preset, can be given), since the stored runs were
    simulated with it. A key that differs raises :class:`ConfigError` naming it.
    """
    raw = _copied(source_cfg)
    given: list[tuple[str, str]] = []
    for table, values in look.items():
        if not isinstance(values, Mapping):
            given.append(("", table))
            raw[table] = values
            continue
        raw[table] = {**raw.get(table, {}), **values}
        given.extend((table, key) for key in values)
    cfg, source = stored_config(raw, source="render config"), stored_config(_copied(source_cfg))
    before, after = source.to_dict(), cfg.to_dict()

    def value(d: dict[str, Any], table: str, key: str) -> Any:
        return d.get(key) if not table else d.get(table, {}).get(key)

    fixed = [f"[{t}] {k}" if t else k for t, k in given
             if not _is_look_key(t, k) and k != "name"
             and value(before, t, k) != value(after, t, k)]
    if fixed:
        raise ConfigError(
            f"{', '.join(fixed)} differ{'s' if len(fixed) == 1 else ''} from the store's: the "
            "stored runs were simulated with "
            f"{'it' if len(fixed) == 1 else 'them'}. A re-render changes only [output], "
            "[labels], the sample-level [sweep] keys (demseis params: level 'sample') and "
            f"[sweep] {', '.join(RENDER_RUN_KEYS)}; run the sweep again with demseis generate")
    if any(t == "sweep" and k in RENDER_RUN_KEYS for t, k in given):
        _check_runs_kept(source, cfg)
    return cfg


def fitted_look(fitted: Mapping[str, Any]) -> dict[str, Any]:
    """The look of a config written by ``demseis fit``: its sampling (``[output]`` ``domain``,
    ``dt_s``, ``trace_spacing_m``) and its sample-level ``[sweep]`` keys (wavelet, frequency,
    noise and processing), for :func:`look_config`; its geology, taken from a preset, is left
    out."""
    return {"output": {k: fitted["output"][k] for k in ("domain", "dt_s", "trace_spacing_m")},
            "sweep": {k: v for k, v in fitted["sweep"].items() if k in SAMPLE_KEYS}}


def rerender_config(source_cfg: dict[str, Any], freqs_hz: list[float] | None = None,
                    snrs_db: list[float] | None = None, noise_kind: str | None = None,
                    imaging: list[str] | None = None,
                    psf_max_angles_deg: list[float] | None = None,
                    psf_aperture_m: float | None = None,
                    look: Mapping[str, Any] | None = None) -> Config:
    """The source config with its render parameters replaced (run parameters unchanged).

    ``look`` (:func:`look_config`) is applied first. ``freqs_hz`` then makes a grid of
    frequencies and SNRs (``snrs_db``, default no noise) with one render per snapshot and
    combination, of ``noise_kind`` (default white); None keeps the frequency, SNR and noise
    kind of the source (or of ``look``), and its renders per snapshot. ``imaging``,
    ``psf_max_angles_deg`` and ``psf_aperture_m`` replace the values when given (lists become
    grids: every snapshot is rendered at each); None keeps them.
    """
    raw = _copied(look_config(source_cfg, look).to_dict() if look else source_cfg)
    raw["sweep"] = dict(raw["sweep"])
    if freqs_hz is not None:
        snrs = [math.inf] if snrs_db is None else snrs_db
        raw["sweep"]["freq_hz"] = [f for f in freqs_hz]
        raw["sweep"]["snr_db"] = ["inf" if math.isinf(s) else s for s in snrs]
        raw["sweep"]["noise_kind"] = noise_kind or "white"
        raw["sweep"]["renders_per_snapshot"] = 1
    elif snrs_db is not None or noise_kind is not None:
        raise ConfigError("the SNRs and the noise kind of a re-render go with its frequencies")
    if imaging is not None:
        raw["sweep"]["imaging"] = list(imaging)
    if psf_max_angles_deg is not None:
        raw["sweep"]["psf_max_angle_deg"] = list(psf_max_angles_deg)
    if psf_aperture_m is not None:
        raw["sweep"]["psf_aperture_m"] = psf_aperture_m
    raw["name"] = f"{source_cfg.get('name', 'demseis')}-render"
    return stored_config(raw, source="re-render config")


def rerender(source: str | Path, out: str | Path, **options: Any) -> SweepSummary:
    """Write a new store with every done run of ``source`` re-rendered, holding ``out``'s
    writer lock (options: those of :func:`_rerender`)."""
    with writer_lock(out, "demseis render"), interrupts.watched():
        return _rerender(source, out, **options)


def _rerender(source: str | Path, out: str | Path, *, freqs_hz: list[float] | None = None,
              snrs_db: list[float] | None = None, noise_kind: str | None = None,
              imaging: list[str] | None = None, psf_max_angles_deg: list[float] | None = None,
              psf_aperture_m: float | None = None, look: Mapping[str, Any] | None = None,
              overwrite: bool = False, progress: bool = True) -> SweepSummary:
    """Write a new store with every done run of ``source`` re-rendered with the config of
    :func:`rerender_config` (its options; at least one of them).

    Runs that are not done in the source are recorded as failed in the new store. With the
    same config as ``generate`` would be given (``look`` of rendering keys only), a run's
    samples equal those ``generate`` writes with it.
    """
    if (freqs_hz is None and imaging is None and psf_max_angles_deg is None
            and psf_aperture_m is None and not look):
        raise ConfigError("a re-render needs something to change: frequencies, imaging or a "
                          "look (a config of rendering keys)")
    src = Path(source)
    root = open_store(src)
    cfg = rerender_config(dict(root.attrs)["config"], freqs_hz, snrs_db, noise_kind, imaging,
                          psf_max_angles_deg, psf_aperture_m, look)
    return _redo(src, out, cfg, overwrite=overwrite, progress=progress)


def relabel_config(source_cfg: dict[str, Any], labels: dict[str, Any]) -> Config:
    """The source config with its ``[labels]`` table replaced (everything else unchanged, so
    the same runs, renders and noise seeds give byte-identical seismic)."""
    raw = _copied(source_cfg)
    # keys not given take today's defaults (the picked fault target), not the source's
    raw["labels"] = {"fault_style": LabelConfig().fault_style, **labels}
    return stored_config(raw, source="relabel config")


def relabel(source: str | Path, out: str | Path, *, labels: dict[str, Any],
            overwrite: bool = False, progress: bool = True) -> SweepSummary:
    """Write a new store with the seismic of ``source`` and labels made with ``labels``,
    holding ``out``'s writer lock.

    Parameters
    ----------
    source : a demseis store with particle snapshots.
    out : the new store (must differ from ``source``).
    labels : a ``[labels]`` table (:class:`demseis.labels.LabelConfig` keys); keys not given
        take their defaults, not the source's values.
    overwrite, progress : as for :func:`rerender`.
    """
    with writer_lock(out, "demseis relabel"), interrupts.watched():
        src = Path(source)
        root = open_store(src)
        cfg = relabel_config(dict(root.attrs)["config"], labels)
        return _redo(src, out, cfg, overwrite=overwrite, progress=progress, desc="relabel")


def _redo(src: Path, out: str | Path, cfg: Config, *, overwrite: bool,
          progress: bool, desc: str = "render") -> SweepSummary:
    """Render and label every done run of ``src`` again with ``cfg`` into ``out``; ``desc``
    labels the progress bar (the command's name)."""
    t0 = time.perf_counter()
    if Path(out).resolve() == src.resolve():
        raise StoreError("--out must differ from the source store")
    require_particles(cfg, "render/relabel")
    src_status = shard_status(src)
    attempts = dem_attempts(src)
    status = prepare_store(cfg, out, overwrite=overwrite)
    pending = [int(i) for i in np.flatnonzero(status != 1)]
    summary = SweepSummary(store=str(out), n_shards=len(status), samples_per_shard=cfg.samples_per_run,
                           done_before=len(status) - len(pending))
    bar = _progress_bar(len(pending) * cfg.samples_per_run, progress and bool(pending), desc=desc)
    try:
        for run in pending:
            interrupts.raise_if_interrupted()  # one swallowed where it landed
            if src_status[run] != 1:
                summary.failed[run] = "not done in the source store"
                continue
            data = render_run(cfg, stored_run(src, run, cfg, attempts),
                              get_engine(cfg.model.engine))
            write_shard(out, run, data.arrays, data.params, data.snapshots)
            summary.completed.append(run)
            bar.update(cfg.samples_per_run)
    finally:
        bar.close()
    record_failures(out, summary.failed)
    finalize_store(out)
    summary.seconds = time.perf_counter() - t0
    return summary


def stored_run(src: Path, run: int, cfg: Config, attempts: dict[int, int]) -> EngineRun:
    """Run ``run`` of store ``src`` from its particle snapshots, planned with ``cfg``
    (``attempts``: :func:`dem_attempts` of ``src``)."""
    return run_from_particles(cfg, plan_run(cfg, run), read_particles(src, run),
                              attempts.get(run, 0))


def dem_attempts(src: Path) -> dict[int, int]:
    """``dem_attempt`` of every done run of ``src`` (run -> try); a store written before the
    DEM's stabilised tries has no such parameter: its runs all ran as configured (0)."""
    done = read_done_params(src, ["run_id", "dem_attempt"])
    if "dem_attempt" not in done.values:
        return {}
    return {int(r): int(a) for r, a in zip(done.values["run_id"], done.values["dem_attempt"])}
