"""The dask side of a sweep: a local cluster of worker processes (or a client of a running
scheduler), a bounded window of shard tasks in flight, and a clean shut-down on Ctrl-C.

This module imports dask, distributed and psutil at its top: :mod:`demseis.generator.sweep.driver`
imports it only for a sweep with workers or a scheduler, so ``workers=0`` and the readers never
load them. It knows nothing of stores: the driver hands it the task, the order of the runs and
what to do with each result.
"""

from __future__ import annotations

import contextlib
import itertools
import logging
import os
import threading
import time
from collections.abc import Callable, Sequence
from typing import Any

import dask
import distributed.utils
import psutil
from distributed import Client, LocalCluster, as_completed

from demseis import interrupts
from demseis.errors import InputError
from demseis.generator.sweep._worker import IgnoreSigint
from demseis.generator.sweep.workers import (main_module_hidden, set_worker_env, sigint_deferred,
                                             sigint_ignored, start_forkserver, worker_start_method)

#: tasks a sweep keeps submitted at least (4 per worker where there are more workers)
SUBMIT_WINDOW = 64



#: dask's periodic work turned down for a local sweep: a task is one long Numba call that holds
#: the GIL, so the worker's stack sampler (every 10 ms), the event-loop tick (20 ms) and the
#: system and nanny memory monitors (the nannies run in the driver) mostly wait for the GIL and
#: take CPU from the tasks on a small machine (the driver's CPU time and the 2-worker speed-up
#: with and without them: CHANGELOG, "Measured performance"). The settings reach the spawned
#: workers with the config.
QUIET_DASK = {
    "distributed.worker.profile.enabled": False,
    "distributed.admin.tick.interval": "1s",
    "distributed.admin.system-monitor.interval": "2s",
    "distributed.worker.memory.monitor-interval": "1s",
}


def connect(scheduler: str) -> Any:
    """A client of the dask scheduler at ``scheduler``; InputError if it cannot be reached."""
    try:
        return Client(scheduler, timeout="20s")
    except (OSError, TimeoutError, ValueError) as exc:
        raise InputError(f"--scheduler {scheduler!r}: cannot connect ({exc})") from None


def run_distributed(task: Callable[[int], dict[str, Any]], order: Sequence[int], *,
                    on_result: Callable[[dict[str, Any]], None],
                    on_failure: Callable[[int, str], None], warm: Callable[[], None],
                    phase_seconds: dict[str, float], workers: int | None, remote: Client | None,
                    retries: int) -> float:
    """Run ``task(run)`` for every run of ``order`` (longest first) on a local cluster of
    ``workers`` processes, or on ``remote`` (a client of a running scheduler, closed here).

    Each result goes to ``on_result``; a task that failed after ``retries`` retries of a dead
    worker goes to ``on_failure(run, "Type: message")``. ``warm`` loads the Numba cache before
    the workers fork (or beside their spawn). Seconds of each phase (``start``, ``warm``,
    ``compute``, ``close``) are added to ``phase_seconds``. Returns the compute seconds.
    """
    cluster = None
    t_start = time.perf_counter()
    # Ctrl-C reaches the terminal's whole process group: the worker processes ignore it (see
    # _start_local_cluster) and the driver closes the cluster in the ``finally`` below, so an
    # interrupted sweep prints no worker traceback and leaks no semaphore.
    client = None
    hidden = contextlib.ExitStack()
    try:
        if remote is not None:
            client = remote
        else:
            # the caller's __main__ stays hidden while the cluster lives: dask restarts a
            # crashed worker in a new process (demseis.generator.sweep.workers)
            hidden.enter_context(main_module_hidden())
            client, cluster = _start_local_cluster(warm, phase_seconds, workers, retries)
        phase_seconds["start"] = time.perf_counter() - t_start
        t_compute = time.perf_counter()
        shard_of: dict[str, int] = {}

        def submit(rank: int, s: int) -> Any:
            fut = client.submit(task, s, retries=retries, pure=False,
                                priority=len(order) - rank, key=f"demseis-shard-{s}-{os.getpid()}")
            shard_of[fut.key] = s
            return fut

        # A bounded window of tasks in flight, refilled as they finish: submitting a 100,000-run
        # sweep at once, and cancelling it on Ctrl-C, each cost tens of seconds; with the window
        # both cost what the few tasks in flight cost.
        queue = iter(enumerate(order))
        window = max(SUBMIT_WINDOW, 4 * len(client.scheduler_info().get("workers", {})))
        running = as_completed([submit(rank, s) for rank, s in itertools.islice(queue, window)])
        while not running.is_empty():
            # a Ctrl-C swallowed where it landed (a __del__, a weakref callback) is raised here:
            # polled every 0.1 s, not only when a task finishes (a DEM run takes minutes)
            interrupts.raise_if_interrupted()
            batch = running.next_batch(block=False)
            if not batch:
                time.sleep(0.1)
                continue
            for fut in batch:
                if fut.status in ("lost", "pending"):
                    # its worker died holding the result after it finished (the shard is
                    # written): the scheduler computes it again; wait for it again
                    running.add(fut)
                    continue
                if fut.status == "finished":
                    on_result(fut.result())
                else:
                    exc = fut.exception()
                    on_failure(shard_of[fut.key], f"{type(exc).__name__}: {exc}")
                shard_of.pop(fut.key, None)
                nxt = next(queue, None)
                if nxt is not None:
                    running.add(submit(*nxt))
        compute_s = time.perf_counter() - t_compute
        phase_seconds["compute"] = compute_s
    except BaseException:
        _quiet_dask_logs()  # the scheduler would log the tasks cancelled by the shut-down
        raise
    finally:
        t_close = time.perf_counter()
        with sigint_deferred():  # a second Ctrl-C does not cut the clean shut-down short
            if client is not None:
                client.close()
            if cluster is not None:
                cluster.close()
            hidden.close()
        phase_seconds["close"] = time.perf_counter() - t_close
    return compute_s


def _quiet_dask_logs() -> None:
    """Only CRITICAL from dask's loggers in this process (an interrupted sweep shutting down)."""
    for name in list(logging.root.manager.loggerDict):
        if name == "distributed" or name.startswith("distributed."):
            logging.getLogger(name).setLevel(logging.CRITICAL)


def _wait_spawned(n: int, timeout_s: float = 60.0) -> None:
    """Wait until ``n`` worker processes (multiprocessing spawn children) exist."""
    me = psutil.Process()
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        found = 0
        for child in me.children(recursive=True):
            try:
                found += "spawn_main" in " ".join(child.cmdline())
            except (psutil.NoSuchProcess, psutil.ZombieProcess, psutil.AccessDenied):
                continue
        if found >= n:
            return
        time.sleep(0.01)


def _start_local_cluster(warm_cache: Callable[[], None], phase_seconds: dict[str, float],
                         workers: int | None, retries: int) -> tuple[Client, LocalCluster]:
    """A LocalCluster of single-threaded worker processes and its client, the Numba cache warm.

    With the forkserver (:func:`demseis.generator.sweep.workers.worker_start_method`), the server warms
    the cache once before it forks any worker. With spawn, the cache is warmed in a thread of
    the driver while the worker processes start: tasks are submitted only after both, so no
    worker compiles a kernel the driver is compiling.
    """
    warm_errors: list[BaseException] = []

    def warm() -> None:
        t_warm = time.perf_counter()
        try:
            warm_cache()
            phase_seconds["warm"] = time.perf_counter() - t_warm
        except BaseException as exc:  # re-raised in the driver below
            warm_errors.append(exc)

    n = workers or os.cpu_count() or 1
    env = set_worker_env()
    method = worker_start_method()
    warmer = None
    if method == "forkserver":
        start_forkserver()  # a no-op when demseis.api.generate started it already
        # dask's own forkserver preload list would import pandas and the like into the driver
        if hasattr(distributed.utils, "_forkserver_preload_set"):
            distributed.utils._forkserver_preload_set = True
    else:
        warmer = threading.Thread(target=warm, name="demseis-warm-numba")
        warmer.start()
    cluster = client = None
    try:
        with dask.config.set({"distributed.worker.daemon": False,
                              "distributed.worker.multiprocessing-method": method,
                              "distributed.scheduler.allowed-failures": retries + 1,
                              **QUIET_DASK}):
            # No dashboard; the scheduler's small HTTP server (health routes) on any free port:
            # the default :8787 warns when another cluster holds it. Logs: CRITICAL only; task errors reach the
            # driver through the futures and end up in the summary, and a worker cut off by an
            # interrupted driver must not print tracebacks.
            cluster = LocalCluster(n_workers=0, threads_per_worker=1, processes=True,
                                   dashboard_address=":0",  # any free port: no warning
                                   scheduler_kwargs={"dashboard": False}, env=env,
                                   silence_logs=logging.CRITICAL)
            client = Client(cluster)
            client.register_plugin(IgnoreSigint())  # workers started later (restarts) too
            if method == "forkserver":  # forked workers inherit the server's ignored SIGINT
                cluster.scale(n)
            else:
                # Spawned workers are started with SIGINT ignored, so they ignore it from their
                # first import on; the driver ignores it only for the ~0.1 s the spawns take.
                with sigint_ignored():
                    cluster.scale(n)
                    _wait_spawned(n)
            # Tasks go out as soon as one worker is up (the others join as they start), and
            # a worker killed while starting does not make the sweep wait for it for ever.
            try:
                client.wait_for_workers(1, timeout=120)
            except TimeoutError:
                raise InputError("no dask worker started within 120 s") from None
        if warmer is not None:
            warmer.join()
        if warm_errors:
            raise warm_errors[0]
    except BaseException:
        if warmer is not None:
            warmer.join()
        if client is not None:
            client.close()
        if cluster is not None:
            cluster.close()
        raise
    return client, cluster


