"""The DEM coverage check: jump field against a slow per-cell reference."""

from __future__ import annotations

import numpy as np
import pytest

from demseis.errors import InputError
from demseis.labels import rasterise_strain
from demseis.seismic.raster import rasterise
from demseis.types import Grid, Snapshot
from demseis_dev.coverage import jump_coverage, jump_field
from demseis_dev.toys import disk_pack


def _jump_reference(u, coh, reach):
    nz, nx = coh.shape
    out = np.zeros((nz, nx))
    for i in range(nz):
        for j in range(nx):
            for dr in range(-reach, reach + 1):
                for dc in range(-reach, reach + 1):
                    ia, ja, ib, jb = i + dr, j + dc, i - dr, j - dc
                    if not (0 <= ia < nz and 0 <= ja < nx and 0 <= ib < nz and 0 <= jb < nx):
                        continue
                    if coh[ia, ja] < 0 or coh[ia, ja] != coh[ib, jb]:
                        continue
                    d = u[ia, ja] - u[ib, jb]
                    if np.all(np.isfinite(d)):
                        out[i, j] = max(out[i, j], float(np.hypot(*d)))
    return out


def test_jump_field_matches_reference_and_sees_a_step():
    xy, r = disk_pack(400.0, 200.0, np.random.default_rng(3))
    n = xy.shape[0]
    disp = np.zeros((n, 2))
    disp[xy[:, 0] > 200.0, 1] = -30.0  # a vertical step of 30 m at x = 200 m
    birth = (xy[:, 1] > 150.0).astype(np.int64)  # two cohorts: no jump across their boundary
    disp[birth == 1, 1] += 5.0
    snap = Snapshot(0, 0, 0.0, np.arange(n, dtype=np.int64), xy, r, np.zeros(n, np.int16),
                    np.zeros(n, bool))
    grid = Grid.covering(400.0, 200.0, 10.0)
    jump, rock = jump_field(snap, disp, birth, grid)
    u, _ = rasterise(xy, r, disp, grid)
    _, owner = rasterise_strain(xy, r, np.zeros(n), grid)
    coh = np.where(owner >= 0, birth[np.maximum(owner, 0)], -1)
    np.testing.assert_allclose(jump, _jump_reference(u, coh, 2))
    assert np.array_equal(rock, owner >= 0)
    hi = jump >= 20.0
    assert hi[:, 17:23].any(axis=1).mean() > 0.9  # the step is seen along its length
    assert not hi[:, :14].any() and not hi[:, 26:].any()  # and nowhere else
    line = np.zeros(grid.shape, dtype=bool)
    line[:, 20] = True
    n_hi, n_near = jump_coverage(line, jump, rock, 10.0)
    cols = np.arange(grid.nx)[None, :]
    assert n_hi == int((hi & rock).sum())
    assert n_near == int((hi & rock & (np.abs(cols - 20) <= 2)).sum()) > 0.8 * n_hi
    assert jump_coverage(np.zeros_like(line), jump, rock, 10.0) == (n_hi, 0)


def test_jump_coverage_chessboard_metric_counts_the_diagonal_of_the_box():
    """A high-jump cell 2 rows and 2 columns from the only label cell: outside 2 cells in the
    Euclidean metric (2.83), inside in the chessboard metric (the jump's own +-2 box)."""
    fault = np.zeros((9, 9), bool)
    fault[4, 4] = True
    jump = np.zeros((9, 9))
    jump[6, 6] = 50.0  # diagonal, 2 cells each way
    jump[4, 6] = 50.0  # straight, 2 cells
    jump[4, 7] = 50.0  # straight, 3 cells: outside either way
    rock = np.ones((9, 9), bool)
    assert jump_coverage(fault, jump, rock, 10.0) == (3, 1)
    assert jump_coverage(fault, jump, rock, 10.0, metric="chessboard") == (3, 2)
    with pytest.raises(InputError, match="metric"):
        jump_coverage(fault, jump, rock, 10.0, metric="manhattan")


def _coverage_benchmark():
    import importlib.util
    from pathlib import Path

    path = Path(__file__).resolve().parents[2] / "benchmarks" / "labels_dem_coverage.py"
    spec = importlib.util.spec_from_file_location("labels_dem_coverage", path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def test_coverage_benchmark_set_overrides_label_keys_like_a_toml_table():
    from demseis.errors import ConfigError
    from demseis.labels import LabelConfig

    bench = _coverage_benchmark()
    sets = bench.parse_sets(["min_trace_cells=8", "min_dip_deg = 12.5", "method='slip_trace'"])
    assert sets == {"min_trace_cells": 8, "min_dip_deg": 12.5, "method": "slip_trace"}
    lc = bench.labels_config(LabelConfig(), 0.0, sets)
    assert (lc.min_trace_cells, lc.min_dip_deg, lc.strand_sigma_cells) == (8, 12.5, 0.0)
    assert lc.ridge_threshold == LabelConfig().ridge_threshold  # the rest stays
    with pytest.raises(InputError, match="KEY=VALUE"):
        bench.parse_sets(["min_trace_cells"])
    with pytest.raises(InputError, match="not TOML"):
        bench.parse_sets(["method=strain_band"])
    with pytest.raises(ConfigError, match="unknown key"):
        bench.labels_config(LabelConfig(), None, {"min_trace": 8})
    with pytest.raises(ConfigError, match="min_dip_deg"):
        bench.labels_config(LabelConfig(), None, {"min_dip_deg": 120.0})
