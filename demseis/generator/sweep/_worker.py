"""Worker-side set-up of the LocalCluster the sweep starts (imported by the driver only there)."""

from __future__ import annotations

import signal
import threading

from distributed import WorkerPlugin


class IgnoreSigint(WorkerPlugin):
    """Ctrl-C is the driver's to handle: every worker of the sweep, also one restarted after a
    crash, ignores SIGINT (the terminal sends it to the whole process group)."""

    name = "demseis-ignore-sigint"

    def setup(self, worker) -> None:  # noqa: ANN001 (distributed.Worker)
        if threading.current_thread() is threading.main_thread():
            signal.signal(signal.SIGINT, signal.SIG_IGN)
