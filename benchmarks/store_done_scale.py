"""Files, bytes and opening time of a store against the runs done in it (10^2 ... 10^4).

A store of the tiny preset with the kinematic engine, planned for the largest ``--done``; one
run is simulated (``shard_task``) and its samples and parameters are written again as every
other run (``write_shard``, ``run_id`` set to the shard), so the store holds what a sweep
writes, at the cost of its writes only. At each size of ``--done`` the driver's end of a sweep
runs (``finalize_store``: the parameter index, consolidated metadata), then one JSON line per
measure:

- ``files_per_run``, ``bytes_per_run``: files and bytes the runs added to the store (particles
  are not written: the kinematic engine stores none);
- ``write_s``: median seconds of one ``write_shard``;
- ``open_store``: ``demseis.open(path)`` and one parameter over every sample;
- ``info``: the lines of ``demseis info`` (``store_summary`` and the fault distribution);
- ``open_dataset``: ``FaultSegDataset(path)`` (done flags, every parameter of the done samples);
- ``where``: ``FaultSegDataset(path, where={"freq_hz": (30, None)})``;
- ``open_dataset_no_index`` (stores with an index): the same with the index files removed, as
  after a sweep cut short before the driver updated it.

Each time is the median of ``--repeats`` calls in this process (page cache warm). Runs with
the code of any version that has ``prepare_store``, ``shard_task`` and ``write_shard`` (the
"before" figures of docs/store.md come from the commit before the parameter table).

``--store PATH`` measures an existing store instead, cold and warm: before each cold call the
page cache is dropped (``/proc/sys/vm/drop_caches``, as root; without the right, every call
is warm and the line says ``"cold": null``), and one JSON line per measure gives the median:
``info_cli`` (``python -m demseis info PATH`` in a new process, imports included),
``imports_cli`` (that process importing what ``info`` imports, without reading the store),
``info`` and ``open_dataset`` as above. Run it with two checkouts on ``PYTHONPATH`` to compare
code side by side on one store.

    PYTHONPATH=$PWD python benchmarks/store_done_scale.py [--done 100,1000,10000] [--repeats 3]
    PYTHONPATH=$PWD python benchmarks/store_done_scale.py --store S.zarr [--repeats 3]
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from store_scale import CONFIG, _median_s  # noqa: E402  (benchmarks/ is on sys.path)


def _tree(path: Path) -> tuple[int, int]:
    """(files, bytes) under ``path``."""
    n = b = 0
    for top, _dirs, files in os.walk(path):
        for f in files:
            n += 1
            b += os.path.getsize(os.path.join(top, f))
    return n, b


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--done", default="100,1000,10000")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--dir", default=None, help="where to write the store (default: a temp dir)")
    ap.add_argument("--store", default=None, help="measure this existing store, cold and warm")
    args = ap.parse_args()
    if args.store:
        _cold_and_warm(Path(args.store), args.repeats)
        return

    import numpy as np

    import demseis
    from demseis.datasets import FaultSegDataset, finalize_store, read_sample, write_shard
    from demseis.datasets.layout import SCHEMA_VERSION
    from demseis.datasets.read import read_params, store_summary
    from demseis.generator.config.settings import load_config, parse_config
    from demseis.generator.sweep.driver import prepare_store, shard_task
    from demseis.generator.sweep.faultinfo import fault_distribution

    sizes = sorted(int(v) for v in args.done.split(","))
    tmp = Path(tempfile.mkdtemp(prefix="demseis_done_", dir=args.dir))
    try:
        (tmp / "c.toml").write_text(CONFIG)
        raw = load_config(str(tmp / "c.toml"), preset="tiny").to_dict()
        raw["sweep"]["n_runs"] = sizes[-1]
        cfg = parse_config(raw)
        path = tmp / "s.zarr"
        prepare_store(cfg, path)
        files0, bytes0 = _tree(path)
        shard_task(str(path), cfg.to_dict(), 0)
        s = cfg.samples_per_run
        first = [read_sample(path, i) for i in range(s)]
        arrays = {n: np.stack([smp.arrays[n] for smp in first]) for n in first[0].arrays}
        stored = read_params(path)
        params = {n: np.asarray(stored[n][:s]) for n in stored}
        write_s = []
        done = 1
        for n in sizes:
            for k in range(done, n):
                params["run_id"] = np.full(s, k)
                t = time.perf_counter()
                write_shard(path, k, arrays, params)
                write_s.append(time.perf_counter() - t)
            done = n
            finalize_store(path)
            files, nbytes = _tree(path)
            measures = {
                "files_per_run": (files - files0) / n,
                "bytes_per_run": (nbytes - bytes0) / n,
                "write_s": statistics.median(write_s),
                "open_store": _median_s(lambda: demseis.open(path).params["run_id"],
                                        args.repeats),
                "info": _median_s(lambda: (store_summary(path), fault_distribution(path)),
                                  args.repeats),
                "open_dataset": _median_s(lambda: FaultSegDataset(path), args.repeats),
                "where": _median_s(lambda: FaultSegDataset(path, where={"freq_hz": (30, None)}),
                                   args.repeats),
            }
            index = [f for name in ("params_index", "params_index_files")
                     if (path / name).is_dir() for f in (path / name).glob("c.*")]
            if index:
                saved = {f: f.read_bytes() for f in index}
                for f in index:
                    f.unlink()
                measures["open_dataset_no_index"] = _median_s(lambda: FaultSegDataset(path),
                                                              args.repeats)
                for f, data in saved.items():
                    f.write_bytes(data)
            for name, value in measures.items():
                print(json.dumps({"measure": name, "done_runs": n, "schema_version": SCHEMA_VERSION,
                                  "value": round(value, 4 if name != "bytes_per_run" else 0)}),
                      flush=True)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


def _drop_page_cache() -> bool:
    """Drop the page cache (root only); whether it was dropped."""
    try:
        os.sync()
        Path("/proc/sys/vm/drop_caches").write_text("3\n")
        return True
    except OSError:
        return False


def _cold_and_warm(path: Path, repeats: int) -> None:
    """One JSON line per measure and state (cold, warm) on the store ``path``."""
    from demseis.datasets import FaultSegDataset
    from demseis.datasets.read import store_summary
    from demseis.generator.sweep.faultinfo import fault_distribution

    def cli(code: str) -> float:
        t = time.perf_counter()
        subprocess.run([sys.executable, "-c", code], check=True, stdout=subprocess.DEVNULL)
        return time.perf_counter() - t

    measures = {
        "info_cli": lambda: cli(f"from demseis.cli import main; main(['info', {str(path)!r}])"),
        "imports_cli": lambda: cli("import demseis.cli.commands.store"),
        "info": lambda: _timed(lambda: (store_summary(path), fault_distribution(path))),
        "open_dataset": lambda: _timed(lambda: FaultSegDataset(path)),
    }
    for name, run in measures.items():
        for state in ("cold", "warm"):
            times, dropped = [], None
            for _ in range(repeats):
                if state == "cold":
                    dropped = _drop_page_cache()
                times.append(run())
            print(json.dumps({"measure": name, "store": str(path), "state": state,
                              "cold": dropped if state == "cold" else False,
                              "value": round(statistics.median(times), 3)}), flush=True)


def _timed(fn) -> float:
    t = time.perf_counter()
    fn()
    return time.perf_counter() - t


if __name__ == "__main__":
    main()
