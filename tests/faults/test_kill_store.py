"""kill -9 of a shard writer: done shards stay valid, the killed shard stays pending, resume completes.

The deterministic tests make the child stop at a known point (it announces it on stdout and
waits to be killed): in the middle of a shard's arrays, and after everything but the done flag.
The slow test kills writers at random moments while they write many shards.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import numpy as np
import pytest

from demseis.datasets import open_store, read_particles, shard_status, validate_store, write_shard
from tests._helpers import ROOT
from tests.datasets._helpers import make_store, shard_data, zarr_params

SHAPE = (24, 32)
S = 6

CHILD = """
import sys, time
import demseis.datasets.particles as particles
import demseis.datasets.write as write
from tests.datasets._helpers import shard_data

path, stop = sys.argv[1], sys.argv[2]
real_write, real_particles = write._write_array, write.write_particles
real_block = particles.write_block
calls = []

def announce_and_wait(written=()):
    print("STOPPED", *written, flush=True)
    while True:
        time.sleep(1)

def write_array(root, arr, sel, data):
    real_write(root, arr, sel, data)
    calls.append(arr.path)
    if stop == "mid-arrays" and len(calls) == 3:  # three of the shard's arrays are written
        announce_and_wait(calls)  # the writer goes no further: no other array of the shard

def write_particles(*a, **k):
    real_particles(*a, **k)
    if stop == "before-done-flag":
        announce_and_wait()

def write_particle_block(*a, **k):
    real_block(*a, **k)
    calls.append("particles")
    if stop == "mid-particles" and calls.count("particles") == 2:  # two of its ten arrays
        announce_and_wait()

write._write_array = write_array
write.write_particles = write_particles
particles.write_block = write_particle_block
write.write_shard(path, 2, *shard_data(2, {S}, {SHAPE}))
print("FINISHED", flush=True)
"""


def _spawn(args: list[str], code: str) -> subprocess.Popen:
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    return subprocess.Popen([sys.executable, "-c", code, *args], stdout=subprocess.PIPE,
                            text=True, env=env, cwd=ROOT)


def _check_resumed(path: Path, n_shards: int, s: int, shape) -> None:
    for k in np.nonzero(shard_status(path) == 0)[0].tolist():
        write_shard(path, k, *shard_data(k, s, shape))
    report = validate_store(path)
    assert report.ok and report.n_done == n_shards, report.problems
    g = open_store(path, "r+")
    for k in range(n_shards):
        data, params, parts = shard_data(k, s, shape)
        for name, arr in data.items():
            np.testing.assert_array_equal(g[name][k * s:(k + 1) * s], arr)
        np.testing.assert_array_equal(zarr_params(path)["run_id"][k * s:(k + 1) * s],
                                      params["run_id"])
        np.testing.assert_array_equal(read_particles(path, k)[-1].xy, parts[-1].xy)


@pytest.mark.parametrize("stop", ["mid-arrays", "mid-particles", "before-done-flag"])
def test_kill_9_mid_shard_then_resume(tmp_path, stop):
    path = make_store(tmp_path / "s.zarr", n_shards=4, s=S, shape=SHAPE, write=[0, 1])
    child = _spawn([str(path), stop], textwrap.dedent(CHILD.format(S=S, SHAPE=SHAPE)))
    try:
        stopped, *written = child.stdout.readline().split()
        assert stopped == "STOPPED", stopped
        os.kill(child.pid, signal.SIGKILL)
        assert child.wait(timeout=30) == -signal.SIGKILL
    finally:
        if child.poll() is None:
            child.kill()
            child.wait()
    # the killed shard got some (or all) of its data, but it is not done
    assert shard_status(path).tolist() == [1, 1, 0, 0]
    g = open_store(path, "r+")
    assert len(written) == (3 if stop == "mid-arrays" else 0)
    if stop == "mid-particles":  # run 2's group was being built under a hidden name
        assert not (path / "particles" / "run_00002").exists()
        assert (path / "particles" / ".run_00002.partial" / "zarr.json").is_file()
    data, _, _ = shard_data(2, S, SHAPE)
    for name in written:  # the child did write these sample arrays of shard 2
        np.testing.assert_array_equal(g[name][2 * S:3 * S], data[name])
    report = validate_store(path)
    assert report.ok and report.n_done == 2, report.problems
    _check_resumed(path, 4, S, SHAPE)


WRITER = """
import sys
from demseis.datasets import shard_status, write_shard
from tests.datasets._helpers import shard_data
path, n_shards, s, h, w = sys.argv[1], *map(int, sys.argv[2:])
for k in range(n_shards):
    if shard_status(path)[k]:
        continue
    data = shard_data(k, s, (h, w))
    print("start", k, flush=True)
    write_shard(path, k, *data)
print("all", flush=True)
"""


@pytest.mark.slow
def test_kill_9_at_random_moments_then_resume(tmp_path):
    n_shards, s, shape = 16, 64, (128, 192)
    path = make_store(tmp_path / "s.zarr", n_shards=n_shards, s=s, shape=shape, write=[])
    rng = np.random.default_rng(1)
    interrupted_mid_shard = 0
    for attempt in range(4):
        child = _spawn([str(path), str(n_shards), str(s), *map(str, shape)], WRITER)
        starts, last = [], None
        wanted = int(rng.integers(2, 4))
        while len(starts) < wanted:
            line = child.stdout.readline().split()
            assert line and line[0] == "start", line
            starts.append(time.perf_counter())
            last = int(line[1])
        # kill somewhere inside the shard being written (a shard took starts[-1]-starts[-2])
        time.sleep(float(rng.uniform(0.0, 1.0)) * (starts[-1] - starts[-2]))
        os.kill(child.pid, signal.SIGKILL)
        assert child.wait(timeout=30) == -signal.SIGKILL
        interrupted_mid_shard += int(shard_status(path)[last] == 0)
        report = validate_store(path)
        assert report.ok, (attempt, report.problems)
    assert interrupted_mid_shard >= 1
    assert shard_status(path).sum() < n_shards
    _check_resumed(path, n_shards, s, shape)
