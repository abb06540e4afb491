"""Ctrl-C (SIGINT to the whole process group) during generate and render: exit 130, one line,
no traceback, no leaked semaphore; running the same command again gives the same bytes as an
uninterrupted run."""

from __future__ import annotations

import subprocess
import sys

import pytest

from tests.faults._helpers import (FINISHED, INTERRUPTED, ROOT, done_shards, interrupt, spawn,
                                   wait_for)
from tests.generator._helpers import assert_same_bytes

CFG = "[sweep]\nn_runs = 8\n"


@pytest.fixture(scope="module")
def reference(tmp_path_factory):
    """The uninterrupted store of CFG (tiny preset, 8 runs) and its re-render."""
    d = tmp_path_factory.mktemp("ref")
    cfg = d / "c.toml"
    cfg.write_text(CFG)
    ref = d / "ref.zarr"
    subprocess.run([sys.executable, "-m", "demseis", "generate", str(cfg), "--preset", "tiny",
                    "--out", str(ref), "--workers", "0", "--quiet"], check=True, cwd=ROOT,
                   capture_output=True)
    rendered = d / "ref_r.zarr"
    subprocess.run([sys.executable, "-m", "demseis", *_render_args(ref, rendered)], check=True,
                   cwd=ROOT, capture_output=True)
    return cfg, ref, rendered


def _render_args(src, out) -> list[str]:
    return ["render", str(src), "--freq", "10,20,30,40,50,60", "--snr", "inf,10,5", "--out",
            str(out), "--quiet"]


def _assert_clean_interrupt(rc: int, out: str, err: str) -> None:
    assert rc == 130, (rc, err[-3000:])
    assert err.strip() == INTERRUPTED, err[-3000:]
    assert "Traceback" not in err and "leaked" not in err


@pytest.mark.slow
@pytest.mark.parametrize("workers, when", [("2", "start-up"), ("2", "mid-sweep"), ("0", "mid-sweep")])
def test_ctrl_c_generate_then_resume(reference, tmp_path, workers, when):
    cfg, ref, _ = reference
    out = tmp_path / "g.zarr"
    args = ["generate", str(cfg), "--preset", "tiny", "--out", str(out), "--workers", workers, "--quiet"]
    proc = spawn(args)
    if when == "start-up":
        # the store exists, the cluster is still starting (no shard done)
        assert wait_for(lambda: (out / "zarr.json").exists(), proc=proc)
    else:
        assert wait_for(lambda: done_shards(out) >= 1, proc=proc), proc.communicate()[1][-2000:]
    _assert_clean_interrupt(*interrupt(proc))
    assert done_shards(out) < 8, "interrupt came after the sweep ended"
    res = subprocess.run([sys.executable, "-m", "demseis", *args], cwd=ROOT, capture_output=True,
                         text=True)
    assert res.returncode == 0, res.stderr[-2000:]
    assert_same_bytes(ref, out)


@pytest.mark.slow
def test_ctrl_c_render_then_resume(reference, tmp_path):
    _, ref, rendered = reference
    out = tmp_path / "r.zarr"
    proc = spawn(_render_args(ref, out))
    assert wait_for(lambda: done_shards(out) >= 1, proc=proc), proc.communicate()[1][-2000:]
    _assert_clean_interrupt(*interrupt(proc))
    res = subprocess.run([sys.executable, "-m", "demseis", *_render_args(ref, out)], cwd=ROOT,
                         capture_output=True, text=True)
    assert res.returncode == 0, res.stderr[-2000:]
    assert_same_bytes(rendered, out)


def test_render_progress_bar_is_labelled_render(tmp_path, capsys):
    from demseis.cli import main

    src = tmp_path / "t.zarr"
    cfg = tmp_path / "c.toml"
    cfg.write_text("[sweep]\nn_runs = 1\n")
    assert main(["generate", str(cfg), "--preset", "tiny", "--out", str(src), "--workers", "0", "--quiet"]) == 0
    capsys.readouterr()
    assert main(["render", str(src), "--freq", "20", "--out", str(tmp_path / "r.zarr")]) == 0
    err = capsys.readouterr().err
    assert "render:" in err and "generate" not in err


@pytest.mark.parametrize("command", ["info", "validate"])
def test_ctrl_c_of_a_read_only_command_says_nothing_about_resuming(tmp_path, monkeypatch,
                                                                   capsys, command):
    """issue 30: a read-only command has nothing to resume; its interrupt is one plain line."""
    import demseis.cli.commands.store as handlers
    from demseis.cli import main

    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(handlers, "validate_store", interrupted)
    monkeypatch.setattr(handlers, "fault_distribution", interrupted)
    monkeypatch.setattr(handlers, "store_summary", interrupted)
    from tests.datasets._helpers import make_store

    make_store(tmp_path / "s.zarr")
    assert main([command, str(tmp_path / "s.zarr")]) == 130
    assert capsys.readouterr().err.strip() == "demseis: interrupted"


def test_ctrl_c_inside_a_class_creation_is_an_interrupt(tmp_path, monkeypatch, capsys):
    """Python 3.11 turns a Ctrl-C that lands while a class is created (e.g. dask's expression
    classes, imported as a sweep's cluster starts) into "RuntimeError: Error calling
    __set_name__" caused by the KeyboardInterrupt: the CLI says its one line, exit 130; any
    other RuntimeError still propagates."""
    import demseis.cli.commands.store as handlers
    from demseis.cli import main

    class Name:
        def __set_name__(self, owner, name):
            raise KeyboardInterrupt

    def create_class(*args, **kwargs):
        type("Expr", (), {"_funcname": Name()})

    from tests.datasets._helpers import make_store

    make_store(tmp_path / "s.zarr")
    monkeypatch.setattr(handlers, "validate_store", create_class)
    assert main(["validate", str(tmp_path / "s.zarr")]) == 130
    assert capsys.readouterr().err.strip() == "demseis: interrupted"

    def other(*args, **kwargs):
        raise RuntimeError("not an interrupt")

    monkeypatch.setattr(handlers, "validate_store", other)
    with pytest.raises(RuntimeError, match="not an interrupt"):
        main(["validate", str(tmp_path / "s.zarr")])


def _shm_files() -> set[str]:
    """The POSIX semaphores and shared-memory blocks multiprocessing leaves in /dev/shm."""
    import glob

    return set(glob.glob("/dev/shm/sem.mp-*")) | set(glob.glob("/dev/shm/psm_*"))


@pytest.mark.slow
@pytest.mark.parametrize("n_runs, engine, latest_s", [(8, "dem", 8.0),
                                                      (100000, "kinematic", 15.0)])
def test_ctrl_c_at_20_moments_is_quick_and_clean(tmp_path, n_runs, engine, latest_s):
    """Ctrl-C at 20 random moments of a sweep of 8 and of 100,000 runs (2 workers): exit 130
    within 5 s with the one line (or, before the CLI's handler exists, Python's default), no
    leaked-semaphore warning, and nothing left behind: no ``pymp-*`` directory in the
    (private) temporary directory, no new semaphore or shared-memory file in /dev/shm."""
    import os
    import random
    import shutil
    import time

    cfg = tmp_path / "big.toml"
    cfg.write_text(f'[sweep]\nn_runs = {n_runs}\n[model]\nengine = "{engine}"\n')
    tmp = tmp_path / "tmp"
    tmp.mkdir()
    env = dict(os.environ, TMPDIR=str(tmp))
    rng = random.Random(n_runs)
    shm = _shm_files()
    for _ in range(20):
        out = tmp_path / "big.zarr"
        shutil.rmtree(out, ignore_errors=True)          # every moment of a fresh sweep
        proc = spawn(["generate", str(cfg), "--preset", "tiny", "--out", str(out),
                      "--workers", "2", "--quiet"], env=env)
        time.sleep(rng.uniform(0.3, latest_s))  # imports, creation, cluster start, sweep
        t0 = time.monotonic()
        rc, _, err = interrupt(proc)
        assert time.monotonic() - t0 < 5.0, err[-2000:]
        if rc == 130:
            assert err.strip() in (INTERRUPTED, FINISHED), err[-3000:]
            if err.strip() == FINISHED:   # only once every run is written
                assert done_shards(out) == n_runs
        elif rc != 0:  # the signal came before the CLI's handler was installed (start-up)
            assert rc == -2, (rc, err[-3000:])
        assert "leaked" not in err and "Traceback" not in err
    assert not list(tmp.glob("pymp-*")), list(tmp.iterdir())
    assert _shm_files() <= shm, _shm_files() - shm


_SLOW_SERVER_START = """\
import multiprocessing.forkserver as fs, pathlib, sys, time
start, where, marker = fs.ensure_running, sys.argv[1], pathlib.Path(sys.argv[2])
def slow():  # the moments around the forkserver's start, widened to seconds
    if where == "before":
        marker.touch(); time.sleep(2.0); start()
    else:
        start(); marker.touch(); time.sleep(2.0)
fs.ensure_running = slow
from demseis.cli import main
raise SystemExit(main(sys.argv[3:]))
"""


@pytest.mark.slow
@pytest.mark.parametrize("where", ["before", "after"])
def test_ctrl_c_while_the_forkserver_starts_is_not_lost(tmp_path, where):
    """A Ctrl-C while the driver starts the workers' forkserver (just before it is forked, or
    while it imports) interrupts the sweep: exit 130 with the one line. A driver that ignored
    SIGINT for that moment would lose such a Ctrl-C, and a 100,000-run sweep would run on (a
    rare "did not exit within 120 s" of the test above)."""
    import os
    import signal
    import time

    from tests.faults._helpers import _default_sigint

    cfg = tmp_path / "big.toml"
    cfg.write_text('[sweep]\nn_runs = 100000\n[model]\nengine = "kinematic"\n')
    script = tmp_path / "driver.py"
    script.write_text(_SLOW_SERVER_START)
    marker = tmp_path / "forking"
    env = {k: v for k, v in os.environ.items() if k != "DEMSEIS_WORKER_START"}
    proc = subprocess.Popen([sys.executable, str(script), where, str(marker), "generate", str(cfg),
                             "--preset", "tiny", "--out", str(tmp_path / "big.zarr"),
                             "--workers", "2", "--quiet"], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, start_new_session=True, cwd=ROOT,
                            env=env, preexec_fn=_default_sigint)
    assert wait_for(marker.exists, proc=proc), proc.communicate()[1][-2000:]
    time.sleep(0.5)
    _assert_clean_interrupt(*interrupt(proc, signal.SIGINT))
