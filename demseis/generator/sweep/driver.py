"""The sweep: every run of a config, one dask task per run, each writing its own shard.

Only this driver creates the store, writes root attributes and consolidates metadata (once, at
the end); a task writes the array data of exactly one shard, then that shard's done flag. A
rerun on the same store completes only the shards that are not done, so an interrupted sweep
resumes where it stopped and gives the same bytes as an uninterrupted one.
"""

from __future__ import annotations

import functools
import json
import os
import shutil
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from tqdm import tqdm

from demseis import interrupts
from demseis.datasets import (ParamSpec, create_store, finalize_store, read_store_attrs,
                              record_failures, remove_partial_writes, shard_status, write_shard,
                              writer_lock)
from demseis.datasets.index import update_index
from demseis.datasets.layout import root_metadata_lost
from demseis.datasets.lock import pid_alive
from demseis.errors import ConfigError, SimulationError, StoreError
from demseis.generator.config.layout import (array_dtypes, grid_of, on_grid, param_codes,
                                             param_dtypes, sample_shape, trace_spacing)
from demseis.generator.config.params import _json_value, spec_candidates
from demseis.generator.config.sampling import run_params
from demseis.generator.config.settings import Config, load_config, parse_config
from demseis.generator.engines import get_engine
from demseis.generator.sweep.pipeline import run_shard
from demseis.generator.sweep.workers import sigint_deferred
from demseis.parameters import PARAMS, SAMPLING_STORED, STORED


@dataclass
class SweepSummary:
    """What a sweep did."""

    store: str
    n_shards: int
    samples_per_shard: int
    done_before: int
    completed: list[int] = field(default_factory=list)
    failed: dict[int, str] = field(default_factory=dict)
    #: runs written now whose last snapshot has no fault pixel (the DEM made no fault)
    no_fault: list[int] = field(default_factory=list)
    #: runs written now that went unstable and finished on a stabilised try: run -> its
    #: ``dem_attempt`` (demseis.generator.engines.dem.TRIES)
    stabilised: dict[int, int] = field(default_factory=dict)
    #: runs marked done whose shard failed its checksums, so the sweep computes them again
    damaged: list[int] = field(default_factory=list)
    seconds: float = 0.0
    #: seconds from the first task submitted to the last finished (no cluster start-up)
    compute_seconds: float = 0.0
    #: wall seconds of the driver's phases: prepare (store), start (cluster + Numba warm-up,
    #: overlapped), compute, close (cluster shutdown), finalize (failures + consolidation)
    phase_seconds: dict[str, float] = field(default_factory=dict)
    #: one record per finished task: shard, pid, start/end (epoch s), engine_s, render_s, write_s,
    #: cpu_s (CPU seconds of the task's thread)
    tasks: list[dict[str, Any]] = field(default_factory=list)
    #: time (perf_counter) the index of the parameter table was last brought up to date
    index_updated: float = field(default_factory=time.perf_counter)
    #: runs of ``completed`` the index held at that update
    indexed: int = 0

    @property
    def n_samples_written(self) -> int:
        return len(self.completed) * self.samples_per_shard

    def lines(self) -> list[str]:
        out = [
            f"store: {self.store}",
            f"shards: {self.n_shards} ({self.samples_per_shard} samples each); "
            f"{self.done_before} already done, {len(self.completed)} written now, "
            f"{len(self.failed)} failed",
            f"time: {self.seconds:.1f} s"
            + (f", {self.n_samples_written / self.seconds:.2f} samples/s" if self.seconds > 0 and self.completed else ""),
        ]
        if self.damaged:
            redone = sorted(set(self.damaged) & set(self.completed))
            out.append(f"{len(self.damaged)} done run(s) failed their checksums and were "
                       f"computed again: {', '.join(map(str, sorted(self.damaged)))}"
                       + ("" if len(redone) == len(self.damaged) else
                          f" ({len(redone)} of them written now)"))
        if self.no_fault:
            out.append(f"{len(self.no_fault)} run(s) ended with no fault (no fault pixel in the "
                       "last snapshot): " + ", ".join(str(r) for r in sorted(self.no_fault)))
        if self.stabilised:
            out.append(f"{len(self.stabilised)} run(s) went unstable and finished on a stabilised "
                       "try (slower basement or relaxed deposits; stored as dem_attempt): "
                       + ", ".join(f"{r} (try {a})" for r, a in sorted(self.stabilised.items())))
        for shard, err in sorted(self.failed.items()):
            out.append(f"  run {shard} failed: {err}")
        unstable = [e for e in self.failed.values() if e.startswith("SimulationError")]
        if unstable:
            # the same config and seed give the same bits, so a rerun fails the same way
            out.append("a DEM run that went unstable on every try (as configured and at a slower "
                       "basement) fails the same way when rerun: change its config (lower "
                       "model.wall_speed_m_s, or raise sweep.damping_scale, or narrow the swept "
                       "ranges) and write a new --out")
        if len(unstable) < len(self.failed):
            out.append("rerun the same command to retry the runs that failed for another reason")
        return out


def domain_text(cfg: Config) -> str:
    """``"depth domain"``, ``"time domain"``, or the domains drawn per run."""
    if "domain" in cfg.sampling:
        return " or ".join(map(str, spec_candidates(cfg.sampling["domain"]))) + " domain per run"
    return f"{cfg.output.domain} domain"


def store_attrs(cfg: Config) -> dict[str, Any]:
    """Root attributes the driver writes when it creates a store."""
    grid = grid_of(cfg)
    grid_attrs: dict[str, Any] = {"x0_m": grid.x0_m, "top_m": grid.top_m, "cell_m": grid.cell_m,
                                  "nz": grid.nz, "nx": sample_shape(cfg)[1],
                                  "domain": cfg.output.domain}
    if not on_grid(cfg):
        grid_attrs["dx_m"] = trace_spacing(cfg)  # traces, not cells: x = x0 + (j + 0.5) dx
    if cfg.output.domain == "time" or "domain" in cfg.sampling:  # rows: time samples (some)
        grid_attrs["dt_s"] = cfg.output.dt_s
        grid_attrs["nt"] = sample_shape(cfg)[0]
    if cfg.sampling:  # each run its own: dt_s and dx_m above are nominal, the table has each
        grid_attrs["sampling"] = {k: spec.to_json() for k, spec in cfg.sampling.items()}
    return {
        "config": cfg.to_dict(),
        "grid": grid_attrs,
        "param_codes": {k: list(v) for k, v in param_codes().items()},
    }


def _first_difference(a: Any, b: Any, path: str = "") -> str | None:
    if isinstance(a, dict) and isinstance(b, dict):
        for key in sorted(set(a) | set(b)):
            if key not in a or key not in b:
                return f"{path}{key}"
            d = _first_difference(a[key], b[key], f"{path}{key}.")
            if d:
                return d
        return None
    return None if a == b else path.rstrip(".")


def _with_new_defaults(old: Any, new: dict[str, Any]) -> Any:
    """``old`` (a stored config) with each parameter it lacks and ``new`` holds at its
    declared default added, so that a store written before a parameter was declared resumes
    under a config that leaves it at its default (its samples were made that way)."""
    if not isinstance(old, dict):
        return old
    out = {k: dict(v) if isinstance(v, dict) else v for k, v in old.items()}
    for section, table in new.items():
        if not isinstance(table, dict) or not isinstance(out.get(section), dict):
            continue
        for key, value in table.items():
            p = PARAMS.get(key)
            if key not in out[section] and p is not None and p.section == section and \
                    value == _json_value(p.default):
                out[section][key] = value
    return out


def _check_same_config(out: Path, attrs: dict[str, Any]) -> None:
    """Refuse the existing store ``out`` unless it was written with the config of ``attrs``
    (:func:`store_attrs`): ConfigError naming the first difference; StoreError (from
    ``read_store_attrs``) for a path that is not a demseis store."""
    old = json.loads(json.dumps(read_store_attrs(out).get("config")))
    new = json.loads(json.dumps(attrs["config"]))
    old = _with_new_defaults(old, new)
    if old != new:
        diff = _first_difference(old, new) or "config"
        raise ConfigError(
            f"store {str(out)!r} was written with a different config (first difference: "
            f"{diff}); use --overwrite to replace it, or choose another --out"
        )


def pending_runs(cfg: Config, out: str | Path, *, overwrite: bool = False) -> tuple[int, str]:
    """How many runs ``generate`` would compute into ``out`` now, and why, without writing.

    All of them for a new store or with ``overwrite``; the runs not yet done in a store of
    this config (a done shard that is damaged counts as pending, as the sweep redoes it).

    Raises
    ------
    ConfigError
        ``out`` holds a store written with another config (as ``generate`` would).
    StoreError
        ``out`` exists and is not a demseis store.
    """
    out = Path(out)
    n = cfg.sweep.n_runs
    if overwrite or not out.exists():
        return n, "a new store" if not out.exists() else "--overwrite replaces the store"
    if root_metadata_lost(out):
        return n, "the store's root metadata is lost: its done runs are checked when it is rebuilt"
    _check_same_config(out, store_attrs(cfg))
    status = shard_status(out, verify=True)
    return int(np.count_nonzero(status != 1)), f"{int(np.count_nonzero(status == 1))} done in {out}"


def prepare_store(cfg: Config, out: str | Path, *, overwrite: bool = False) -> np.ndarray:
    """Create the store, or check that an existing one was written with this config.

    Returns the per-shard status (1 = done).
    """
    out = Path(out)
    attrs = store_attrs(cfg)
    if out.exists() and not overwrite:
        if root_metadata_lost(out):  # its config is lost with it: the arrays must match
            _create(cfg, out, attrs, overwrite=False)
        _check_same_config(out, attrs)
        # a driver killed mid-write (kill -9) leaves zarr's temporary files; we hold the lock
        # and no task runs yet, so every one of them is stale
        remove_partial_writes(out)
        _create(cfg, out, attrs, overwrite=False)  # rewrites damaged metadata, checks the layout
        return shard_status(out, verify=True)  # a damaged done shard is redone
    # A new store is built beside ``out`` and renamed into place, so a kill -9 while its
    # arrays are being created leaves no half-made store at ``out`` (found by the kill test).
    target = out
    if not out.exists():
        _remove_orphan_creations(out)
        out = out.with_name(f".{out.name}.creating-{os.getpid()}")
    try:
        _create(cfg, out, attrs, overwrite=overwrite)
    except OSError as exc:  # name the path the user gave, not the temporary one
        if out != target:
            shutil.rmtree(out, ignore_errors=True)
        raise OSError(exc.errno, exc.strerror, str(target)) from None
    if out != target:
        os.rename(out, target)
    return shard_status(target)


def _create(cfg: Config, out: Path, attrs: dict[str, Any], *, overwrite: bool) -> None:
    """:func:`~demseis.datasets.create_store` of ``cfg`` at ``out``: a new store, or (an
    existing one, without ``overwrite``) its damaged metadata rewritten and its layout checked."""
    create_store(out, n_shards=cfg.sweep.n_runs, samples_per_shard=cfg.samples_per_run,
                 shape=sample_shape(cfg), arrays=array_dtypes(cfg), params=store_param_specs(cfg),
                 attrs=attrs, overwrite=overwrite)


def _remove_orphan_creations(out: Path) -> None:
    """Delete the half-made stores ``.<name>.creating-<pid>`` beside ``out`` whose creating
    process is gone (a driver killed while it created the arrays). The caller holds the lock
    of ``out``, so no live driver is creating it; our own pid's leftover goes too."""
    for d in out.parent.glob(f".{out.name}.creating-*"):
        pid = d.name.rsplit("-", 1)[-1]
        if d.is_dir() and pid.isdigit() and (int(pid) == os.getpid() or not pid_alive(int(pid))):
            shutil.rmtree(d, ignore_errors=True)


def store_param_specs(cfg: Config) -> dict[str, Any]:
    """Per-sample parameters of the store of ``cfg`` with their declared unit and doc
    (demseis.parameters) and, for the categorical ones, the names of their codes."""
    decl = {k: (p.unit, p.doc) for k, p in cfg.scenario.items()}
    decl.update({p.name: (p.unit, p.doc) for p in STORED + SAMPLING_STORED})  # throw_m: reached
    codes = param_codes()
    return {k: ParamSpec(v, long_name=decl[k][1], units=decl[k][0] or "1",
                         categories=codes.get(k))
            for k, v in param_dtypes(cfg).items()}


def shard_task(store: str, cfg_dict: dict[str, Any], shard: int) -> dict[str, Any]:
    """Simulate and render run ``shard`` and write its shard. Runs in a dask worker (or in-process).

    An unstable simulation is returned as an error record (retrying it would fail the same
    way); any other exception propagates so that dask retries the task.
    """
    start = time.time()
    t0 = time.perf_counter()
    c0 = time.thread_time()
    cfg = parse_config(cfg_dict)
    timings: dict[str, float] = {}
    try:
        data = run_shard(cfg, shard, timings=timings)
    except SimulationError as exc:
        return {"shard": shard, "error": f"SimulationError: {exc}"}
    t2 = time.perf_counter()
    try:
        write_shard(store, shard, data.arrays, data.params, data.snapshots or None)
    except OSError as exc:  # disk full, read-only, permissions: retrying cannot help
        return {"shard": shard, "os_error": describe_os_error(exc, store)}
    t3 = time.perf_counter()
    snapshot = np.asarray(data.params["snapshot"])
    last = snapshot == snapshot.max()
    return {"shard": shard, "seconds": t3 - t0, "samples": int(data.arrays["seismic"].shape[0]),
            "no_fault": not bool(np.any(data.arrays["fault"][last])), "pid": os.getpid(),
            "dem_attempt": int(np.max(data.params["dem_attempt"])),
            "start": start, "end": time.time(), "engine_s": timings.get("engine_s", 0.0),
            "render_s": timings.get("render_s", 0.0), "write_s": t3 - t2,
            "cpu_s": time.thread_time() - c0}


def warm_numba_cache() -> None:
    """Compile (or load from cache) every kernel by running a minute model in this process.

    Workers then load the cached machine code instead of each compiling it again.
    """
    raw_cfg = load_config(preset="tiny").to_dict()
    raw_cfg["sweep"].update(n_runs=1, n_layers=2, throw_m=20.0, dip_deg=60.0)
    # 1 m/s: the run outlasts one damping relaxation time (demseis.generator.engines.physics)
    raw_cfg["model"].update(n_snapshots=2, width_m=300.0, height_m=200.0, wall_speed_m_s=1.0)
    run_shard(parse_config(raw_cfg), 0)


def run_cost(cfg: Config, run: int) -> float:
    """Relative cost of run ``run`` by its engine
    (:meth:`demseis.generator.engines.Engine.cost`); the sweep starts the costliest runs
    first."""
    return get_engine(cfg.model.engine).cost(cfg, run_params(cfg, run))


def human_bytes(n: float) -> str:
    """``n`` bytes in the largest binary unit that keeps the number >= 1: ``"69.0 TiB"``."""
    units = ("bytes", "KiB", "MiB", "GiB", "TiB", "PiB", "EiB")
    k = 0
    while n >= 1024 and k < len(units) - 1:
        n /= 1024
        k += 1
    return f"{n:,.0f} {units[k]}" if k == 0 else f"{n:,.1f} {units[k]}"


def dry_run_plan(cfg: Config, pending: int | None = None, why: str = "") -> list[str]:
    """Human lines describing the sweep without computing it: ``pending`` runs of the
    config's (default all; :func:`pending_runs` of an existing store), ``why`` said beside."""
    grid = grid_of(cfg)
    S = cfg.samples_per_run
    n_runs = cfg.sweep.n_runs if pending is None else pending
    h, w = sample_shape(cfg)
    bytes_per_sample = sum(np.dtype(d).itemsize for d in array_dtypes(cfg).values()) * h * w
    engine = get_engine(cfg.model.engine)
    what, secs = engine.describe(cfg)
    return [
        f"config: {cfg.name} (seed {cfg.sweep.seed})",
        f"{cfg.model.engine} runs: {n_runs} to compute (of {cfg.sweep.n_runs}"
        + (f"; {why}" if why else "") + f"); {what}",
        f"samples: {n_runs * S} ({cfg.model.n_snapshots} snapshots x "
        f"{cfg.renders_per_run_snapshot} renders per run)",
        f"sample shape: {h} x {w} ({domain_text(cfg)}; {grid.cell_m:g} m cells"
        + ("; " + ", ".join(sorted(cfg.sampling)) + " drawn per run, sections cropped to it"
           if cfg.sampling else "") + "); arrays: "
        + ", ".join(f"{k} {v}" for k, v in array_dtypes(cfg).items()),
        f"size on disk: at most {human_bytes(n_runs * S * bytes_per_sample)} (uncompressed)"
        + (" plus particle snapshots" if engine.particles else ""),
        f"estimated time: up to ~{secs * n_runs / 60:,.1f} core-minutes "
        f"(~{secs:,.0f} s per run on one core at most; divide by the worker count for wall time)",
    ]


def run_sweep(cfg: Config, out: str | Path, **options: Any) -> SweepSummary:
    """Run (or resume) the sweep of ``cfg`` into the store ``out``, holding its writer lock.

    A second writer of ``out`` is refused with StoreError naming the holder; only this driver
    holds the lock, the dask workers write their shards (see demseis.datasets.lock). The
    options are those of :func:`_run_sweep`.
    """
    with writer_lock(out, "demseis generate"), interrupts.watched():
        return _run_sweep(cfg, out, **options)


def _run_sweep(
    cfg: Config,
    out: str | Path,
    *,
    workers: int | None = None,
    scheduler: str | None = None,
    overwrite: bool = False,
    progress: bool = True,
    retries: int = 2,
) -> SweepSummary:
    """Run (or resume) the sweep of ``cfg`` into the store ``out`` (the caller holds its lock).

    Parameters
    ----------
    workers : number of LocalCluster worker processes (default: all cores). ``0`` runs every
        task in this process without dask (useful for debugging).
    scheduler : address of an existing dask scheduler; overrides ``workers``.
    overwrite : replace an existing store written with another config.
    progress : show a progress bar on stderr.
    retries : dask retries of a task whose worker died.
    """
    out = Path(out)
    t0 = time.perf_counter()
    cluster = None
    if workers != 0 or scheduler is not None:  # else every run in this process, no dask
        import demseis.generator.sweep.cluster as cluster
    remote = cluster.connect(scheduler) if scheduler is not None else None  # before writing
    existed = out.exists()
    try:
        with sigint_deferred():  # a store is created whole: Ctrl-C waits for the metadata
            status = prepare_store(cfg, out, overwrite=overwrite)
    except BaseException:
        if remote is not None:
            remote.close()
        raise
    pending = [int(i) for i in np.flatnonzero(status != 1)]
    summary = SweepSummary(store=str(out), n_shards=len(status), samples_per_shard=cfg.samples_per_run,
                           done_before=len(status) - len(pending))
    if existed and pending:  # done flags set on shards that failed their checksums
        flagged = shard_status(out)
        summary.damaged = [int(i) for i in np.flatnonzero((flagged == 1) & (status != 1))]
        # before any of them is written again: the index holds no entry a worker may replace
        update_index(out, done=(status == 1), shards=pending)
    summary.phase_seconds["prepare"] = time.perf_counter() - t0
    cfg_dict = cfg.to_dict()
    bar = _progress_bar(len(pending) * cfg.samples_per_run, progress and bool(pending))
    try:
        if pending:
            if cluster is None:
                t_compute = time.perf_counter()
                for shard in pending:
                    interrupts.raise_if_interrupted()  # one swallowed where it landed
                    _account(summary, bar, shard_task(str(out), cfg_dict, shard))
                summary.compute_seconds = time.perf_counter() - t_compute
                summary.phase_seconds["compute"] = summary.compute_seconds
            else:
                # absolute: a worker's working directory is its forkserver's, which may differ
                # from this process's (a notebook that changed directory since)
                task = functools.partial(shard_task, str(out.absolute()), cfg_dict)
                summary.compute_seconds = cluster.run_distributed(
                    # longest runs first (LPT): fewer workers idle at the end of unequal runs
                    task, sorted(pending, key=lambda s: -run_cost(cfg, s)),
                    on_result=lambda result: _account(summary, bar, result),
                    on_failure=summary.failed.__setitem__, warm=warm_numba_cache,
                    phase_seconds=summary.phase_seconds, workers=workers, remote=remote,
                    retries=retries)
    finally:
        bar.close()
        if remote is not None and not pending:
            remote.close()
    t_fin = time.perf_counter()
    # every run was written (none failed): a Ctrl-C now leaves nothing to resume
    with sigint_deferred(KeyboardInterrupt if summary.failed else interrupts.Finished):
        record_failures(out, summary.failed)
        finalize_store(out)
    summary.phase_seconds["finalize"] = time.perf_counter() - t_fin
    summary.seconds = time.perf_counter() - t0
    return summary


def describe_os_error(exc: OSError, path: str | Path) -> str:
    """``PATH: cause`` for a filesystem error (the path it names, else ``path``)."""
    where = exc.filename if exc.filename is not None else path
    return f"{where}: {exc.strerror or exc}"


def _account(summary: SweepSummary, bar: Any, result: dict[str, Any]) -> None:
    """Book one finished task's result (written shard, or a run recorded as failed).

    A shard that could not be written (disk full, read-only) stops the sweep with a
    :class:`StoreError`: its done flag is not set, so the same command resumes it later.
    """
    if "os_error" in result:
        raise StoreError(f"cannot write run {result['shard']}: {result['os_error']}; fix that "
                         "(free space, permissions) and run the same command to resume")
    if "error" in result:
        summary.failed[result["shard"]] = result["error"]
    else:
        summary.tasks.append(result)
        summary.completed.append(result["shard"])
        if result.get("no_fault"):
            summary.no_fault.append(result["shard"])
        if result.get("dem_attempt"):
            summary.stabilised[result["shard"]] = result["dem_attempt"]
        bar.update(result["samples"])
        if time.perf_counter() - summary.index_updated > INDEX_EVERY_S:
            # readers of a store being written read the shards the index lacks one by one
            update_index(summary.store, shards=summary.completed[summary.indexed:])
            summary.indexed = len(summary.completed)
            summary.index_updated = time.perf_counter()


#: seconds between the driver's updates of the parameter table's index while a sweep runs
#: (and once at its end: finalize_store)
INDEX_EVERY_S = 60.0

def _progress_bar(total: int, enabled: bool, desc: str = "generate") -> Any:
    return tqdm(total=total, unit="sample", desc=desc, disable=not enabled,
                file=sys.stderr, dynamic_ncols=True)
