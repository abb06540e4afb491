"""kill -9 once, mid-sweep, through the real ``demseis generate``: of the in-process driver (the
done shards are complete and the same command resumes to the bytes of an uninterrupted run), and
of one dask worker (the sweep retries its task and completes every shard)."""

from __future__ import annotations

import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
import zarr

from demseis.cli import main
from tests.faults._helpers import dask_workers
from tests.generator._helpers import assert_same_bytes


def _generate_cmd(cfg: Path, out: Path, *extra: str) -> list[str]:
    return [sys.executable, "-m", "demseis", "generate", str(cfg), "--preset", "tiny", "--out", str(out),
            "--quiet", *extra]


@pytest.mark.slow
def test_interrupted_then_resumed_is_identical(tmp_path):
    cfg = tmp_path / "c.toml"
    cfg.write_text("[sweep]\nn_runs = 6\n")
    ref = tmp_path / "ref.zarr"
    subprocess.run(_generate_cmd(cfg, ref, "--workers", "0"), check=True, capture_output=True)
    out = tmp_path / "int.zarr"
    proc = subprocess.Popen(_generate_cmd(cfg, out, "--workers", "0"), stdout=subprocess.DEVNULL,
                            stderr=subprocess.DEVNULL)
    done = 0
    deadline = time.time() + 120
    while time.time() < deadline and proc.poll() is None:
        try:
            done = int((zarr.open_array(str(out / "shard_done"), mode="r")[:] == 1).sum())
        except Exception:
            done = 0
        if done >= 1:
            break
        time.sleep(0.02)
    proc.send_signal(signal.SIGKILL)
    proc.wait()
    status = zarr.open_array(str(out / "shard_done"), mode="r")[:]
    assert 1 <= int((status == 1).sum()) < 6, f"kill did not land mid-sweep: {status}"
    assert main(["validate", str(out)]) == 0  # done shards are complete
    subprocess.run(_generate_cmd(cfg, out, "--workers", "0"), check=True, capture_output=True)
    assert_same_bytes(ref, out)


@pytest.mark.slow
def test_killed_worker_is_retried(tmp_path):
    """SIGKILL one dask worker process mid-sweep: the sweep still completes every shard."""
    import psutil

    cfg = tmp_path / "c.toml"
    cfg.write_text("[sweep]\nn_runs = 4\nthrow_m = 200\n[model]\nwidth_m = 2400.0\nheight_m = 800.0\n")
    out = tmp_path / "k.zarr"
    proc = subprocess.Popen(_generate_cmd(cfg, out, "--workers", "2"), stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)
    killed = None
    deadline = time.time() + 240
    while time.time() < deadline and proc.poll() is None and killed is None:
        workers = []
        for p in dask_workers(proc.pid):
            try:
                if sum(p.cpu_times()[:2]) > 2.0:  # a forked worker is into its first DEM run
                    workers.append(p)
            except (psutil.NoSuchProcess, psutil.ZombieProcess, psutil.AccessDenied):
                continue
        if workers:
            try:
                workers[0].send_signal(signal.SIGKILL)
                killed = workers[0].pid
            except psutil.NoSuchProcess:
                pass
        time.sleep(0.1)
    stdout, stderr = proc.communicate(timeout=300)
    assert killed is not None, "never found a worker to kill"
    assert proc.returncode == 0, stderr[-2000:]
    assert "4 written now, 0 failed" in stdout
    assert main(["validate", str(out)]) == 0
