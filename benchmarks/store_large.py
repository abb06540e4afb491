"""A large store made by the real sweep, measured against the runs done (10^2 ... 10^4).

Runs ``demseis generate`` (a preset, an engine, ``--runs`` runs, ``--workers`` processes) in
its own process group. Each time the runs done cross a checkpoint (``--at``), the whole sweep
is paused (SIGSTOP to its process group, SIGCONT after), so every measure is taken on an
otherwise idle machine, and one JSON line is printed:

- ``done_runs``, ``sweep_s`` (wall seconds the sweep ran, pauses excluded),
  ``s_per_run`` (``sweep_s / done_runs``: wall time per run with all workers) and
  ``s_per_run_since`` (the same over the runs since the last checkpoint);
- ``files``, ``bytes`` (the whole store) and per done run;
- ``info_s``: ``demseis info STORE`` as a user runs it (a new process: imports included);
- ``open_dataset_s``: ``FaultSegDataset(path)`` in this process (median of 3);
- ``where_s``: the same with ``where={"freq_hz": (30, None)}``;
- ``samples_per_s``: a ``DataLoader`` (batch 16, shuffled, no workers) over ``--samples``
  random samples (seismic and fault), so most batches touch 16 shards (after one untimed
  batch of others: first calls).

The parameter index lags up to a minute behind the sweep (the driver updates it every 60 s),
so a checkpoint reads the newest shards from their own chunks, as any reader during a sweep.
A rerun with the same ``--out`` resumes the sweep (``generate`` completes missing shards) and
measures again the checkpoints not yet passed. With ``--plot FILE.png`` it draws a JSONL file
of these lines (``--plot-from``) instead.

    PYTHONPATH=$PWD python benchmarks/store_large.py --out /scratch/k.zarr [--runs 10000]
        [--preset field] [--engine kinematic] [--workers 2] [--at 100,300,1000,3000,10000]
    python benchmarks/store_large.py --plot docs/figures/store_large.png --plot-from L.jsonl
"""

from __future__ import annotations

import argparse
import json
import os
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

from store_done_scale import _tree  # noqa: E402  (benchmarks/ is on sys.path)
from store_scale import _median_s  # noqa: E402


def _done_runs(path: Path) -> int:
    """Done shards: the files of the done-flag array (a pending flag has no file)."""
    flags = path / "shard_done" / "c"
    return len(os.listdir(flags)) if flags.is_dir() else 0


def _measure(path: Path, samples: int) -> dict[str, float]:
    import numpy as np
    import torch

    from demseis.datasets import FaultSegDataset

    files, nbytes = _tree(path)
    t = time.perf_counter()
    subprocess.run([sys.executable, "-m", "demseis", "info", str(path)], check=True,
                   stdout=subprocess.DEVNULL)
    info_s = time.perf_counter() - t
    out = {"files": files, "bytes": nbytes, "info_s": round(info_s, 3),
           "open_dataset_s": round(_median_s(lambda: FaultSegDataset(path), 3), 4),
           "where_s": round(_median_s(
               lambda: FaultSegDataset(path, where={"freq_hz": (30, None)}), 3), 4)}
    ds = FaultSegDataset(path, ("seismic",), ("fault",))
    rng = np.random.default_rng(0)
    pick = rng.choice(len(ds), size=min(samples + 16, len(ds)), replace=False).tolist()
    for _x, _y in torch.utils.data.DataLoader(torch.utils.data.Subset(ds, pick[:16]),
                                              batch_size=16):
        pass  # first calls (codecs, torch) not timed
    pick = pick[16:]
    loader = torch.utils.data.DataLoader(torch.utils.data.Subset(ds, pick), batch_size=16,
                                         shuffle=True, num_workers=0)
    t = time.perf_counter()
    n = sum(int(x.shape[0]) for x, _y in loader)
    out["samples_per_s"] = round(n / (time.perf_counter() - t), 1)
    return out


def _plot(lines: list[dict], png: str) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    engines = sorted({r["engine"] for r in lines})
    panels = [("files_per_run", "files per run"), ("s_per_run", "sweep wall s per run"),
              ("info_s", "demseis info, s"), ("open_dataset_s", "FaultSegDataset(path), s"),
              ("samples_per_s", "DataLoader samples/s")]
    fig, axes = plt.subplots(1, len(panels), figsize=(3.2 * len(panels), 2.8))
    for ax, (key, label) in zip(axes, panels):
        for engine in engines:
            rows = [r for r in lines if r["engine"] == engine]
            ax.plot([r["done_runs"] for r in rows], [r[key] for r in rows], "o-", label=engine)
        ax.set_xscale("log")
        ax.set_xlabel("runs done")
        ax.set_title(label, fontsize=9)
        ax.set_ylim(bottom=0)
    axes[0].legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(png, dpi=110)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", help="store path (kept; rerun to resume)")
    ap.add_argument("--runs", type=int, default=10000)
    ap.add_argument("--preset", default="field")
    ap.add_argument("--engine", default="kinematic")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--at", default="100,300,1000,3000,10000")
    ap.add_argument("--samples", type=int, default=256)
    ap.add_argument("--plot", default=None, metavar="FILE.png")
    ap.add_argument("--plot-from", default=None, metavar="LINES.jsonl")
    args = ap.parse_args()
    if args.plot:
        if not args.plot_from:
            ap.error("--plot needs --plot-from LINES.jsonl")
        rows = [json.loads(s) for s in Path(args.plot_from).read_text().splitlines()
                if s.startswith("{")]
        _plot([r for r in rows if "sweep_s" in r], args.plot)
        return
    if not args.out:
        ap.error("--out is required")
    path = Path(args.out)
    cfg = Path(tempfile.mkdtemp(prefix="demseis_large_")) / "c.toml"
    cfg.write_text(f'[sweep]\nn_runs = {args.runs}\n[model]\nengine = "{args.engine}"\n')
    checkpoints = [int(v) for v in args.at.split(",") if int(v) <= args.runs]
    checkpoints = [c for c in checkpoints if c > _done_runs(path)]
    cmd = [sys.executable, "-m", "demseis", "generate", "--preset", args.preset, str(cfg),
           "--out", str(path), "--workers", str(args.workers), "--quiet"]
    proc = subprocess.Popen(cmd, start_new_session=True, stdout=sys.stderr)  # stdout: JSON only
    swept = 0.0
    t0 = time.perf_counter()
    last = (_done_runs(path), 0.0)
    while checkpoints:
        finished = proc.poll() is not None
        done = _done_runs(path)
        # the last checkpoint waits for the sweep's end (its index and metadata written)
        if (done >= checkpoints[0] and checkpoints[0] < args.runs) or finished:
            if not finished:
                os.killpg(proc.pid, signal.SIGSTOP)
            swept += time.perf_counter() - t0
            done = _done_runs(path)
            row: dict[str, Any] = {"bench": "store_large", "preset": args.preset,
                                   "engine": args.engine, "workers": args.workers,
                                   "done_runs": done, "sweep_s": round(swept, 1),
                                   "s_per_run": round(swept / max(done, 1), 4),
                                   "s_per_run_since": round(
                                       (swept - last[1]) / max(done - last[0], 1), 4)}
            row.update(_measure(path, args.samples))
            row["files_per_run"] = round(row["files"] / max(done, 1), 2)
            row["bytes_per_run"] = round(row["bytes"] / max(done, 1))
            print(json.dumps(row), flush=True)
            last = (done, swept)
            while checkpoints and checkpoints[0] <= done:
                checkpoints.pop(0)
            if finished:
                break
            t0 = time.perf_counter()
            os.killpg(proc.pid, signal.SIGCONT)
        time.sleep(2.0)
    rc = proc.wait()
    if rc != 0:
        raise SystemExit(f"demseis generate exited {rc}")


if __name__ == "__main__":
    main()
