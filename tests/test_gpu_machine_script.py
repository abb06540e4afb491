"""benchmarks/gpu_machine.sh, the GPU machine's measurements, checked at GPU_SMALL size here."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
SCRIPT = ROOT / "benchmarks" / "gpu_machine.sh"


def _run(args: list[str], tmp_path: Path) -> subprocess.CompletedProcess:
    env = {**os.environ, "GPU_SMALL": "1", "GPU_WORK": str(tmp_path / "work"),
           "OUT": str(tmp_path / "out"),
           "PATH": f"{Path(sys.executable).parent}{os.pathsep}{os.environ.get('PATH', '')}"}
    return subprocess.run(["bash", str(SCRIPT), *args], cwd=ROOT, env=env, capture_output=True,
                          text=True, timeout=600)


def _lines(path: Path) -> list[dict]:
    return [json.loads(x) for x in path.read_text().splitlines()]


def test_probe_and_bad_stages(tmp_path):
    res = _run(["probe"], tmp_path)
    assert res.returncode == 0, res.stderr
    probe = _lines(tmp_path / "out" / "gpu_results.jsonl")[0]
    assert probe["stage"] == "probe" and probe["cpus"] == os.cpu_count()
    assert probe["numpy"] and "torch" in probe
    for bad in (["nonsense"], ["learn", "bogus"]):
        res = _run(bad, tmp_path)
        assert res.returncode == 2 and res.stderr.strip(), bad


@pytest.mark.slow
def test_learn_half_keeps_the_held_out_runs(tmp_path):
    res = _run(["learn", "new48"], tmp_path)
    assert res.returncode == 0, res.stderr[-2000:]
    rows = _lines(tmp_path / "out" / "gpu_results.jsonl")
    assert [r["stage"] for r in rows] == ["learn_store", "learn"]
    result = rows[1]["result"]
    assert result["train_runs_used"] == 2 and result["test_runs"] == 2
    assert (tmp_path / "out" / "pred_new48.npz").stat().st_size > 0  # for the figure
    bands = result["test_recall_by_slip_tol2"]  # a generated store has slip_m
    assert set(bands) == {"below", "10-20", "20-40", "40-80", "80-160", "160-inf"}
    assert sum(n for _, n in bands.values()) > 0
