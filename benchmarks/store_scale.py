"""Cost of planning, opening and reading a store against its planned size (issue 30).

For stores planned for 10^2 ... 10^6 runs (``--sizes``) of the tiny preset with the kinematic
engine, with
``--done`` runs written (the first ones), prints one JSON line per measure and size:

- ``plan``: creating the store for N runs (``prepare_store``: every array's metadata; what
  ``demseis generate`` does before its first task);
- ``open_store``: ``demseis.open(path)`` and its done mask (``Store.done``);
- ``info``: the lines of ``demseis info`` (``store_summary`` and the fault distribution);
- ``open_dataset``: ``FaultSegDataset(path)`` (done flags, every parameter of the done
  samples);
- ``read_sample``: ``read_sample(path, 0)`` (every array of one sample, checksums checked);
- ``resume_status``: ``shard_status(path, verify=True)`` (what a resumed sweep checks).

Each figure is the median of ``--repeats`` calls in this process (imports warm, page cache
warm). With ``--plot FILE.png`` it also draws the seconds against the planned runs.

    PYTHONPATH=$PWD python benchmarks/store_scale.py [--sizes 100,1000,10000,100000,1000000]
        [--done 10] [--repeats 3] [--plot docs/figures/store_scale.png]
"""

from __future__ import annotations

import argparse
import json
import shutil
import statistics
import tempfile
import time
from pathlib import Path
from typing import Any, Callable

#: the tiny preset (900 x 400 m, 3 snapshots, 6 samples per run of 40 x 90) with the fast
#: kinematic engine; ``n_runs`` is set per size
CONFIG = '[model]\nengine = "kinematic"\n'


def _median_s(fn: Callable[[], Any], repeats: int) -> float:
    times = []
    for _ in range(repeats):
        t = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t)
    return statistics.median(times)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", default="100,1000,10000,100000,1000000")
    ap.add_argument("--done", type=int, default=10)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--plot", default=None, metavar="FILE.png")
    args = ap.parse_args()

    import demseis
    from demseis.datasets import FaultSegDataset, read_sample, shard_status
    from demseis.datasets.read import store_summary
    from demseis.generator.config.settings import load_config, parse_config
    from demseis.generator.sweep.driver import prepare_store, shard_task
    from demseis.generator.sweep.faultinfo import fault_distribution

    rows = []
    tmp = Path(tempfile.mkdtemp(prefix="demseis_scale_"))
    try:
        (tmp / "c.toml").write_text(CONFIG)
        base = load_config(str(tmp / "c.toml"), preset="tiny").to_dict()
        for n in (int(v) for v in args.sizes.split(",")):
            raw = json.loads(json.dumps(base))
            raw["sweep"]["n_runs"] = n
            cfg = parse_config(raw)
            path = tmp / f"s{n}.zarr"
            t = time.perf_counter()
            prepare_store(cfg, path)
            plan = time.perf_counter() - t
            for k in range(min(args.done, n)):
                shard_task(str(path), cfg.to_dict(), k)
            measures = {
                "plan": plan,
                "open_store": _median_s(lambda: demseis.open(path).done, args.repeats),
                "info": _median_s(lambda: (store_summary(path), fault_distribution(path)),
                                  args.repeats),
                "open_dataset": _median_s(lambda: FaultSegDataset(path), args.repeats),
                "read_sample": _median_s(lambda: read_sample(path, 0), args.repeats),
                "resume_status": _median_s(lambda: shard_status(path, verify=True),
                                           args.repeats),
            }
            for name, seconds in measures.items():
                row = {"measure": name, "planned_runs": n, "done_runs": min(args.done, n),
                       "seconds": round(seconds, 4)}
                rows.append(row)
                print(json.dumps(row), flush=True)
            shutil.rmtree(path)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    if args.plot:
        _plot(rows, args.plot)


def _plot(rows: list[dict], out: str) -> None:
    """Seconds of each measure against the planned runs (log-log)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6, 4))
    for name in dict.fromkeys(r["measure"] for r in rows):
        pts = [(r["planned_runs"], r["seconds"]) for r in rows if r["measure"] == name]
        ax.plot(*zip(*pts), marker="o", label=name)
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("planned runs (shards)")
    ax.set_ylabel("seconds (median)")
    ax.set_title(f"store cost against planned size, {rows[0]['done_runs']} runs done")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    Path(out).parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=120)


if __name__ == "__main__":
    main()
