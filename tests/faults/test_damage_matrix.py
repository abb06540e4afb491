"""Every command on a damaged store: one line naming what is damaged, exit 2 (issue 30).

The matrix is damage kind x command. Damage kinds: a truncated chunk (seismic shard file cut
short), flipped bytes (in a fault chunk), a truncated or missing ``zarr.json`` of an array
(seismic) and of the root, a missing shard file. Commands: ``info``, ``validate``, ``plot``,
``export-segy``, ``baseline``, ``score`` and the Dataset (through ``python -c``), each in its
own process as a user runs it. ``validate`` lists data damage as problems (exit 1, its
contract) and refuses what it cannot open (exit 2); ``generate`` repairs every kind: the
resumed store is byte-identical to the undamaged one.
"""

from __future__ import annotations

import hashlib
import re
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from tests.faults._helpers import ROOT

#: the tiny preset with 3 runs of the fast kinematic engine
CONFIG = '[sweep]\nn_runs = 3\n[model]\nengine = "kinematic"\n'

DAMAGE = ("truncated-chunk", "flipped-bytes", "array-meta-truncated", "array-meta-missing",
          "root-meta-truncated", "root-meta-missing", "missing-shard")
COMMANDS = ("info", "validate", "plot", "export-segy", "baseline", "score", "dataset")
#: the sample arrays whose data each command reads (the damage of others does not concern it)
READS = {"info": (), "plot": ("seismic", "fault"), "export-segy": ("seismic",),
         "baseline": ("seismic",), "score": ("fault",), "dataset": ("seismic", "fault")}


def _run(args: list[str], cwd: Path) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, *args], capture_output=True, text=True, cwd=cwd,
                          env={"PYTHONPATH": str(ROOT), "PATH": "/usr/bin:/bin",
                               "MPLBACKEND": "Agg"}, timeout=300)


def _digest(path: Path) -> dict[str, str]:
    return {str(f.relative_to(path)): hashlib.sha256(f.read_bytes()).hexdigest()
            for f in sorted(path.rglob("*")) if f.is_file()}


@pytest.fixture(scope="module")
def pristine(tmp_path_factory) -> Path:
    """A finished 3-run kinematic store (with its config file and zero predictions)."""
    base = tmp_path_factory.mktemp("matrix")
    (base / "c.toml").write_text(CONFIG)
    r = _run(["-m", "demseis", "generate", "c.toml", "--preset", "tiny", "--out", "s.zarr",
              "--workers", "0", "--quiet"], base)
    assert r.returncode == 0, r.stderr
    from demseis.datasets import read_layout

    lay = read_layout(base / "s.zarr")
    np.save(base / "pred.npy", np.zeros((lay.n_samples, *lay.shape), np.float32))
    return base


def damage(store: Path, kind: str) -> None:
    """Damage shard 0 (samples 0..S-1) of ``store`` or its metadata in the way ``kind`` says."""
    if kind == "truncated-chunk":
        f = store / "seismic" / "c" / "0" / "0" / "0"
        data = f.read_bytes()
        f.write_bytes(data[: len(data) // 2])
    elif kind == "flipped-bytes":
        f = store / "fault" / "c" / "0" / "0" / "0"
        data = bytearray(f.read_bytes())
        for i in range(16):
            data[10 + i] ^= 0xFF
        f.write_bytes(bytes(data))
    elif kind == "array-meta-truncated":
        f = store / "seismic" / "zarr.json"
        f.write_bytes(f.read_bytes()[:100])
    elif kind == "array-meta-missing":
        (store / "seismic" / "zarr.json").unlink()
    elif kind == "root-meta-truncated":
        f = store / "zarr.json"
        f.write_bytes(f.read_bytes()[:100])
    elif kind == "root-meta-missing":
        (store / "zarr.json").unlink()
    elif kind == "missing-shard":
        (store / "seismic" / "c" / "0" / "0" / "0").unlink()
    else:  # pragma: no cover
        raise ValueError(kind)


def _command(cmd: str, base: Path) -> list[str]:
    m = ["-m", "demseis"]
    return {
        "info": [*m, "info", "s.zarr"],
        "validate": [*m, "validate", "s.zarr"],
        "plot": [*m, "plot", "s.zarr", "--sample", "0", "--out", "p.png"],
        "export-segy": [*m, "export-segy", "s.zarr", "--sample", "0", "--out", "s.sgy"],
        "baseline": [*m, "baseline", "s.zarr", "--out", "b.npy"],
        "score": [*m, "score", "pred.npy", "s.zarr"],
        "dataset": ["-c", "import sys\nfrom demseis.datasets import FaultSegDataset\n"
                    "from demseis.errors import DemseisError\ntry:\n"
                    "    ds = FaultSegDataset('s.zarr')\n    ds.__getitems__(list(range(len(ds))))\n"
                    "except DemseisError as e:\n    print(f'demseis: error: {e}', file=sys.stderr)\n"
                    "    sys.exit(2)\n"],
    }[cmd]


@pytest.mark.slow
@pytest.mark.parametrize("cmd", COMMANDS)
@pytest.mark.parametrize("kind", DAMAGE)
def test_damaged_store_gives_one_line(tmp_path, pristine, kind, cmd):
    shutil.copytree(pristine / "s.zarr", tmp_path / "s.zarr")
    shutil.copy(pristine / "pred.npy", tmp_path / "pred.npy")
    damage(tmp_path / "s.zarr", kind)
    r = _run(_command(cmd, tmp_path), tmp_path)
    err = r.stderr.strip().splitlines()
    assert "Traceback" not in r.stderr and "Warning" not in r.stderr, r.stderr[-3000:]
    array = "fault" if kind == "flipped-bytes" else "seismic"
    if cmd == "validate" and not kind.startswith("root"):
        # validate's contract: exit 1, one line per problem (naming the array), then a summary
        assert r.returncode == 1, (r.stdout, r.stderr)
        assert any(array in line for line in r.stdout.splitlines()[:-1]), r.stdout
        return
    if kind.startswith("root"):
        assert r.returncode == 2, r.stderr
        assert len(err) == 1 and err[0].startswith("demseis: error: ") and "zarr.json" in err[0]
    elif kind in ("truncated-chunk", "flipped-bytes", "missing-shard"):
        if array not in READS[cmd]:  # the command does not read the damaged array
            assert r.returncode == 0, r.stderr
            return
        assert r.returncode == 2, (r.stdout, r.stderr[-3000:])
        assert len(err) == 1 and err[0].startswith("demseis: error: "), r.stderr
        assert re.search(rf"samples? 0(\.\.\d+)? of array '{array}'", err[0]), err[0]
    else:
        # an array's metadata: the readers that find it damaged say so in one line; those
        # that read the consolidated copy in the root (intact) are right to go on
        assert r.returncode in (0, 2), r.stderr
        if r.returncode == 2:
            assert len(err) == 1 and err[0].startswith("demseis: error: "), r.stderr
            assert "zarr.json" in err[0] or "seismic" in err[0], err[0]


@pytest.mark.slow
@pytest.mark.parametrize("kind", DAMAGE)
def test_generate_repairs_every_damage(tmp_path, pristine, kind):
    shutil.copytree(pristine / "s.zarr", tmp_path / "s.zarr")
    shutil.copy(pristine / "c.toml", tmp_path / "c.toml")
    damage(tmp_path / "s.zarr", kind)
    r = _run(["-m", "demseis", "generate", "c.toml", "--preset", "tiny", "--out", "s.zarr",
              "--workers", "0", "--quiet"], tmp_path)
    assert r.returncode == 0, r.stderr[-3000:]
    assert _digest(tmp_path / "s.zarr") == _digest(pristine / "s.zarr")
