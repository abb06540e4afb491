"""What the ``strata`` rendering costs against ``elements``, measured side by side.

One JSON line per measure:

- ``render_run_s``: rendering every sample of run 0 of `quick` (4 snapshots x 3 frequencies,
  states and imaging, no DEM), the median of ``--repeats`` interleaved repeats, in the preset's
  depth domain (10 m cells, 250 traces) and sampled like a survey (4 ms, 25 m traces);
- ``generate_s``: `demseis generate --preset quick` wall time with each rendering
  (``--workers``; one run each, after a warm-up run that compiles the kernels).

    PYTHONPATH=$PWD python benchmarks/strata_cost.py [--repeats 5] [--workers 2] [--no-generate]
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import statistics
import tempfile
import time
from pathlib import Path

from demseis.generator.config.sampling import plan_run
from demseis.generator.config.settings import load_config
from demseis.generator.engines import get_engine
from demseis.generator.render.section import render_run
from demseis.generator.sweep.driver import run_sweep

SURVEY = {"domain": "time", "dt_s": 0.004, "trace_spacing_m": 25.0}


def with_output(cfg, **output):
    return dataclasses.replace(cfg, output=dataclasses.replace(cfg.output, **output))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--no-generate", action="store_true")
    args = ap.parse_args()
    base = load_config(preset="quick")
    engine = get_engine(base.model.engine)
    run = engine.simulate(base, plan_run(base, 0))
    for sampling, extra in (("quick depth", {}), ("survey 4 ms 25 m", SURVEY)):
        cfgs = {r: with_output(base, rendering=r, **extra) for r in ("elements", "strata")}
        times: dict[str, list[float]] = {r: [] for r in cfgs}
        for cfg in cfgs.values():
            render_run(cfg, run, engine)                          # compile, warm caches
        for _ in range(args.repeats):
            for r, cfg in cfgs.items():
                t0 = time.perf_counter()
                render_run(cfg, run, engine)
                times[r].append(time.perf_counter() - t0)
        med = {r: statistics.median(v) for r, v in times.items()}
        print(json.dumps({"measure": "render_run_s", "sampling": sampling,
                          **{r: round(v, 3) for r, v in med.items()},
                          "ratio": round(med["strata"] / med["elements"], 2),
                          "repeats": args.repeats}), flush=True)
    if args.no_generate:
        return
    with tempfile.TemporaryDirectory() as tmp:
        walls = {}
        for r in ("strata", "elements", "strata"):              # the first strata warms up
            cfg = with_output(base, rendering=r)
            t0 = time.perf_counter()
            run_sweep(cfg, Path(tmp) / f"{r}.zarr", workers=args.workers, overwrite=True,
                      progress=False)
            walls[r] = time.perf_counter() - t0
        print(json.dumps({"measure": "generate_s", "preset": "quick", "workers": args.workers,
                          **{r: round(v, 2) for r, v in walls.items()},
                          "ratio": round(walls["strata"] / walls["elements"], 2)}), flush=True)


if __name__ == "__main__":
    main()
