"""The docs-figure scripts (outside the package) still run end to end (slow)."""

import importlib.util
from pathlib import Path

import numpy as np
import pytest

SCRIPTS = Path(__file__).resolve().parents[1] / "scripts"


@pytest.mark.slow
def test_seismic_figures_render(tmp_path):
    spec = importlib.util.spec_from_file_location("seismic_figures", SCRIPTS / "seismic_figures.py")
    figures = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(figures)
    from demseis.diagnostics.toys import faulted_sequence
    from demseis.types import Grid

    snaps = faulted_sequence(800.0, 500.0, n_layers=8, throw_m=100.0, n_snapshots=3,
                             rng=np.random.default_rng(0))
    grid = Grid.covering(800.0, 500.0)
    figures.frequency_sequence_figure(snaps, grid, tmp_path / "a.png", "toy")
    figures.properties_figure(snaps[-1], grid, tmp_path / "b.png", "toy")
    figures.tuning_figure(tmp_path / "c.png")
    assert all((tmp_path / n).stat().st_size > 10_000 for n in ("a.png", "b.png", "c.png"))
