"""How the sweep starts its local workers (demseis.generator.sweep.workers): forked from a forkserver
that has loaded the kernels, or spawned; either way the same bytes."""

from __future__ import annotations

import multiprocessing
import os
import re
import signal
import subprocess
import sys

import pytest

from demseis.errors import InputError
from demseis.generator.sweep.workers import sigint_blocked, sigint_deferred, worker_start_method
from tests._helpers import ROOT
from tests.generator._helpers import assert_same_bytes


def test_default_method_is_forkserver_where_available(monkeypatch):
    monkeypatch.delenv("DEMSEIS_WORKER_START", raising=False)
    expected = "forkserver" if "forkserver" in multiprocessing.get_all_start_methods() else "spawn"
    assert worker_start_method() == expected


def test_method_can_be_forced(monkeypatch):
    monkeypatch.setenv("DEMSEIS_WORKER_START", "spawn")
    assert worker_start_method() == "spawn"


@pytest.mark.parametrize("value", ["fork", "threads", "Spawn"])
def test_unknown_method_is_one_clear_error(monkeypatch, value):
    monkeypatch.setenv("DEMSEIS_WORKER_START", value)
    with pytest.raises(InputError, match="DEMSEIS_WORKER_START") as err:
        worker_start_method()
    assert "spawn" in str(err.value)


def test_unknown_method_from_the_cli_exits_2(tmp_path):
    env = {**os.environ, "DEMSEIS_WORKER_START": "threads"}
    res = subprocess.run([sys.executable, "-m", "demseis", "generate", "--preset", "tiny", "--out",
                          str(tmp_path / "x.zarr"), "--workers", "1", "--quiet"],
                         cwd=ROOT, env=env, capture_output=True, text=True)
    assert res.returncode == 2, res.stderr
    assert "DEMSEIS_WORKER_START" in res.stderr and "Traceback" not in res.stderr
    assert not (tmp_path / "x.zarr").exists()


@pytest.mark.skipif("forkserver" not in multiprocessing.get_all_start_methods(),
                    reason="no forkserver on this platform")
def test_forked_workers_start_with_the_kernels_loaded(monkeypatch):
    """A forked worker has every kernel of a run loaded before its first task (the preload);
    a spawned one has none, and would load them in its first task."""
    from demseis.generator.sweep.cluster import _start_local_cluster
    from demseis.generator.sweep.driver import warm_numba_cache

    def loaded_signatures() -> dict[str, int]:
        import sys as worker_sys

        kernels = worker_sys.modules.get("demseis.labels._kernels")
        dem = worker_sys.modules.get("demseis.dem._kernels")
        return {"labels": len(kernels.finite_strain.signatures) if kernels else 0,
                "dem_loaded": int(dem is not None)}

    seen = {}
    for method in ("forkserver", "spawn"):
        monkeypatch.setenv("DEMSEIS_WORKER_START", method)
        client, cluster = _start_local_cluster(warm_numba_cache, {}, 1, 0)
        try:
            seen[method] = list(client.run(loaded_signatures).values())[0]
        finally:
            client.close()
            cluster.close()
    assert seen["forkserver"]["labels"] >= 1 and seen["forkserver"]["dem_loaded"] == 1
    assert seen["spawn"] == {"labels": 0, "dem_loaded": 0}


@pytest.mark.slow
def test_spawned_and_forked_workers_write_the_same_bytes(tiny_store, tmp_path):
    for method in ("spawn", "forkserver"):
        out = tmp_path / f"{method}.zarr"
        env = {**os.environ, "DEMSEIS_WORKER_START": method}
        res = subprocess.run([sys.executable, "-m", "demseis", "generate", "--preset", "tiny",
                              "--out", str(out), "--workers", "2", "--quiet"],
                             cwd=ROOT, env=env, capture_output=True, text=True)
        assert res.returncode == 0, res.stderr[-2000:]
        assert_same_bytes(tiny_store, out)


def _blocked_and_ignored(status: str) -> tuple[bool, bool]:
    """Whether SIGINT is in the SigBlk and SigIgn masks of a /proc/PID/status text."""
    bit = 1 << (signal.SIGINT - 1)
    masks = [int(re.search(rf"{k}:\s*([0-9a-f]+)", status).group(1), 16)
             for k in ("SigBlk", "SigIgn")]
    return bool(masks[0] & bit), bool(masks[1] & bit)


@pytest.mark.skipif(not os.path.exists("/proc/self/status")
                    or not hasattr(signal, "pthread_sigmask"), reason="signal masks in /proc")
def test_a_ctrl_c_while_a_child_starts_is_held_here_and_blocked_there():
    """The forkserver's start: a SIGINT sent to this process inside sigint_deferred +
    sigint_blocked is raised at the block's end (not lost, as with SIG_IGN), and a process
    started in the block starts with SIGINT blocked and not ignored (it is held pending)."""
    old = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        with pytest.raises(KeyboardInterrupt):
            with sigint_deferred(), sigint_blocked():
                child = subprocess.Popen(
                    [sys.executable, "-c", "print(open('/proc/self/status').read())"],
                    stdout=subprocess.PIPE, text=True)
                os.kill(os.getpid(), signal.SIGINT)
                status = child.communicate()[0]
        assert signal.pthread_sigmask(signal.SIG_BLOCK, set()) == set()  # unblocked after it
        assert _blocked_and_ignored(status) == (True, False)
    finally:
        signal.signal(signal.SIGINT, old)


def test_an_ignored_sigint_stays_ignored_while_deferred():
    """A background job ignores SIGINT: deferring it must not start catching it."""
    old = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        with sigint_deferred():
            assert signal.getsignal(signal.SIGINT) is signal.SIG_IGN
            os.kill(os.getpid(), signal.SIGINT)
    finally:
        signal.signal(signal.SIGINT, old)


@pytest.mark.skipif("forkserver" not in multiprocessing.get_all_start_methods() or
                    not os.path.exists("/proc/self/status"), reason="forkserver, /proc")
def test_the_forkserver_and_its_workers_ignore_sigint_with_a_plain_mask(monkeypatch):
    """The server starts with SIGINT blocked (held pending, not acted on); its preload ignores
    SIGINT (which discards one held) and unblocks it again; a process it forks inherits both."""
    code = ("import multiprocessing, multiprocessing.forkserver as fs, time\n"
            "from demseis.generator.sweep.workers import start_forkserver\n"
            "start_forkserver()\n"
            "print(open(f'/proc/{fs._forkserver._forkserver_pid}/status').read())  # starting\n"
            "ctx = multiprocessing.get_context('forkserver')\n"
            "p = ctx.Process(target=time.sleep, args=(30,))\n"
            "p.start()  # forked once the preload is done\n"
            "for pid in (fs._forkserver._forkserver_pid, p.pid):\n"
            "    print(open(f'/proc/{pid}/status').read())\n"
            "p.kill()\n")
    monkeypatch.delenv("DEMSEIS_WORKER_START", raising=False)
    res = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT,
                         timeout=300)
    assert res.returncode == 0, res.stderr[-2000:]
    starting, server, worker = res.stdout.split("Name:")[1:]
    assert any(_blocked_and_ignored(starting))  # (True, False) until its preload, then ignored
    assert _blocked_and_ignored(server) == (False, True)
    assert _blocked_and_ignored(worker) == (False, True)


@pytest.mark.skipif(not hasattr(signal, "pthread_sigmask"), reason="signal masks")
def test_importing_the_preload_elsewhere_leaves_sigint_alone():
    """The preload ignores SIGINT only in a process started with it blocked (the forkserver):
    imported by a script or a test (test_docrefs imports every module), Ctrl-C still works."""
    code = ("import signal\n"
            "import demseis.generator.sweep._forkserver_preload as p\n"
            "assert signal.getsignal(signal.SIGINT) is signal.default_int_handler\n"
            "signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})\n"
            "assert p.ignore_sigint_held_since_start()\n"
            "assert signal.getsignal(signal.SIGINT) is signal.SIG_IGN\n"
            "assert signal.SIGINT not in signal.pthread_sigmask(signal.SIG_BLOCK, set())\n")
    res = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT,
                         timeout=300,
                         preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    assert res.returncode == 0, res.stderr[-2000:]
