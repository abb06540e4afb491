"""kill -9 at random moments, 20+ trials: a dask worker (the sweep retries its task) or the
driver with its whole process group (the store keeps every done shard; the same command
resumes). After each trial a resume gives the bytes of an uninterrupted run."""

from __future__ import annotations

import os
import random
import signal
import subprocess
import sys
import time

import psutil
import pytest

from demseis.cli import main
from tests.faults._helpers import ROOT, dask_workers, spawn
from tests.generator._helpers import assert_same_bytes

N_TRIALS = 20


def _kill_a_worker(proc: subprocess.Popen, delay_s: float) -> bool:
    """SIGKILL one worker process of the sweep ``delay_s`` after the first worker exists."""
    t_first = None
    while proc.poll() is None:
        workers = dask_workers(proc.pid)
        if workers:
            t_first = t_first or time.time()
            if time.time() - t_first >= delay_s:
                try:
                    workers[0].send_signal(signal.SIGKILL)
                    return True
                except psutil.NoSuchProcess:
                    pass
        time.sleep(0.02)
    return False


def _seconds(args: list[str]) -> float:
    """Wall seconds of an uninterrupted ``demseis ARGS`` run, as the trials start it."""
    t0 = time.perf_counter()
    proc = spawn(args)
    _, err = proc.communicate(timeout=300)
    assert proc.returncode == 0, err[-2000:]
    return time.perf_counter() - t0


@pytest.mark.slow
def test_kill9_worker_and_driver_at_random_moments(tmp_path):
    """The kill moments are drawn within the measured length of an uninterrupted sweep of the
    same kind (fixed delays landed after a fast machine's sweep had ended, and the test then
    checked resumes of complete stores only)."""
    cfg = tmp_path / "c.toml"
    cfg.write_text("[sweep]\nn_runs = 4\n")
    ref = tmp_path / "ref.zarr"
    assert main(["generate", str(cfg), "--preset", "tiny", "--out", str(ref), "--workers", "0",
                 "--quiet"]) == 0
    seconds = {w: _seconds(["generate", str(cfg), "--preset", "tiny", "--out",
                            str(tmp_path / f"len{w}.zarr"), "--workers", w, "--quiet"])
               for w in ("0", "2")}
    rng = random.Random(14)
    outcomes = []
    for trial in range(N_TRIALS):
        out = tmp_path / f"t{trial}.zarr"
        target = ("worker", "driver", "driver-w0")[trial % 3]
        workers = "0" if target == "driver-w0" else "2"
        args = ["generate", str(cfg), "--preset", "tiny", "--out", str(out), "--workers", workers,
                "--quiet"]
        proc = spawn(args)
        if target == "worker":
            # counted from the first worker's start, which comes after the cluster's
            hit = _kill_a_worker(proc, rng.uniform(0.0, 0.5) * seconds["2"])
            out_text, err = proc.communicate(timeout=300)
            # the killed worker's task was retried; the summary on stdout names a failed run
            assert proc.returncode == 0, (out_text[-2000:], err[-2000:])
        else:
            time.sleep(rng.uniform(0.05, 0.95) * seconds[workers])
            hit = proc.poll() is None
            try:
                os.killpg(proc.pid, signal.SIGKILL)
            except ProcessLookupError:
                pass
            proc.communicate(timeout=60)
        outcomes.append((target, hit))
        if out.exists():
            assert main(["validate", str(out)]) in (0, 1, 2)  # an answer, never a crash
        res = subprocess.run([sys.executable, "-m", "demseis", *args[:-3], "--workers", "0",
                              "--quiet"], cwd=ROOT, capture_output=True, text=True)
        assert res.returncode == 0, (trial, target, res.stderr[-2000:])
        assert_same_bytes(ref, out)
        assert main(["validate", str(out)]) == 0
    # the kills must have landed while the sweep ran, most of the time
    assert sum(hit for _, hit in outcomes) >= N_TRIALS // 2, outcomes
