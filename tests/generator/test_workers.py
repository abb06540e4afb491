"""How the sweep starts its local workers (demseis.generator.sweep.workers): forked from a forkserver
that has loaded the kernels, or spawned; either way the same bytes."""

from __future__ import annotations

import multiprocessing
import os
import subprocess
import sys

import pytest

from demseis.errors import InputError
from demseis.generator.sweep.workers import worker_start_method
from tests._helpers import ROOT
from tests.generator._helpers import assert_same_bytes


def test_default_method_is_forkserver_where_available(monkeypatch):
    monkeypatch.delenv("DEMSEIS_WORKER_START", raising=False)
    expected = "forkserver" if "forkserver" in multiprocessing.get_all_start_methods() else "spawn"
    assert worker_start_method() == expected


def test_method_can_be_forced(monkeypatch):
    monkeypatch.setenv("DEMSEIS_WORKER_START", "spawn")
    assert worker_start_method() == "spawn"


@pytest.mark.parametrize("value", ["fork", "threads", "Spawn"])
def test_unknown_method_is_one_clear_error(monkeypatch, value):
    monkeypatch.setenv("DEMSEIS_WORKER_START", value)
    with pytest.raises(InputError, match="DEMSEIS_WORKER_START") as err:
        worker_start_method()
    assert "spawn" in str(err.value)


def test_unknown_method_from_the_cli_exits_2(tmp_path):
    env = {**os.environ, "DEMSEIS_WORKER_START": "threads"}
    res = subprocess.run([sys.executable, "-m", "demseis", "generate", "--preset", "tiny", "--out",
                          str(tmp_path / "x.zarr"), "--workers", "1", "--quiet"],
                         cwd=ROOT, env=env, capture_output=True, text=True)
    assert res.returncode == 2, res.stderr
    assert "DEMSEIS_WORKER_START" in res.stderr and "Traceback" not in res.stderr
    assert not (tmp_path / "x.zarr").exists()


@pytest.mark.skipif("forkserver" not in multiprocessing.get_all_start_methods(),
                    reason="no forkserver on this platform")
def test_forked_workers_start_with_the_kernels_loaded(monkeypatch):
    """A forked worker has every kernel of a run loaded before its first task (the preload);
    a spawned one has none, and would load them in its first task."""
    from demseis.generator.sweep.cluster import _start_local_cluster
    from demseis.generator.sweep.driver import warm_numba_cache

    def loaded_signatures() -> dict[str, int]:
        import sys as worker_sys

        kernels = worker_sys.modules.get("demseis.labels._kernels")
        dem = worker_sys.modules.get("demseis.dem._kernels")
        return {"labels": len(kernels.finite_strain.signatures) if kernels else 0,
                "dem_loaded": int(dem is not None)}

    seen = {}
    for method in ("forkserver", "spawn"):
        monkeypatch.setenv("DEMSEIS_WORKER_START", method)
        client, cluster = _start_local_cluster(warm_numba_cache, {}, 1, 0)
        try:
            seen[method] = list(client.run(loaded_signatures).values())[0]
        finally:
            client.close()
            cluster.close()
    assert seen["forkserver"]["labels"] >= 1 and seen["forkserver"]["dem_loaded"] == 1
    assert seen["spawn"] == {"labels": 0, "dem_loaded": 0}


@pytest.mark.slow
def test_spawned_and_forked_workers_write_the_same_bytes(tiny_store, tmp_path):
    for method in ("spawn", "forkserver"):
        out = tmp_path / f"{method}.zarr"
        env = {**os.environ, "DEMSEIS_WORKER_START": method}
        res = subprocess.run([sys.executable, "-m", "demseis", "generate", "--preset", "tiny",
                              "--out", str(out), "--workers", "2", "--quiet"],
                             cwd=ROOT, env=env, capture_output=True, text=True)
        assert res.returncode == 0, res.stderr[-2000:]
        assert_same_bytes(tiny_store, out)
