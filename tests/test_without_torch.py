"""torch is an extra: without it demseis generates, validates, renders, scores and runs its
baseline; what needs it (the Dataset, training, prediction) says in one line which extra to
install. torch is made unimportable for the subprocesses (and their dask workers) by a package
``torch`` on PYTHONPATH whose import fails the way a missing module does."""

from __future__ import annotations

import os
import subprocess
import sys

import pytest

from tests._helpers import ROOT


@pytest.fixture(scope="module")
def no_torch(tmp_path_factory):
    """(run, directory): run(*args) runs ``python -m demseis ARGS`` with torch unimportable."""
    d = tmp_path_factory.mktemp("no_torch")
    shim = d / "shim" / "torch"
    shim.mkdir(parents=True)
    (shim / "__init__.py").write_text(
        "raise ModuleNotFoundError(\"No module named 'torch'\", name='torch')\n")
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(d / "shim"), str(ROOT)])}

    def run(*args: str, code: str | None = None):
        cmd = [sys.executable, "-c", code] if code else [sys.executable, "-m", "demseis", *args]
        return subprocess.run(cmd, cwd=d, env=env, capture_output=True, text=True, timeout=300)

    return run, d


def test_the_shim_hides_torch(no_torch):
    run, _ = no_torch
    res = run(code="import torch")
    assert res.returncode == 1 and "No module named 'torch'" in res.stderr


def test_generate_validate_render_baseline_score_without_torch(no_torch):
    run, d = no_torch
    for args in (["generate", "--preset", "tiny", "--out", "t.zarr", "--workers", "1", "--quiet"],
                 ["validate", "t.zarr"],
                 ["info", "t.zarr"],
                 ["render", "t.zarr", "--freq", "20", "--out", "r.zarr", "--quiet"],
                 ["baseline", "t.zarr", "--out", "pred.npy"],
                 ["score", "pred.npy", "t.zarr", "--out-prefix", "s"]):
        res = run(*args)
        assert res.returncode == 0, (args, res.stderr[-2000:])
        assert "torch" not in res.stderr, (args, res.stderr[-2000:])
    assert (d / "s.json").exists()
    # the Python API too, with its default (dask) workers
    res = run(code="import demseis, sys; s = demseis.generate('tiny', out='api.zarr'); "
                   "assert s.done.all(); assert 'torch' not in sys.modules; "
                   "print(demseis.score(s.sample(0)['fault'][None] * 1.0, s, indices=[0]).overall)")
    assert res.returncode == 0, res.stderr[-2000:]


def test_what_needs_torch_names_the_extra(no_torch):
    run, _ = no_torch
    res = run(code="import demseis\n"
                   "try:\n    demseis.open('t.zarr').torch_dataset()\n"
                   "except demseis.DemseisError as e:\n    print('ERR', e)\n")
    assert res.returncode == 0, res.stderr[-2000:]
    line = res.stdout.strip()
    assert line.startswith("ERR Store.torch_dataset needs PyTorch") and "demseis[torch]" in line


@pytest.mark.parametrize("args", [["train", "t.zarr", "--out", "m.pt"],
                                  ["predict", "m.pt", "in.npy", "--out", "out.npy"],
                                  ["predict", "m.pt", "in.npy", "--out", "o.npy", "--mask",
                                   "k.npy"],
                                  ["threshold", "m.pt", "t.zarr"]])
def test_train_and_predict_name_the_extra(no_torch, args):
    run, d = no_torch
    import numpy as np

    np.save(d / "in.npy", np.zeros((8, 8), np.float32))
    (d / "m.pt").write_bytes(b"not a model")
    res = run(*args)
    assert res.returncode == 2, res.stderr
    assert res.stderr.count("\n") == 1 and "needs PyTorch" in res.stderr
    assert 'pip install "demseis[torch]"' in res.stderr
