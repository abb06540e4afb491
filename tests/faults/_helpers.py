"""Helpers of the fault-injection tests: run the CLI in its own process group, find its dask
workers, wait for shards, interrupt it. ``ROOT`` (the repository root) is re-exported from
``tests._helpers``."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

from tests._helpers import ROOT

__all__ = ["FINISHED", "INTERRUPTED", "ROOT", "dask_workers", "done_shards", "interrupt", "spawn", "wait_for"]

INTERRUPTED = "demseis: interrupted; run the same command to resume"
#: the line of a Ctrl-C that came after every run was written and the store finalized
FINISHED = "demseis: interrupted after the work was done: nothing to resume"


def spawn(args: list[str], env: dict[str, str] | None = None) -> subprocess.Popen:
    """``python -m demseis ARGS`` in a new session (its own process group, like a terminal job).

    The child starts with SIGINT at its default, as a foreground job of a terminal: when the
    test run itself was started as a background job of a non-interactive shell (``cmd &``),
    SIGINT is ignored there and every child would inherit that (Python keeps an ignored SIGINT
    ignored), so the Ctrl-C tests could not interrupt anything.
    """
    return subprocess.Popen([sys.executable, "-m", "demseis", *args], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, start_new_session=True, cwd=ROOT,
                            env=env, preexec_fn=_default_sigint)


def _default_sigint() -> None:
    signal.signal(signal.SIGINT, signal.SIG_DFL)


def dask_workers(driver_pid: int) -> list:
    """The sweep's dask worker processes below ``driver_pid`` (psutil processes).

    Spawned workers run multiprocessing's ``spawn_main``; forked ones (the default start method,
    see ``demseis.generator.sweep.driver.worker_start_method``) are the children of the forkserver, a
    child of the driver whose command line names ``multiprocessing.forkserver``.
    """
    import psutil

    try:
        below = psutil.Process(driver_pid).children(recursive=True)
    except psutil.NoSuchProcess:  # the driver has ended
        return []
    found = []
    for p in below:
        try:
            cmd = " ".join(p.cmdline())
            if "spawn_main" in cmd or ("forkserver" in cmd and "forkserver" in " ".join(p.parent().cmdline())):
                found.append(p)
        except (psutil.NoSuchProcess, psutil.ZombieProcess, psutil.AccessDenied, AttributeError):
            continue
    return found


def done_shards(store: Path) -> int:
    """Shards marked done so far (0 while the store does not exist yet).

    Counted from the flag files themselves (a done flag is the chunk file ``shard_done/c/<k>``;
    a pending one has no file: zarr deletes a chunk written with the fill value 0), not through
    zarr, so that the poll is cheap and does not depend on this process's zarr state.
    """
    try:
        return sum(1 for f in (store / "shard_done" / "c").iterdir() if f.name.isdigit())
    except FileNotFoundError:
        return 0


def wait_for(pred, timeout_s: float = 240.0, proc: subprocess.Popen | None = None) -> bool:
    """Poll ``pred()`` every 20 ms until it is true, the process ended, or the timeout."""
    deadline = time.time() + timeout_s
    while time.time() < deadline:
        if pred():
            return True
        if proc is not None and proc.poll() is not None:
            return False
        time.sleep(0.02)
    return False


def interrupt(proc: subprocess.Popen, sig: int = signal.SIGINT) -> tuple[int, str, str]:
    """Send ``sig`` to the whole process group (what Ctrl-C does); return (rc, stdout, stderr)."""
    try:
        os.killpg(proc.pid, sig)
    except ProcessLookupError:
        pass
    try:
        out, err = proc.communicate(timeout=120)
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGKILL)
        out, err = proc.communicate()
        raise AssertionError(f"did not exit within 120 s of the signal: {err[-2000:]}") from None
    return proc.returncode, out, err
