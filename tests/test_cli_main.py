"""demseis.cli.main: how the command line ends when its output or its input goes wrong."""

from __future__ import annotations

import subprocess
import sys

import pytest

from demseis.cli import main
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


@pytest.mark.parametrize("argv, words", [
    (["generate"], "the following arguments are required: --out"),
    (["score"], "the following arguments are required: predictions, STORE|MASK"),
    (["nosuch"], "invalid choice: 'nosuch'"),
    (["generate", "--out", "x", "--workers", "-1"], "'-1' must be >= 0"),
    (["info", "a", "b", "c"], "unrecognized arguments"),
])
def test_usage_errors_are_one_line_and_exit_2(argv, words, capsys):
    """issue 38: argparse printed 2 to 8 lines of usage before its error; the README promises
    one line naming the problem, with where to look."""
    with pytest.raises(SystemExit) as exc:
        main(argv)
    err = capsys.readouterr().err
    assert exc.value.code == 2
    assert len(err.strip().splitlines()) == 1 and words in err and "--help" in err, err

