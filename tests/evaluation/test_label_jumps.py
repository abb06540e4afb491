"""benchmarks/label_jumps.py: the rock's jump across a label from element displacements."""

from __future__ import annotations

import runpy
from pathlib import Path

import numpy as np
import pytest

BENCH = Path(__file__).resolve().parents[2] / "benchmarks" / "label_jumps.py"


@pytest.fixture(scope="module")
def lj():
    return runpy.run_path(str(BENCH), run_name="label_jumps")


def _elements(seed: int = 0):
    """Elements scattered over 1000 x 500 m."""
    rng = np.random.default_rng(seed)
    return rng.uniform(0, 1000, 4000), rng.uniform(0, 500, 4000)


@pytest.mark.parametrize("dip_deg, opening_m", [(60.0, 0.0), (60.0, 10.0), (80.0, 4.0)])
def test_side_jump_reads_a_block_motion(lj, dip_deg, opening_m):
    """A hanging wall right of a plane through (500, 250) slips 12 m down the dip and opens by
    ``opening_m``: the jump is that vector, at any point of the plane."""
    ex, ey = _elements()
    t = np.radians(dip_deg)
    xf = 500.0 + (250.0 - ey) / np.tan(t)           # the plane dips to the right
    hw = ex > xf
    ux = np.where(hw, 12.0 * np.cos(t) + opening_m, 0.0)
    uy = np.where(hw, -12.0 * np.sin(t), 0.0)
    for y in (200.0, 250.0, 300.0):
        x = 500.0 + (250.0 - y) / np.tan(t)
        dx, dy = lj["side_jump"](ex, ey, ux, uy, x, y, 30.0, 90.0, 30.0)
        assert dx == pytest.approx(12.0 * np.cos(t) + opening_m)
        assert dy == pytest.approx(-12.0 * np.sin(t))


def test_side_jump_needs_elements_on_both_sides(lj):
    ex, ey = _elements()
    u = np.zeros_like(ex)
    assert lj["side_jump"](ex, ey, u, u, 20.0, 250.0, 30.0, 90.0, 30.0) is None
    assert lj["side_jump"](ex, ey, u, u, 500.0, 250.0, 30.0, 90.0, 30.0) == (0.0, 0.0)


def test_reference_jump_removes_the_trend(lj):
    row = 0.7 * np.arange(30.0)                     # a tilted bed: 0.7 m per trace
    row[15:] -= 5.0                                 # a 5 m step between traces 14 and 15
    assert lj["reference_jump"](row, 15) == pytest.approx(5.0)
    assert lj["reference_jump"](row, 3) is None     # too near the edge for the trend
    row[17] = np.nan                                # no rock within the window
    assert lj["reference_jump"](row, 15) is None
    assert lj["reference_jump"](0.7 * np.arange(30.0), 15) == pytest.approx(0.0)
