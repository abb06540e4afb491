"""How a local sweep starts its dask worker processes (light: imports nothing heavy).

Where the platform has it (Linux, macOS), the workers are forked from multiprocessing's
*forkserver*, a process that has first imported dask's worker machinery and demseis and loaded
every Numba kernel (:mod:`demseis.generator.sweep._forkserver_preload`). A spawned worker instead
imports all of it itself (~0.8 s of CPU) and loads the kernels in its first task (~0.7 s): on a
machine with as many workers as cores that CPU is taken from the other workers' tasks. A forked
worker also exits without the interpreter's shut-down of Numba and LLVM, so closing the cluster
takes ~0.03 s instead of ~0.5 s.

:func:`demseis.api.generate` starts the server before it imports the rest of the sweep, so that
the server's preload (~1.5 s of CPU) runs on another core while the driver imports, prepares
the store and starts the scheduler. Measured with ``python benchmarks/sweep.py --methods
forkserver,spawn``.

``DEMSEIS_WORKER_START=spawn`` (or ``forkserver``) forces a method.

The workers need no user code, so nothing of the caller's ``__main__`` reaches them: while the
server and the workers start (and for the cluster's whole life, since dask restarts a crashed
worker), :func:`main_module_hidden` hides the caller's main module from multiprocessing, which
would otherwise run the caller's script again in every new process. ``demseis.generate(...)``
therefore works from a script without an ``if __name__ == "__main__":`` guard, from stdin
(``python - < script.py``), from ``python -m`` and in a Jupyter kernel.
"""

from __future__ import annotations

import contextlib
import multiprocessing
import multiprocessing.forkserver
import multiprocessing.resource_tracker
import os
import signal
import sys
import threading
from collections.abc import Iterator

from demseis.errors import InputError

#: thread counts of the worker processes: one task per worker, one thread per task
WORKER_ENV = {"NUMBA_NUM_THREADS": "1", "OMP_NUM_THREADS": "1", "MKL_NUM_THREADS": "1",
              "OPENBLAS_NUM_THREADS": "1"}

METHODS = ("forkserver", "spawn")


def worker_start_method() -> str:
    """``forkserver`` where the platform has it, else ``spawn``; ``DEMSEIS_WORKER_START`` forces one.

    Raises
    ------
    InputError
        ``DEMSEIS_WORKER_START`` names another method, or one this platform lacks.
    """
    available = multiprocessing.get_all_start_methods()
    forced = os.environ.get("DEMSEIS_WORKER_START", "").strip()
    if forced:
        if forced not in METHODS or forced not in available:
            usable = [m for m in METHODS if m in available]
            raise InputError(f"DEMSEIS_WORKER_START={forced!r}: use one of {usable}")
        return forced
    return "forkserver" if "forkserver" in available else "spawn"


def set_worker_env() -> dict[str, str]:
    """Put :data:`WORKER_ENV` into this process's environment (the workers and the forkserver
    inherit it; Numba reads its thread count at import) and return it."""
    os.environ.update(WORKER_ENV)
    return dict(WORKER_ENV)


def start_forkserver() -> None:
    """Start the forkserver with the sweep's preload, unless it runs already; no-op with spawn.

    Ctrl-C is the driver's (it shuts the cluster down): the server starts with SIGINT blocked
    (:func:`sigint_blocked`), ignores it from the first line of its preload on, and every worker
    it forks inherits that. A Ctrl-C that comes while the server starts is held in this process
    and raised once the server runs (:func:`sigint_deferred`); ignoring SIGINT here instead
    would lose it, and the sweep would run on. The server serves every later sweep of this
    process and exits with it; its preloaded modules are those of its start.
    """
    if worker_start_method() != "forkserver":
        return
    set_worker_env()
    multiprocessing.get_context("forkserver").set_forkserver_preload(
        ["demseis.generator.sweep._forkserver_preload"])
    with sigint_deferred(), main_module_hidden():
        # the server's start starts multiprocessing's resource tracker first, unless it runs,
        # and that start unblocks SIGINT in this thread when it is done: started here, outside
        # the block, so that the server starts with SIGINT blocked
        multiprocessing.resource_tracker.ensure_running()
        with sigint_blocked():
            multiprocessing.forkserver.ensure_running()


_ABSENT = object()


@contextlib.contextmanager
def main_module_hidden() -> Iterator[None]:
    """Processes multiprocessing starts in the block do not run the caller's ``__main__`` again.

    multiprocessing's spawn and forkserver children re-run the parent's main script (its
    ``__main__.__file__``) or re-import its main module (``__main__.__spec__.name``) before
    they unpickle their task. A script without a ``__main__`` guard then starts a sweep inside
    every worker, and a script read from stdin has a ``__file__`` of ``<stdin>`` that does not
    exist. The block removes ``__file__`` and clears ``__spec__`` of ``sys.modules["__main__"]``
    and restores them at its end; the sweep's workers import only demseis and dask.
    """
    main = sys.modules.get("__main__")
    if main is None:
        yield
        return
    saved_file = main.__dict__.pop("__file__", _ABSENT)
    saved_spec = main.__dict__.get("__spec__", _ABSENT)
    main.__spec__ = None
    try:
        yield
    finally:
        if saved_spec is _ABSENT:
            main.__dict__.pop("__spec__", None)
        else:
            main.__spec__ = saved_spec
        if saved_file is not _ABSENT:
            main.__file__ = saved_file


@contextlib.contextmanager
def sigint_ignored() -> Iterator[None]:
    """SIGINT ignored (SIG_IGN) for the block, in the main thread (elsewhere a no-op): processes
    started meanwhile inherit it."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    old = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, old)


@contextlib.contextmanager
def sigint_blocked() -> Iterator[None]:
    """SIGINT blocked in this thread's signal mask for the block. A process started meanwhile
    (fork and exec keep the mask) holds a SIGINT sent to it pending instead of acting on it,
    until it unblocks the signal; installing SIG_IGN first discards it
    (:mod:`demseis.generator.sweep._forkserver_preload`). This process still gets its own: the
    signal goes to another of its threads, whose handler hands it to the main thread's, or it
    is delivered at the block's end. Nothing is lost, unlike with :func:`sigint_ignored`. A
    no-op where the platform has no signal masks."""
    if not hasattr(signal, "pthread_sigmask"):
        yield
        return
    old = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, old)


@contextlib.contextmanager
def sigint_deferred(raises: type[KeyboardInterrupt] = KeyboardInterrupt) -> Iterator[None]:
    """Hold SIGINT in the main thread for the block; one that arrived is raised at its end (as
    ``raises``: :class:`demseis.interrupts.Finished` where the block completes the work). An
    ignored SIGINT (a background job's) stays ignored."""
    if threading.current_thread() is not threading.main_thread() or \
            signal.getsignal(signal.SIGINT) is signal.SIG_IGN:
        yield
        return
    got: list[int] = []
    old = signal.signal(signal.SIGINT, lambda signum, frame: got.append(signum))
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, old)
    if got:
        raise raises
