"""benchmarks/fetch_field_gsb.sh: the hand-picked Great South Basin sections taken from a
(mirror of the) source repository into a cache folder as (H, W) seismic and mask pairs."""

from __future__ import annotations

import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

SCRIPT = Path(__file__).resolve().parents[1] / "benchmarks" / "fetch_field_gsb.sh"
LINES = ("crl_2600", "crl_2700", "crl_2800", "crl_2900", "crl_3000", "inl_1791", "inl_2011")

pytestmark = pytest.mark.skipif(shutil.which("git") is None or shutil.which("sh") is None,
                                reason="needs git and sh")


def _mirror(root: Path, bad: str | None = None) -> Path:
    """A git repository laid out as the source: gsbData/gsb_<line>.npy (1, H, W) float64 and
    gsb_<line>_mask.npy (1, H, W) uint8 (``bad``: that line's mask of another shape)."""
    data = root / "SFD-CNN-TL" / "gsbData"
    data.mkdir(parents=True)
    rng = np.random.default_rng(0)
    for i, line in enumerate(LINES):
        seis = rng.normal(size=(1, 6, 9 + i))
        mask = np.zeros(seis.shape, np.uint8)
        mask[0, :, 3] = 1
        np.save(data / f"gsb_{line}.npy", seis)
        np.save(data / f"gsb_{line}_mask.npy", mask[:, :, :-1] if line == bad else mask)
    git = ["git", "-c", "user.email=t@t", "-c", "user.name=t"]
    subprocess.run(["git", "init", "-q", str(root)], check=True)
    subprocess.run([*git, "-C", str(root), "add", "-A"], check=True)
    subprocess.run([*git, "-C", str(root), "commit", "-qm", "data"], check=True)
    return root


def _fetch(repo: Path, dest: Path) -> subprocess.CompletedProcess:
    env = {"PATH": "/usr/bin:/bin", "FIELD_REPO": str(repo), "PYTHON": sys.executable,
           "HOME": str(dest.parent)}
    return subprocess.run(["sh", str(SCRIPT), str(dest)], env=env, capture_output=True,
                          text=True, timeout=120)


def test_six_lines_become_section_and_mask_pairs(tmp_path):
    repo = _mirror(tmp_path / "repo")
    dest = tmp_path / "cache"
    done = _fetch(repo, dest)
    assert done.returncode == 0, done.stderr
    names = sorted(p.name for p in dest.iterdir())
    keep = [ln for ln in LINES if ln != "crl_2800"]
    assert names == sorted(["SOURCE_COMMIT"] + [f"{k}_{ln}.npy" for k in ("mask", "seismic")
                                                for ln in keep])
    for line in keep:
        src = np.load(repo / "SFD-CNN-TL" / "gsbData" / f"gsb_{line}.npy")
        seis, mask = np.load(dest / f"seismic_{line}.npy"), np.load(dest / f"mask_{line}.npy")
        assert seis.dtype == np.float32 and mask.dtype == np.uint8
        np.testing.assert_array_equal(seis, src[0].astype(np.float32))
        assert mask.shape == seis.shape and mask.sum() == 6 and mask[:, 3].all()
    head = subprocess.run(["git", "-C", str(repo), "rev-parse", "HEAD"], capture_output=True,
                          text=True, check=True).stdout
    assert (dest / "SOURCE_COMMIT").read_text() == head


def test_a_mask_of_another_shape_is_refused(tmp_path):
    done = _fetch(_mirror(tmp_path / "repo", bad="inl_1791"), tmp_path / "cache")
    assert done.returncode != 0
    assert "gsb_inl_1791: seismic (1, 6, 14) and mask (1, 6, 13)" in done.stderr
