"""benchmarks/labels_visibility.py: the label pixels' offsets by slip band."""

from __future__ import annotations

import runpy
from pathlib import Path

import numpy as np
import pytest

BENCH = Path(__file__).resolve().parents[2] / "benchmarks" / "labels_visibility.py"


@pytest.fixture(scope="module")
def lv():
    return runpy.run_path(str(BENCH), run_name="labels_visibility")


def _section():
    """Two vertical labels: one of 15 m slip on an offset of 1.5 samples, one of 50 m slip on
    an offset of 0.5 samples (below a visible offset of 1), rock everywhere."""
    h, w = 30, 40
    fault = np.zeros((h, w), np.uint8)
    slip = np.zeros((h, w), np.float32)
    offset = np.full((h, w - 1), np.nan)
    fault[:, 10] = 1
    slip[:, 10] = 15.0
    offset[:, 10] = 1.5                          # the pair (10, 11)
    fault[:, 30] = 1
    slip[:, 30] = 50.0
    offset[:, 29] = 0.5                          # the pair (29, 30)
    return fault, slip, offset, np.ones((h, w), bool)


def test_bands_split_the_labels(lv):
    fault, slip, offset, _ = _section()
    parts = lv["label_offsets_by_slip"](fault, offset, slip, 1.0, 2)
    assert set(parts) == set(lv["slip_band_keys"]())
    vis, off = parts["10-20"]
    assert vis.size == 30 and vis.all() and np.all(off == 1.5)
    vis, off = parts["40-80"]
    assert vis.size == 30 and not vis.any() and np.all(off == 0.5)
    assert all(parts[k][0].size == 0 for k in ("below", "20-40", "80-160", "160-inf"))


def test_bands_agree_with_label_visible(lv):
    """Pooled over the bands, the share on a visible offset is the per-sample measure's."""
    fault, slip, offset, rock = _section()
    offset[5:12, 10] = 0.2                       # part of the first label loses its offset
    for tol in (0, 2):
        whole = lv["sample_measures"](fault, offset, rock, 1.0, tol)["label_visible"]
        pooled = lv["pooled_by_slip"]([lv["label_offsets_by_slip"](fault, offset, slip, 1.0,
                                                                    tol)])
        n = sum(b["pixels"] for b in pooled.values())
        vis = sum(b["visible"] * b["pixels"] for b in pooled.values() if b["pixels"])
        assert n == int(fault.sum())
        assert vis / n == pytest.approx(whole, abs=1e-4)   # the bands are rounded to 4 places
    # within 2 px the rows beside the weakened stretch still see the 1.5-sample offset
    band = lv["pooled_by_slip"]([lv["label_offsets_by_slip"](fault, offset, slip, 1.0, 2)])
    assert band["10-20"]["visible"] == pytest.approx((30 - 3) / 30)
    assert band["40-80"] == {"pixels": 30, "visible": 0.0, "median_offset": 0.5}
    assert band["below"] == {"pixels": 0, "visible": None, "median_offset": None}
