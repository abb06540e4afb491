"""``demseis render``: new sections from a store's particle snapshots, without the DEM."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np

from demseis.errors import StoreError
from demseis.generator.config import Config, parse_config
from demseis.generator.pipeline import render_run, run_info
from demseis.generator.sampling import plan_run
from demseis.generator.sweep import SweepSummary, _progress_bar, prepare_store


def rerender_config(source_cfg: dict[str, Any], freqs_hz: list[float], snrs_db: list[float],
                    noise_kind: str) -> Config:
    """The source config with its render parameters replaced (run parameters unchanged)."""
    raw = {k: (dict(v) if isinstance(v, dict) else v) for k, v in source_cfg.items()}
    raw["sweep"] = dict(raw["sweep"])
    raw["sweep"]["freq_hz"] = [f for f in freqs_hz]
    raw["sweep"]["snr_db"] = ["inf" if math.isinf(s) else s for s in snrs_db]
    raw["sweep"]["noise_kind"] = noise_kind
    raw["sweep"]["renders_per_snapshot"] = 1
    raw["name"] = f"{source_cfg.get('name', 'demseis')}-render"
    return parse_config(raw, source="re-render config")


def rerender(source: str | Path, out: str | Path, *, freqs_hz: list[float], snrs_db: list[float],
             noise_kind: str = "white", overwrite: bool = False, progress: bool = True) -> SweepSummary:
    """Write a new store with every done run of ``source`` re-rendered.

    Runs that are not done in the source are recorded as failed in the new store.
    """
    import time

    from demseis.datasets import (
        finalize_store,
        open_store,
        read_particles,
        record_failures,
        shard_status,
        write_shard,
    )

    t0 = time.perf_counter()
    src = Path(source)
    root = open_store(src)
    if Path(out).resolve() == src.resolve():
        raise StoreError("--out must differ from the source store")
    cfg = rerender_config(dict(root.attrs)["config"], freqs_hz, snrs_db, noise_kind)
    src_status = shard_status(src)
    status = prepare_store(cfg, out, overwrite=overwrite)
    pending = [int(i) for i in np.flatnonzero(status != 1)]
    summary = SweepSummary(store=str(out), n_shards=len(status), samples_per_shard=cfg.samples_per_run,
                           done_before=len(status) - len(pending))
    bar = _progress_bar(len(pending) * cfg.samples_per_run, progress, desc="render")
    try:
        for run in pending:
            if src_status[run] != 1:
                summary.failed[run] = "not done in the source store"
                continue
            spec = plan_run(cfg, run)
            snaps = read_particles(src, run)
            p = spec.params
            info = run_info(cfg, p)
            data = render_run(cfg, spec, snaps, info)
            write_shard(out, run, data.arrays, data.params, data.snapshots)
            summary.completed.append(run)
            bar.update(cfg.samples_per_run)
    finally:
        bar.close()
    record_failures(out, summary.failed)
    finalize_store(out)
    summary.seconds = time.perf_counter() - t0
    return summary
