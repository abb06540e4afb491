"""What the loader's checksum policy costs: each chunk checked once vs on every read (one JSON line).

Builds a temporary store like ``python -m demseis_dev.bench loader`` (band-limited 277x500 sections and fault
masks), then times DataLoader epochs (0 workers, random 256x256 crops, batch 32,
ShardAwareSampler) of two FaultSegDatasets over it, alternating epoch by epoch in one process:

- ``once``: the product: a chunk's crc32c is checked on its first read, not again while its
  shard file is unchanged (docs/store.md, Integrity);
- ``every_read``: the same reader with its "already checked" flags cleared before each epoch,
  so that every crop checks its chunk's crc32c again (what the loader did before).

After one untimed epoch each, ``--repeats`` timed epochs each; medians and their ratio.

    PYTHONPATH=$PWD python benchmarks/loader_checks.py [--shards 24] [--repeats 7]
"""

from __future__ import annotations

import argparse
import json
import shutil
import statistics
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # demseis_dev: the checkout's

import numpy as np


def main() -> None:
    import torch
    from torch.utils.data import DataLoader

    from demseis.datasets import (FaultSegDataset, ShardAwareSampler, create_store, finalize_store,
                                  write_shard)
    from demseis_dev.bench import synthetic_shard

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--shards", type=int, default=24)
    ap.add_argument("--samples-per-shard", type=int, default=32)
    ap.add_argument("--repeats", type=int, default=7)
    args = ap.parse_args()
    torch.set_num_threads(1)
    h, w, s = 277, 500, args.samples_per_shard
    tmp = Path(tempfile.mkdtemp(prefix="demseis_checks_"))
    try:
        store = tmp / "bench.zarr"
        create_store(store, n_shards=args.shards, samples_per_shard=s, shape=(h, w),
                     arrays=["seismic", "fault"], params={"run_id": "int32"},
                     attrs={"config": {"benchmark": "loader_checks"},
                            "grid": {"x0_m": 0.0, "top_m": 0.0, "cell_m": 10.0, "nz": h, "nx": w}})
        rng = np.random.default_rng(0)
        for k in range(args.shards):
            write_shard(store, k, synthetic_shard(rng, s, h, w), {"run_id": np.full(s, k)})
        finalize_store(store)
        sets = {name: FaultSegDataset(store, ("seismic",), ("fault",), crop=256, seed=0)
                for name in ("once", "every_read")}
        loaders = {name: DataLoader(ds, batch_size=32, sampler=ShardAwareSampler(ds, seed=0))
                   for name, ds in sets.items()}

        def epoch(name: str) -> float:
            if name == "every_read":
                for reader in sets[name]._raw.values():
                    for shard in reader._open.values():
                        shard.verified[:] = [False] * len(shard.verified)
            t0 = time.perf_counter()
            n = sum(x.shape[0] for x, _y in loaders[name])
            return n / (time.perf_counter() - t0)

        for name in loaders:
            epoch(name)
        rates: dict[str, list[float]] = {name: [] for name in loaders}
        for _ in range(args.repeats):
            for name in loaders:
                rates[name].append(epoch(name))
        med = {name: statistics.median(r) for name, r in rates.items()}
        print(json.dumps({
            "benchmark": "loader_checks",
            "n_samples": args.shards * s,
            "repeats": args.repeats,
            "once_samples_per_s": round(med["once"], 1),
            "every_read_samples_per_s": round(med["every_read"], 1),
            "once_over_every_read": round(med["once"] / med["every_read"], 3),
            "once_runs": [round(r, 1) for r in rates["once"]],
            "every_read_runs": [round(r, 1) for r in rates["every_read"]],
        }))
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


if __name__ == "__main__":
    main()
