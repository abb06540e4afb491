"""One run → all of its labelled samples (one shard): the one path from an engine to a store.

``run_shard`` looks up the config's engine (:mod:`demseis.generator.engines`), runs it, and
renders its states (:mod:`demseis.generator.render.section`); the sweep writes the result as the run's
shard. Re-rendering (``demseis render`` / ``relabel``) takes the same path from stored particle
snapshots instead of a new simulation.
"""

from __future__ import annotations

import time
from collections.abc import Callable

from demseis.generator.config.sampling import plan_run
from demseis.generator.config.settings import Config
from demseis.generator.engines import get_engine
from demseis.generator.render.section import ShardData, render_run


def run_shard(cfg: Config, run: int, progress: Callable[[float], None] | None = None, *,
              timings: dict[str, float] | None = None) -> ShardData:
    """Run ``run`` with the config's engine and render all its samples; ``timings`` (if given)
    gets ``engine_s`` (the engine's simulation) and ``render_s`` (states, imaging, labels)."""
    t0 = time.perf_counter()
    engine = get_engine(cfg.model.engine)
    result = engine.simulate(cfg, plan_run(cfg, run), progress)
    t1 = time.perf_counter()
    data = render_run(cfg, result, engine)
    if timings is not None:
        timings.update(engine_s=t1 - t0, render_s=time.perf_counter() - t1)
    return data
