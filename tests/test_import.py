"""``import demseis`` (and its subpackages' light modules) must not pull in torch, dask or matplotlib."""

from __future__ import annotations

import subprocess
import sys

CODE = """
import sys
import demseis, demseis.dem, demseis.seismic, demseis.labels, demseis.datasets, demseis.generator
import demseis.cli, demseis.evaluation, demseis.types, demseis_dev.toys
heavy = sorted(m for m in ("torch", "dask", "distributed", "matplotlib") if m in sys.modules)
print(",".join(heavy))
"""


def test_import_is_light():
    proc = subprocess.run([sys.executable, "-c", CODE], capture_output=True, text=True, check=True)
    assert proc.stdout.strip() == "", f"heavy modules imported by `import demseis`: {proc.stdout}"


def test_help_is_fast_and_light():
    code = "import sys; from demseis.cli import build_parser; build_parser(); " \
           "print(','.join(m for m in ('torch','dask','matplotlib') if m in sys.modules))"
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert proc.stdout.strip() == ""
