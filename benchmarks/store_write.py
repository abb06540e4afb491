"""Seconds per ``write_shard`` of a `quick` shard: this checkout against another one's, interleaved.

Loads ``write_shard`` from another checkout's ``demseis/datasets/write.py`` (``--baseline``,
e.g. the previous main, which wrote every chunk through zarr) beside this one's, writes the
same shards (``run_shard`` of the `quick` preset, kinematic engine by default, or the DEM
engine's with particles) into fresh stores with each, alternating A B A B, and prints one JSON
line: the median seconds of each, their ratio, and whether the two stores' files are
byte-identical.

    git worktree add /tmp/prev main
    PYTHONPATH=$PWD python benchmarks/store_write.py --baseline /tmp/prev --repeats 9
"""

from __future__ import annotations

import argparse
import dataclasses
import hashlib
import importlib.util
import json
import platform
import sys
import tempfile
import time
from pathlib import Path

import numpy as np


def _load_write_shard(checkout: Path):
    """``write_shard`` of ``checkout``'s writing module (``demseis/datasets/write.py``, or
    ``store.py`` in checkouts from before the store was split), loaded under another module
    name (it imports only ``demseis`` modules whose API both checkouts share)."""
    folder = checkout / "demseis" / "datasets"
    path = folder / "write.py" if (folder / "write.py").exists() else folder / "store.py"
    spec = importlib.util.spec_from_file_location("_baseline_store", path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # dataclasses look their module up there
    spec.loader.exec_module(module)
    return module.write_shard


def _digest(path: Path) -> dict[str, str]:
    return {str(f.relative_to(path)): hashlib.sha256(f.read_bytes()).hexdigest()
            for f in sorted(path.rglob("*")) if f.is_file()}


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--baseline", type=Path, required=True, help="another demseis checkout")
    ap.add_argument("--repeats", type=int, default=9)
    ap.add_argument("--engine", choices=("kinematic", "dem"), default="kinematic")
    args = ap.parse_args(argv)

    from demseis.datasets import write_shard
    from demseis.generator.config.settings import load_config
    from demseis.generator.sweep.driver import prepare_store
    from demseis.generator.sweep.pipeline import run_shard

    base = load_config(preset="quick")
    cfg = dataclasses.replace(base, model=dataclasses.replace(base.model, engine=args.engine))
    data = run_shard(cfg, 0)
    shard = (data.arrays, data.params, data.snapshots or None)
    writers = {"baseline": _load_write_shard(args.baseline), "this": write_shard}
    seconds: dict[str, list[float]] = {k: [] for k in writers}
    same = True
    with tempfile.TemporaryDirectory() as tmp:
        for r in range(args.repeats + 1):  # the first round warms imports and caches
            stores = {}
            for name, write in writers.items():
                out = stores[name] = Path(tmp) / f"{name}{r}.zarr"
                prepare_store(cfg, out)
                t0 = time.perf_counter()
                write(out, 0, *shard)
                if r:
                    seconds[name].append(time.perf_counter() - t0)
            same &= _digest(stores["baseline"]) == _digest(stores["this"])
    med = {k: float(np.median(v)) for k, v in seconds.items()}
    print(json.dumps({
        "benchmark": "store_write", "preset": "quick", "engine": args.engine,
        "samples_per_shard": cfg.samples_per_run, "shape": list(data.arrays["seismic"].shape),
        "particles": shard[2] is not None, "repeats": args.repeats,
        "baseline_s": round(med["baseline"], 4), "this_s": round(med["this"], 4),
        "speedup": round(med["baseline"] / med["this"], 1), "identical_files": same,
        "cpu": platform.processor() or platform.machine()}))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
