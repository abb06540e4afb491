"""benchmarks/fault_lags.py: the step of the reflectors at fault pixels, read from the seismic."""

from __future__ import annotations

import runpy
from pathlib import Path

import numpy as np
import pytest

BENCH = Path(__file__).resolve().parents[2] / "benchmarks" / "fault_lags.py"


@pytest.fixture(scope="module")
def fl():
    return runpy.run_path(str(BENCH), run_name="fault_lags")


def _stepped_section(step: int):
    """Random reflectivity, level beds, the traces right of column 40 shifted down by ``step``
    samples; a one-pixel fault label along column 40."""
    rng = np.random.default_rng(1)
    h, w = 120, 80
    trace = np.convolve(rng.standard_normal(h + 20), np.hanning(7), mode="same")
    sec = np.empty((h, w))
    sec[:, :40] = trace[10:10 + h, None]
    sec[:, 40:] = trace[10 - step:10 - step + h, None]
    fault = np.zeros((h, w), np.uint8)
    fault[:, 40] = 1
    return sec, fault


@pytest.mark.parametrize("step", [0, 1, 2, 3])
def test_the_step_at_the_fault_and_none_beside_it(fl, step):
    sec, fault = _stepped_section(step)
    at_fault, background = fl["section_lags"](sec, fault, np.random.default_rng(0))
    assert at_fault.size == 120 - 2 * 12                   # rows whose window fits
    assert np.all(at_fault == step)
    assert background.size > 0 and np.all(background == 0)
    line = fl["summary"]("s", [at_fault], [background])
    assert line["median_fault_lag"] == step
    assert line["fault_lag_at_least_1_2_3"] == [float(step >= k) for k in (1, 2, 3)]
    assert line["background_lag_at_least_1_2_3"] == [0.0, 0.0, 0.0]


def test_traces_holding_another_label_are_skipped(fl):
    sec, fault = _stepped_section(2)
    fault[:, 37] = 1                                        # a second label 3 traces left
    at_fault, _ = fl["section_lags"](sec, fault, np.random.default_rng(0))
    # column 40 sees the label at 37 in its left trace; column 37 sees it at 40 on its right
    assert at_fault.size == 0
