"""Fault injection through the real ``demseis generate``: concurrent writers, kill -9 of the
driver mid-shard, bit flips in done shards. Each trial loses nothing, and a resume gives a store
byte-identical to an uninterrupted run."""

from __future__ import annotations

import json
import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from demseis.datasets import shard_status, validate_store
from demseis.datasets.lock import lock_path
from tests._helpers import ROOT
from tests.datasets._helpers import digest

pytestmark = pytest.mark.slow

MINI = """
name = "mini"
[sweep]
seed = {seed}
n_runs = {n_runs}
dip_deg = [50, 60]
throw_m = 30  # 20 m fails the relaxation-time check of demseis.generator.engines.physics
n_layers = 2
freq_hz = 30
snr_db = [inf, 10]
noise_kind = "band"
[model]
width_m = 300.0
height_m = 200.0
n_snapshots = 2
"""


def _config(dir_: Path, seed: int = 0, n_runs: int = 4) -> Path:
    path = dir_ / f"mini{seed}.toml"
    path.write_text(MINI.format(seed=seed, n_runs=n_runs))
    return path


def _generate(cfg: Path, out: Path, *extra: str, **popen) -> subprocess.Popen:
    return subprocess.Popen(
        [sys.executable, "-m", "demseis", "generate", str(cfg), "--preset", "tiny", "--out",
         str(out), "--workers", "0", "--quiet", *extra],
        cwd=ROOT, env={**os.environ, "PYTHONPATH": str(ROOT)}, stdout=subprocess.PIPE,
        stderr=subprocess.PIPE, text=True, **popen)


def _run(cfg: Path, out: Path) -> subprocess.CompletedProcess:
    p = _generate(cfg, out)
    stdout, stderr = p.communicate(timeout=600)
    return subprocess.CompletedProcess(p.args, p.returncode, stdout, stderr)




@pytest.fixture(scope="module")
def reference(tmp_path_factory):
    """An uninterrupted run of the mini config."""
    d = tmp_path_factory.mktemp("ref")
    cfg = _config(d)
    res = _run(cfg, d / "ref.zarr")
    assert res.returncode == 0, res.stderr
    return cfg, d / "ref.zarr"


def test_two_identical_commands_at_once(tmp_path, reference):
    cfg, ref = reference
    out = tmp_path / "s.zarr"
    a, b = _generate(cfg, out), _generate(cfg, out)
    (_, err_a), (_, err_b) = a.communicate(timeout=600), b.communicate(timeout=600)
    codes = sorted([a.returncode, b.returncode])
    assert codes == [0, 2], (err_a, err_b)
    refused = err_a if a.returncode == 2 else err_b
    assert "is being written by pid" in refused and "demseis generate" in refused
    assert len(refused.strip().splitlines()) == 1  # one line, no traceback
    assert digest(out) == digest(ref)
    assert not lock_path(out).exists()


def _stop_once_locked(p: subprocess.Popen, out: Path, timeout_s: float = 120.0) -> None:
    """SIGSTOP ``p`` as soon as the lock of ``out`` names it: a stopped writer is alive and
    holds the lock, however fast its own work would end (with a fixed head start, a fast
    machine can finish the first writer before the second one looks)."""
    t0 = time.perf_counter()
    while True:
        try:
            holder = json.loads(lock_path(out).read_text())
        except (FileNotFoundError, ValueError):
            holder = None
        if isinstance(holder, dict) and holder.get("pid") == p.pid:
            os.kill(p.pid, signal.SIGSTOP)
            return
        assert p.poll() is None, p.communicate()
        assert time.perf_counter() - t0 < timeout_s
        time.sleep(0.001)


def test_two_configs_at_once(tmp_path, reference):
    _, ref = reference
    out = tmp_path / "s.zarr"
    other = _config(tmp_path, seed=7)
    a = _generate(reference[0], out)
    _stop_once_locked(a, out)  # a holds the lock (b would be refused the other way round too)
    try:
        b = _generate(other, out)
        _, err_b = b.communicate(timeout=600)
    finally:
        os.kill(a.pid, signal.SIGCONT)
    _, err_a = a.communicate(timeout=600)
    assert a.returncode == 0, err_a
    assert b.returncode == 2 and "is being written by pid" in err_b, err_b
    assert digest(out) == digest(ref)
    # afterwards, the other config is refused for what it is, not for a lock
    res = _run(other, out)
    assert res.returncode == 2 and "different config" in res.stderr


@pytest.mark.parametrize("trial", range(3))
def test_kill_9_of_the_driver_mid_shard_then_resume(tmp_path, reference, trial):
    cfg, ref = reference
    out = tmp_path / "s.zarr"
    rng = np.random.default_rng(trial)
    p = _generate(cfg, out)
    k = int(rng.integers(1, 3))  # after shard k is done, kill inside shard k + 1 (of 0..3)
    done_at = []
    t0 = time.perf_counter()
    for j in range(k + 1):
        while not (out / "shard_done" / "c" / str(j)).exists():
            assert p.poll() is None, p.communicate()
            assert time.perf_counter() - t0 < 300
            time.sleep(0.002)
        done_at.append(time.perf_counter())
    # at a random moment within the next shard (a shard takes about as long as the last one)
    time.sleep(float(rng.uniform(0.0, 0.6)) * (done_at[-1] - done_at[-2]))
    assert p.poll() is None, "the sweep finished before the kill"
    os.kill(p.pid, signal.SIGKILL)
    p.wait()
    assert lock_path(out).exists()  # the dead driver's lock is left behind
    status = shard_status(out)
    assert status[: k + 1].all() and status.sum() < len(status)
    assert validate_store(out).ok  # the done shards are intact
    res = _run(cfg, out)  # takes over the stale lock and completes the store
    assert res.returncode == 0, res.stderr
    assert digest(out) == digest(ref)


@pytest.mark.parametrize("target", ["seismic/c/1/0/0", "fault/c/1/0/0", "params/c.1.0",
                                    "particles/run_00001/x_m/c/0", "shard_done/c/1"])
def test_bit_flip_in_a_done_shard_is_regenerated_by_resume(tmp_path, reference, target):
    cfg, ref = reference
    out = tmp_path / "s.zarr"
    shutil.copytree(ref, out)
    f = out / target
    data = bytearray(f.read_bytes())
    data[len(data) // 3] ^= 0x01
    f.write_bytes(bytes(data))
    assert not validate_store(out).ok
    res = _run(cfg, out)
    assert res.returncode == 0, res.stderr
    assert "3 already done, 1 written now" in res.stdout
    if target != "shard_done/c/1":  # a flag that fails its check reads as not done
        assert "1 done run(s) failed their checksums and were computed again: 1" in res.stdout
    assert digest(out) == digest(ref)
