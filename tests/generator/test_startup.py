"""demseis.generate with its default (dask) workers from every way a user starts Python.

The workers need no user code: a script without an ``if __name__ == "__main__":`` guard, a
script read from stdin, ``python -m`` of an unguarded module and code run the way a notebook
kernel runs it (``python -c``) must each generate once and exit, under both worker start methods
(demseis.generator.sweep.workers.main_module_hidden). Each case runs in its own interpreter.
"""

from __future__ import annotations

import os
import subprocess
import sys
import types

import pytest

from demseis.generator.sweep.workers import main_module_hidden
from tests._helpers import ROOT

#: an unguarded user script: a small kinematic sweep (no DEM) with the default workers
SCRIPT = """\
import tomllib, demseis
print("SCRIPT-START", flush=True)
cfg = tomllib.load(open({preset!r}, "rb"))
cfg["model"]["engine"] = "kinematic"
store = demseis.generate(cfg, out="k.zarr", overwrite=True)
assert store.done.all(), store
print("SCRIPT-DONE", len(store), flush=True)
"""

TINY = str(ROOT / "demseis" / "generator" / "presets" / "tiny.toml")


def _run(args: list[str], cwd, stdin: str | None = None, method: str | None = None):
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(ROOT), str(cwd)])}
    env.pop("DEMSEIS_WORKER_START", None)
    if method:
        env["DEMSEIS_WORKER_START"] = method
    return subprocess.run([sys.executable, *args], cwd=cwd, env=env, input=stdin,
                          capture_output=True, text=True, timeout=120)


def _check(res) -> None:
    assert res.returncode == 0, res.stderr[-3000:]
    assert res.stdout.count("SCRIPT-START") == 1, res.stdout  # the script ran once, not per worker
    assert "SCRIPT-DONE 18" in res.stdout
    assert "bootstrapping" not in res.stderr and "Traceback" not in res.stderr, res.stderr[-3000:]


@pytest.mark.parametrize("method", ["forkserver", "spawn"])
def test_script_without_main_guard(tmp_path, method):
    if method == "forkserver" and sys.platform == "win32":
        pytest.skip("no forkserver on this platform")
    (tmp_path / "user_script.py").write_text(SCRIPT.format(preset=TINY))
    _check(_run(["user_script.py"], tmp_path, method=method))


def test_script_from_stdin(tmp_path):
    _check(_run(["-"], tmp_path, stdin=SCRIPT.format(preset=TINY)))


def test_code_run_like_a_notebook_cell(tmp_path):
    """A kernel runs a cell's code in a ``__main__`` without a file, as ``python -c`` does."""
    _check(_run(["-c", SCRIPT.format(preset=TINY)], tmp_path))


def test_unguarded_module_run_with_dash_m(tmp_path):
    (tmp_path / "user_module.py").write_text(SCRIPT.format(preset=TINY))
    _check(_run(["-m", "user_module"], tmp_path))


def test_main_module_hidden_restores_the_main_module(monkeypatch):
    fake = types.ModuleType("__main__")
    fake.__file__ = "/somewhere/script.py"
    spec = types.SimpleNamespace(name="script")
    fake.__spec__ = spec
    monkeypatch.setitem(sys.modules, "__main__", fake)
    with main_module_hidden():
        assert not hasattr(fake, "__file__") and fake.__spec__ is None
        from multiprocessing import spawn

        data = spawn.get_preparation_data("x")
        assert "main_path" not in data and "init_main_from_name" not in data
    assert fake.__file__ == "/somewhere/script.py" and fake.__spec__ is spec


def test_relative_out_after_a_change_of_directory(tmp_path):
    """The forkserver keeps the directory it started in; a relative --out still lands in the
    caller's current directory (a notebook that called os.chdir)."""
    (tmp_path / "a").mkdir()
    (tmp_path / "b").mkdir()
    code = ("import os, tomllib, demseis\n"
            f"cfg = tomllib.load(open({TINY!r}, 'rb'))\n"
            "cfg['model']['engine'] = 'kinematic'\n"
            "demseis.generate(cfg, out='first.zarr')\n"
            "os.chdir('../b')\n"
            "s = demseis.generate(cfg, out='second.zarr')\n"
            "assert s.done.all(), s\n"
            "print('SCRIPT-START SCRIPT-DONE 18')\n")
    _check(_run(["-c", code], tmp_path / "a"))
    assert (tmp_path / "b" / "second.zarr").is_dir() and not (tmp_path / "a" / "second.zarr").exists()
