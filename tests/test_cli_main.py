"""demseis.cli.main: how the command line ends when its output or its input goes wrong."""

from __future__ import annotations

import subprocess
import sys

from tests._helpers import ROOT


def test_a_closed_stdout_ends_quietly_with_141(tiny_store):
    """issue 38: `demseis info STORE | head -0` printed "error: (path unknown): Broken pipe"
    and exited 2; now it prints nothing and exits as a program killed by SIGPIPE does."""
    proc = subprocess.Popen([sys.executable, "-m", "demseis", "info", str(tiny_store)],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, cwd=ROOT)
    proc.stdout.close()                       # the reader is gone before anything is written
    err = proc.stderr.read().decode()
    assert proc.wait(timeout=120) == 141, err
    assert err == ""
