"""Light imports; figure functions run end to end (slow)."""

import subprocess
import sys

import numpy as np
import pytest


def test_import_is_light():
    code = ("import sys, demseis.seismic; "
            "print(sorted(m for m in ('torch', 'dask', 'matplotlib') if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"


def test_toy_sequence_geometry():
    from demseis.seismic.demo import faulted_sequence

    snaps = faulted_sequence(1000.0, 600.0, n_layers=6, throw_m=120.0, dip_deg=60.0,
                             n_snapshots=4, rng=np.random.default_rng(0))
    assert [s.throw_m for s in snaps] == [0.0, 40.0, 80.0, 120.0]
    first, last = snaps[0], snaps[-1]
    np.testing.assert_array_equal(last.ids[: first.n], first.ids)  # ids are stable
    moved = np.linalg.norm(last.xy[: first.n] - first.xy, axis=1)
    # rigid hanging wall: moved by throw / sin(dip) down-dip, footwall not at all
    np.testing.assert_allclose(np.unique(np.round(moved, 6)), [0.0, 120.0 / np.sin(np.radians(60))])
    assert last.layer.max() == 6 + 3 - 1 and last.deposited.sum() > 0


@pytest.mark.slow
def test_figures_render(tmp_path):
    from demseis.seismic.demo import faulted_sequence
    from demseis.seismic.figures import (frequency_sequence_figure, properties_figure,
                                         tuning_figure)
    from demseis.seismic.grid import Grid

    snaps = faulted_sequence(800.0, 500.0, n_layers=8, throw_m=100.0, n_snapshots=3,
                             rng=np.random.default_rng(0))
    grid = Grid.covering(800.0, 500.0)
    frequency_sequence_figure(snaps, grid, tmp_path / "a.png", "toy")
    properties_figure(snaps[-1], grid, tmp_path / "b.png", "toy")
    tuning_figure(tmp_path / "c.png")
    assert all((tmp_path / n).stat().st_size > 10_000 for n in ("a.png", "b.png", "c.png"))
