"""Preloaded by the forkserver that forks the sweep's local dask workers (imported nowhere else).

What every worker process would otherwise do by itself before its first task is done here once:
import dask's worker machinery and demseis, and load every Numba kernel from the on-disk cache
(compiling it if the cache is cold). Each worker forked from this process inherits all of it.
See :mod:`demseis.generator.sweep.workers` for why and what it saves.
"""

from __future__ import annotations

import signal

# Ctrl-C is the driver's. This process started with SIGINT blocked
# (demseis.generator.sweep.workers.start_forkserver): ignoring it discards one sent meanwhile,
# and the workers forked from here inherit both.
signal.signal(signal.SIGINT, signal.SIG_IGN)
if hasattr(signal, "pthread_sigmask"):
    signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGINT})

import distributed.nanny  # noqa: F401  (the worker process's own imports)
import distributed.worker  # noqa: F401

from demseis.generator.sweep.driver import shard_task, warm_numba_cache  # noqa: F401

try:
    warm_numba_cache()
except Exception:  # noqa: BLE001 - a worker then loads or compiles what its task needs, and a
    pass  # real error surfaces in that task, where the sweep reports it
