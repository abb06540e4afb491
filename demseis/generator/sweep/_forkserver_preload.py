"""Preloaded by the forkserver that forks the sweep's local dask workers (imported nowhere else).

What every worker process would otherwise do by itself before its first task is done here once:
import dask's worker machinery and demseis, and load every Numba kernel from the on-disk cache
(compiling it if the cache is cold). Each worker forked from this process inherits all of it.
See :mod:`demseis.generator.sweep.workers` for why and what it saves.
"""

from __future__ import annotations

import signal
import threading


def ignore_sigint_held_since_start() -> bool:
    """In a process started with SIGINT blocked (the forkserver of
    :func:`demseis.generator.sweep.workers.start_forkserver`): ignore SIGINT, which discards one
    held pending since the start, then unblock it; the workers forked from here inherit both.
    Ctrl-C is the driver's. Anywhere else (this module imported by a test or a script, SIGINT
    not blocked) nothing changes. Returns whether it acted."""
    if not hasattr(signal, "pthread_sigmask") or \
            threading.current_thread() is not threading.main_thread() or \
            signal.SIGINT not in signal.pthread_sigmask(signal.SIG_BLOCK, set()):
        return False
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGINT})
    return True


ignore_sigint_held_since_start()  # first, before the imports below take seconds

import distributed.nanny  # noqa: F401  (the worker process's own imports)
import distributed.worker  # noqa: F401

from demseis.generator.sweep.driver import shard_task, warm_numba_cache  # noqa: F401

try:
    warm_numba_cache()
except Exception:  # noqa: BLE001 - a worker then loads or compiles what its task needs, and a
    pass  # real error surfaces in that task, where the sweep reports it
