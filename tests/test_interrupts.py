"""demseis.interrupts: a Ctrl-C that lands in a ``__del__`` or a weakref callback (where Python
can only print "Exception ignored" and carry on) is recorded and raised by the next check, in
the library and through the CLI; nothing is printed for it."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time

import pytest

from demseis import interrupts
from tests.faults._helpers import FINISHED, INTERRUPTED, ROOT, done_shards


class _SigintInDel:
    """An object whose ``__del__`` receives SIGINT: Python runs the handler there, and the
    KeyboardInterrupt it raises cannot leave ``__del__``."""

    def __del__(self) -> None:
        os.kill(os.getpid(), signal.SIGINT)
        deadline = time.monotonic() + 2.0
        while time.monotonic() < deadline:  # the handler runs between these bytecodes
            pass


def swallow_sigint() -> None:
    """Deliver SIGINT where its KeyboardInterrupt is swallowed."""
    _SigintInDel()


@pytest.fixture(autouse=True)
def _clear():
    interrupts.clear()
    yield
    interrupts.clear()


def test_default_handler_loses_a_ctrl_c_in_del(monkeypatch):
    """The failure the module exists for, with Python's own handler: the interrupt goes to the
    unraisable hook (which prints "Exception ignored") and the program goes on."""
    seen = []
    monkeypatch.setattr(sys, "unraisablehook", seen.append)
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler
    swallow_sigint()
    assert [u.exc_type for u in seen] == [KeyboardInterrupt]
    assert not interrupts.interrupted()


def test_installed_records_a_swallowed_ctrl_c_silently(monkeypatch):
    seen = []
    monkeypatch.setattr(sys, "unraisablehook", seen.append)
    old = signal.getsignal(signal.SIGINT)
    hook = sys.unraisablehook
    with interrupts.installed() as active:
        assert active
        swallow_sigint()
        assert interrupts.interrupted()
        with pytest.raises(KeyboardInterrupt):
            interrupts.raise_if_interrupted()
    assert seen == []
    assert signal.getsignal(signal.SIGINT) is old and sys.unraisablehook is hook


def test_installed_still_raises_where_it_can():
    with interrupts.installed(), pytest.raises(KeyboardInterrupt):
        os.kill(os.getpid(), signal.SIGINT)
        time.sleep(2.0)
    assert interrupts.interrupted()


def test_installed_leaves_an_ignored_sigint_ignored():
    old = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        with interrupts.installed() as active:
            assert not active
            assert signal.getsignal(signal.SIGINT) is signal.SIG_IGN
    finally:
        signal.signal(signal.SIGINT, old)


def test_other_unraisable_errors_are_still_reported(monkeypatch):
    class Bad:
        def __del__(self) -> None:
            raise ValueError("still reported")

    seen = []
    monkeypatch.setattr(sys, "unraisablehook", seen.append)
    with interrupts.installed():
        Bad()
    assert [str(u.exc_value) for u in seen] == ["still reported"]


def test_watched_raises_a_swallowed_ctrl_c_at_its_end_and_restores():
    with pytest.raises(interrupts.Finished), interrupts.watched():   # the block completed
        swallow_sigint()
    assert not interrupts.interrupted()
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler


def test_in_process_sweep_stops_at_the_next_run(tmp_path, monkeypatch):
    """workers=0: the first run swallows a Ctrl-C; the sweep stops before the second."""
    import demseis.generator.sweep.driver as sweep
    from demseis.generator.config.settings import load_config

    real = sweep.shard_task
    calls = []

    def task(*args, **kwargs):
        calls.append(1)
        result = real(*args, **kwargs)
        swallow_sigint()
        return result

    monkeypatch.setattr(sweep, "shard_task", task)
    toml = tmp_path / "c.toml"
    toml.write_text("[sweep]\nn_runs = 4\n")
    cfg = load_config(toml, preset="tiny")
    with pytest.raises(KeyboardInterrupt):
        sweep.run_sweep(cfg, tmp_path / "s.zarr", workers=0, progress=False)
    assert len(calls) == 1
    assert done_shards(tmp_path / "s.zarr") == 1


#: a CLI run whose driver swallows a Ctrl-C when it books the first finished run
_SCRIPT = """
import os, signal, sys, time
sys.path.insert(0, {root!r})
import demseis.generator.sweep.driver as sweep
from tests.test_interrupts import swallow_sigint
real = sweep._account
def account(*args):
    real(*args)
    if not getattr(account, "done", False):
        account.done = True
        swallow_sigint()
        print("swallowed", time.monotonic(), file=sys.stderr, flush=True)
sweep._account = account
from demseis.cli import main
sys.exit(main(sys.argv[1:]))
"""


@pytest.mark.slow
def test_cli_sweep_with_workers_stops_soon_after_a_swallowed_ctrl_c(tmp_path):
    """2 dask workers, 2000 kinematic runs (minutes of work): the swallowed Ctrl-C ends the
    sweep within seconds, exit 130, the one line (no "Exception ignored"), the store resumable."""
    cfg = tmp_path / "c.toml"
    cfg.write_text('[sweep]\nn_runs = 2000\n[model]\nengine = "kinematic"\n')
    out = tmp_path / "s.zarr"
    proc = subprocess.run([sys.executable, "-c", _SCRIPT.format(root=str(ROOT)), "generate",
                           str(cfg), "--preset", "tiny", "--out", str(out), "--workers", "2",
                           "--quiet"], capture_output=True, text=True, cwd=ROOT, timeout=300)
    t_end = time.monotonic()
    lines = proc.stderr.strip().splitlines()
    assert proc.returncode == 130, proc.stderr[-3000:]
    assert lines[0].startswith("swallowed") and lines[1:] == [INTERRUPTED], proc.stderr[-3000:]
    swallowed_at = float(lines[0].split()[1])
    assert t_end - swallowed_at < 30.0  # cluster shut-down included; the sweep needs minutes
    assert 1 <= done_shards(out) < 2000


#: a CLI run that receives Ctrl-C while it finalizes the store, after every run was written
_FINALIZE_SCRIPT = """
import os, signal, sys
sys.path.insert(0, {root!r})
import demseis.generator.sweep.driver as sweep
real = sweep.finalize_store
def finalize(out):
    os.kill(os.getpid(), signal.SIGINT)
    real(out)
sweep.finalize_store = finalize
from demseis.cli import main
sys.exit(main(sys.argv[1:]))
"""


def test_ctrl_c_after_every_run_is_written_says_nothing_to_resume(tmp_path):
    """issue 38: a Ctrl-C after all shards were written said "run the same command to
    resume"; the store is complete and finalized, and the line says so."""
    cfg = tmp_path / "c.toml"
    cfg.write_text("[sweep]\nn_runs = 1\n")
    out = tmp_path / "s.zarr"
    proc = subprocess.run([sys.executable, "-c", _FINALIZE_SCRIPT.format(root=str(ROOT)),
                           "generate", str(cfg), "--preset", "tiny", "--out", str(out),
                           "--workers", "0", "--quiet"], capture_output=True, text=True,
                          cwd=ROOT, timeout=300)
    assert proc.returncode == 130, proc.stderr[-3000:]
    assert proc.stderr.strip() == FINISHED
    from demseis.datasets import validate_store

    assert done_shards(out) == 1 and validate_store(out).ok
