"""A sweep on an existing dask cluster (``--scheduler``) against the built-in local workers.

Starts a multi-process dask cluster of its own (a scheduler and ``--workers`` single-threaded
worker processes, as `dask scheduler` and `dask worker` on other machines would be; the store
on the filesystem they share), runs ``demseis generate --scheduler ADDRESS`` on it, then the
same sweep with ``--workers N``, and prints one JSON line: both walls and whether the two
stores hold the same bytes.

What a run across machines needs (docs/store.md, "Scale"): demseis installed on every worker
with ``NUMBA_NUM_THREADS=1``, and the output path on a filesystem every worker and the driver
see at the same path; the driver holds the store's writer lock, the workers write their shards.

    PYTHONPATH=$PWD python benchmarks/scheduler_cluster.py [--preset tiny] [--workers 2]
"""

from __future__ import annotations

import argparse
import hashlib
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path


def digest(root: Path) -> str:
    h = hashlib.sha256()
    for p in sorted(root.rglob("*")):
        rel = p.relative_to(root)
        if p.is_file() and not any(part.startswith(".") for part in rel.parts):
            h.update(str(rel).encode())
            h.update(p.read_bytes())
    return h.hexdigest()


def generate(args: list[str]) -> float:
    t0 = time.perf_counter()
    subprocess.run([sys.executable, "-m", "demseis", "generate", *args, "--quiet"], check=True,
                   capture_output=True)
    return time.perf_counter() - t0


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--preset", default="tiny")
    ap.add_argument("--workers", type=int, default=2)
    args = ap.parse_args()
    from distributed import LocalCluster

    os.environ.setdefault("NUMBA_NUM_THREADS", "1")
    with tempfile.TemporaryDirectory() as tmp:
        a, b = Path(tmp) / "cluster.zarr", Path(tmp) / "local.zarr"
        with LocalCluster(n_workers=args.workers, threads_per_worker=1, processes=True,
                          dashboard_address=None) as cluster:
            wall_cluster = generate(["--preset", args.preset, "--out", str(a), "--scheduler",
                                     cluster.scheduler_address])
        wall_local = generate(["--preset", args.preset, "--out", str(b), "--workers",
                               str(args.workers)])
        print(json.dumps({"measure": "scheduler_cluster", "preset": args.preset,
                          "workers": args.workers, "cluster_wall_s": round(wall_cluster, 2),
                          "local_wall_s": round(wall_local, 2),
                          "same_bytes": digest(a) == digest(b)}))


if __name__ == "__main__":
    main()
