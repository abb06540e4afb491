"""The PSF figure script (outside the package) still runs end to end (slow)."""

import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]


@pytest.mark.slow
def test_psf_figure_script_runs_on_the_toy_snapshot(tmp_path):
    out = tmp_path / "psf.png"
    res = subprocess.run([sys.executable, str(ROOT / "scripts" / "psf_figure.py"), "--out",
                          str(out), "--angles", "40", "15"], capture_output=True, text=True,
                         cwd=ROOT, timeout=300)
    assert res.returncode == 0, res.stderr
    assert out.stat().st_size > 20_000
