"""The writer lock: a second writer is refused naming the holder; a stale lock is taken over."""

from __future__ import annotations

import json
import multiprocessing as mp
import os
import socket
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

from demseis.cli import main
from demseis.datasets import writer_lock
from demseis.datasets.lock import lock_path
from demseis.errors import StoreError

ROOT = Path(__file__).resolve().parents[2]

HOLDER = """
import sys, time
from demseis.datasets import writer_lock
lock = writer_lock(sys.argv[1], "test holder").acquire()
print("HELD", flush=True)
time.sleep(600)
"""


def _hold(store: Path) -> subprocess.Popen:
    child = subprocess.Popen([sys.executable, "-c", textwrap.dedent(HOLDER), str(store)],
                             stdout=subprocess.PIPE, text=True, cwd=ROOT,
                             env={**os.environ, "PYTHONPATH": str(ROOT)})
    assert child.stdout.readline().strip() == "HELD"
    return child


def _dead_pid() -> int:
    p = subprocess.Popen([sys.executable, "-c", "pass"])
    p.wait()
    return p.pid


def test_lock_file_sits_beside_the_store(tmp_path):
    assert lock_path(tmp_path / "t.zarr") == tmp_path / "t.zarr.lock"
    assert lock_path(str(tmp_path / "t.zarr") + "/") == tmp_path / "t.zarr.lock"
    with writer_lock(tmp_path / "t.zarr", "me") as lock:
        holder = json.loads(lock.path.read_text())
        assert holder["pid"] == os.getpid() and holder["host"] == socket.gethostname()
        assert holder["command"] == "me" and holder["started"]
    assert not lock.path.exists()


def test_second_writer_is_refused_naming_the_holder(tmp_path):
    store = tmp_path / "t.zarr"
    child = _hold(store)
    try:
        with pytest.raises(StoreError) as err:
            writer_lock(store).acquire()
        msg = str(err.value)
        assert f"pid {child.pid} on host {socket.gethostname()!r}, started 20" in msg
        assert "test holder" in msg
    finally:
        child.kill()
        child.wait()
    # the holder was killed (-9): its lock is stale and is taken over
    with writer_lock(store, "next") as lock:
        assert json.loads(lock.path.read_text())["pid"] == os.getpid()


def test_stale_lock_of_a_dead_pid_is_taken_over(tmp_path):
    store = tmp_path / "t.zarr"
    lock_path(store).write_text(json.dumps({"host": socket.gethostname(), "pid": _dead_pid(),
                                            "token": "old"}))
    with writer_lock(store) as lock:
        assert json.loads(lock.path.read_text())["token"] != "old"


def test_reused_pid_counts_as_stale(tmp_path):
    """The pid is alive but started at another time than the holder recorded."""
    store = tmp_path / "t.zarr"
    lock_path(store).write_text(json.dumps({"host": socket.gethostname(), "pid": os.getppid(),
                                            "proc_start": "1", "token": "old"}))
    with writer_lock(store) as lock:
        holder = json.loads(lock.path.read_text())
        assert holder["token"] != "old" and holder["pid"] == os.getpid()


def test_lock_of_another_host_is_never_taken_over(tmp_path):
    store = tmp_path / "t.zarr"
    lock_path(store).write_text(json.dumps({"host": "elsewhere", "pid": _dead_pid(),
                                            "started": "2026-01-01T00:00:00+00:00"}))
    with pytest.raises(StoreError, match=r"host 'elsewhere'.*delete .*t\.zarr\.lock"):
        writer_lock(store).acquire()


def test_unreadable_lock_is_refused(tmp_path):
    store = tmp_path / "t.zarr"
    lock_path(store).write_text("garbage")
    with pytest.raises(StoreError, match="unknown holder"):
        writer_lock(store).acquire()


def _race(store: str, barrier, finished, results) -> None:
    barrier.wait()
    try:
        lock = writer_lock(store).acquire()
    except StoreError:
        results.put("refused")
        return
    results.put("won")
    finished.wait(60)  # hold it until every racer has tried
    lock.release()


def test_racing_takeovers_of_a_stale_lock_have_one_winner(tmp_path):
    store = tmp_path / "t.zarr"
    for _trial in range(5):
        lock_path(store).write_text(json.dumps({"host": socket.gethostname(),
                                                "pid": _dead_pid(), "token": "old"}))
        ctx = mp.get_context("fork")
        n = 4
        barrier, finished, results = ctx.Barrier(n), ctx.Event(), ctx.Queue()
        procs = [ctx.Process(target=_race, args=(str(store), barrier, finished, results))
                 for _ in range(n)]
        for p in procs:
            p.start()
        outcome = sorted(results.get(timeout=60) for _ in range(n))
        finished.set()  # the winner releases
        for p in procs:
            p.join(timeout=60)
        assert outcome == ["refused"] * (n - 1) + ["won"], outcome
        assert not lock_path(store).exists()  # released by the winner
        assert not lock_path(store).with_name("t.zarr.lock.break").exists()


def test_generate_and_render_refuse_a_locked_store(tmp_path, capsys):
    store = tmp_path / "t.zarr"
    child = _hold(store)
    try:
        assert main(["generate", "--preset", "tiny", "--out", str(store), "--workers", "0",
                     "--quiet"]) == 2
        err = capsys.readouterr().err
        assert f"is being written by pid {child.pid}" in err
        assert not store.exists()  # nothing was written
        assert main(["render", str(tmp_path / "src.zarr"), "--freq", "20", "--out", str(store),
                     "--quiet"]) == 2
        assert f"is being written by pid {child.pid}" in capsys.readouterr().err
    finally:
        child.kill()
        child.wait()
