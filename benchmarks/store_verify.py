"""Cost of the store's integrity checks: what a resumed sweep pays before it skips done shards.

Builds a temporary store like the loader benchmark's (band-limited float32 sections, raw, plus
Blosc fault masks; every chunk with its crc32c), then times, with a warm page cache, the median
over ``--repeats`` of:

- ``shard_status(path)``: the done flags only;
- ``shard_status(path, verify=True)``: every checksum of every done shard (what ``generate``
  does on resume);
- ``validate_store(path)``: checksums plus decoding and value checks.

Prints one JSON line with the seconds and the verified GB/s.

    PYTHONPATH=$PWD python benchmarks/store_verify.py [--shards 24 --samples-per-shard 32]
"""

from __future__ import annotations

import argparse
import json
import shutil
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # demseis_dev: the checkout's

import numpy as np

from demseis.datasets import create_store, shard_status, validate_store, write_shard
from demseis_dev.bench import median_ms, synthetic_shard


def _seconds(fn, repeats: int) -> float:
    """Median wall-clock seconds of ``fn()`` over ``repeats`` calls."""
    return median_ms(fn, repeats)[0] / 1e3


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--shards", type=int, default=24)
    ap.add_argument("--samples-per-shard", type=int, default=32)
    ap.add_argument("--shape", type=int, nargs=2, default=(277, 500))
    ap.add_argument("--repeats", type=int, default=5)
    args = ap.parse_args()
    h, w = args.shape
    s = args.samples_per_shard
    tmp = Path(tempfile.mkdtemp(prefix="demseis_verify_"))
    try:
        store = tmp / "v.zarr"
        create_store(store, n_shards=args.shards, samples_per_shard=s, shape=(h, w),
                     arrays=["seismic", "fault"], params={"run_id": "int32"},
                     attrs={"config": {}, "grid": {"x0_m": 0.0, "top_m": 0.0, "cell_m": 10.0,
                                                   "nz": h, "nx": w}})
        rng = np.random.default_rng(0)
        for k in range(args.shards):
            write_shard(store, k, synthetic_shard(rng, s, h, w), {"run_id": np.full(s, k)})
        nbytes = sum(f.stat().st_size for f in store.rglob("*") if f.is_file())
        shard_status(store, verify=True)  # warm the page cache
        flags = _seconds(lambda: shard_status(store), args.repeats)
        verify = _seconds(lambda: shard_status(store, verify=True), args.repeats)
        validate = _seconds(lambda: validate_store(store), max(1, args.repeats // 2))
        print(json.dumps({
            "benchmark": "store_verify",
            "n_shards": args.shards,
            "n_samples": args.shards * s,
            "store_mb": round(nbytes / 2**20, 1),
            "flags_s": round(flags, 4),
            "verify_s": round(verify, 3),
            "verify_gb_per_s": round(nbytes / verify / 1e9, 2),
            "verify_ms_per_shard": round(1e3 * verify / args.shards, 2),
            "validate_s": round(validate, 3),
        }))
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


if __name__ == "__main__":
    main()
