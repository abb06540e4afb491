"""Interpreter-style fault picks: one smooth one-pixel line per fault, where the throw shows."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import ndimage

from demseis.errors import InputError
from demseis.labels import PickConfig, loop_count, pick_faults, rung_fraction, throw_samples
from demseis.labels._kernels import thin_path
from demseis.labels.picks import draw_path, fault_polylines


def _maps(shape):
    return {"fault": np.zeros(shape, np.uint8), "fault_id": np.zeros(shape, np.int16),
            "slip_m": np.zeros(shape, np.float32), "dip_deg": np.zeros(shape, np.float32),
            "sense": np.zeros(shape, np.uint8), "damage": np.zeros(shape, np.uint8)}


def _put(maps, rows, cols, fid, slip, dip=60.0, sense=1):
    maps["fault"][rows, cols] = 1
    maps["fault_id"][rows, cols] = fid
    maps["slip_m"][rows, cols] = slip
    maps["dip_deg"][rows, cols] = dip
    maps["sense"][rows, cols] = sense


def _line(r0, r1, c_at):
    rows = np.arange(r0, r1)
    return rows, np.rint(c_at(rows)).astype(int)


def _per_row(mask):
    return np.bincount(np.nonzero(mask)[0], minlength=mask.shape[0])


def test_two_strands_of_one_fault_become_one_line_near_the_strand_that_slips_most():
    m = _maps((120, 80))
    rows, cols = _line(10, 110, lambda r: 30 + 0.1 * (r - 10))
    _put(m, rows, cols, 1, 40.0)                    # the main strand
    _put(m, rows[20:70], cols[20:70] + 4, 1, 5.0)   # a minor strand beside it
    out = pick_faults(m, np.full((120, 80), 5.0))
    f = out["fault"].astype(bool)
    assert _per_row(f).max() == 1                   # one pixel per row: one line
    assert loop_count(f) == 0 and rung_fraction(f) == 0.0
    rr, cc = np.nonzero(f)
    true = 30 + 0.1 * (rr - 10)
    assert np.abs(cc - true).max() <= 1.0           # pulled at most a pixel towards the strand
    assert set(np.unique(out["fault_id"][f])) == {1}
    np.testing.assert_allclose(out["dip_deg"][f], 60.0)
    assert (out["sense"][f] == 1).all()
    assert out["slip_m"][f].max() <= 40.0 and out["slip_m"][f].min() >= 5.0
    np.testing.assert_array_equal(out["damage"], m["damage"])   # other maps untouched


def test_drawn_only_where_the_throw_reaches_min_throw_samples():
    m = _maps((100, 40))
    rows, cols = _line(0, 100, lambda r: 20 + 0 * r)
    _put(m, rows, cols, 1, 10.0)
    throw = np.zeros((100, 40))
    throw[:, 20] = np.where(rows < 60, 2.0, 0.5)   # visible above row 60 only
    out = pick_faults(m, throw, PickConfig(min_throw_samples=1.0))
    r = np.nonzero(out["fault"])[0]
    assert r.min() == 0 and r.max() == 59
    assert not pick_faults(m, throw, PickConfig(min_throw_samples=3.0))["fault"].any()
    # a piece shorter than min_length_px is dropped
    assert not pick_faults(m, throw, PickConfig(min_length_px=61))["fault"].any()


def test_gaps_are_bridged_up_to_max_gap_px_and_split_beyond():
    m = _maps((100, 40))
    rows, cols = _line(0, 100, lambda r: 20 + 0 * r)
    keep = (rows < 40) | (rows >= 45)
    _put(m, rows[keep], cols[keep], 1, 10.0)
    thr = np.full((100, 40), 3.0)
    bridged = pick_faults(m, thr, PickConfig(max_gap_px=5))["fault"]
    assert bridged[:, 20].sum() == 100
    split = pick_faults(m, thr, PickConfig(max_gap_px=4))["fault"]
    assert split[40:45, 20].sum() == 0 and split[:, 20].sum() == 95


def test_crossing_faults_keep_their_ids_and_the_first_keeps_the_crossing():
    m = _maps((100, 100))
    r1, c1 = _line(0, 100, lambda r: 20 + 0.6 * r)
    r2, c2 = _line(0, 100, lambda r: 80 - 0.6 * r)
    _put(m, r2, c2, 2, 10.0, sense=2)
    _put(m, r1, c1, 1, 30.0)
    out = pick_faults(m, np.full((100, 100), 5.0))
    assert set(np.unique(out["fault_id"])) == {0, 1, 2}
    assert (out["sense"][out["fault_id"] == 2] == 2).all()
    assert (out["sense"][out["fault_id"] == 1] == 1).all()
    for k in (1, 2):
        one = out["fault_id"] == k
        assert ndimage.label(one, np.ones((3, 3)))[1] <= 2   # cut once at most by the crossing


def test_a_dropped_fault_frees_its_id():
    m = _maps((60, 60))
    r, c = _line(0, 60, lambda r: 10 + 0 * r)
    _put(m, r, c, 1, 1.0)                            # invisible
    r, c = _line(0, 60, lambda r: 40 + 0 * r)
    _put(m, r, c, 2, 50.0)
    thr = throw_samples(m["slip_m"], m["dip_deg"], cell_m=10.0)
    out = pick_faults(m, thr)
    assert set(np.unique(out["fault_id"])) == {0, 1}
    assert out["fault"][:, 40].all() and not out["fault"][:, 10].any()


def test_throw_samples_in_depth_and_time():
    slip, dip = np.array([20.0]), np.array([30.0])
    np.testing.assert_allclose(throw_samples(slip, dip, cell_m=5.0), [2.0])   # 10 m / 5 m
    # 10 m of throw at 2500 m/s: 8 ms of two-way time, 2 samples of 4 ms
    np.testing.assert_allclose(throw_samples(slip, dip, vp_m_s=np.array([2500.0]), dt_s=0.004),
                               [2.0])
    assert throw_samples(slip, dip, vp_m_s=np.array([0.0]), dt_s=0.004)[0] == 0.0   # no rock
    with pytest.raises(InputError, match="cell_m"):
        throw_samples(slip, dip)


def _thin_reference(rows, cols):
    """thin_path written plainly: a list as the stack of kept indices."""
    kept = []
    for i, (r, c) in enumerate(zip(rows.tolist(), cols.tolist())):
        if kept and (rows[kept[-1]], cols[kept[-1]]) == (r, c):
            continue
        while len(kept) >= 2 and max(abs(r - rows[kept[-2]]), abs(c - cols[kept[-2]])) <= 1:
            kept.pop()
        if kept and (rows[kept[-1]], cols[kept[-1]]) == (r, c):
            continue
        kept.append(i)
    out = np.zeros(len(rows), bool)
    out[kept] = True
    return out


def test_thin_path_leaves_a_one_pixel_path_from_start_to_end():
    rng = np.random.default_rng(3)
    for _ in range(300):
        steps = rng.integers(-1, 2, size=(rng.integers(2, 60), 2))
        steps[rng.random(len(steps)) < 0.2] = 0        # repeated pixels
        pos = np.cumsum(steps, axis=0)
        rows, cols = pos[:, 0].astype(np.int64), pos[:, 1].astype(np.int64)
        keep = thin_path(rows, cols)
        np.testing.assert_array_equal(keep, _thin_reference(rows, cols))
        r, c = rows[keep], cols[keep]
        assert keep[0] and (r[-1], c[-1]) == (rows[-1], cols[-1])
        assert (np.abs(np.diff(r)) <= 1).all() and (np.abs(np.diff(c)) <= 1).all()
        assert ((np.diff(r) != 0) | (np.diff(c) != 0)).all()
        if r.size > 2:                                  # no L corners left
            assert ((np.abs(r[2:] - r[:-2]) > 1) | (np.abs(c[2:] - c[:-2]) > 1)).all()
    # an L step loses its corner; a straight run keeps every pixel
    keep = thin_path(np.array([0, 0, 1, 2]), np.array([0, 1, 1, 1]))
    np.testing.assert_array_equal(keep, [True, False, True, True])
    assert thin_path(np.arange(5), np.zeros(5, np.int64)).all()


def test_draw_path_is_a_connected_line_through_its_points():
    pts = np.array([[0.0, 0.0, 0], [10.0, 3.0, 1], [20.0, 3.0, 2], [24.0, 12.0, 3]])
    r, c, k = draw_path(pts, (30, 30))
    assert (r[0], c[0]) == (0, 0) and (r[-1], c[-1]) == (24, 12)
    assert (np.maximum(np.abs(np.diff(r)), np.abs(np.diff(c))) == 1).all()
    assert set(k.tolist()) == {0, 1, 2, 3}


def test_fault_polylines_follow_a_shallow_line_too():
    # a 20 degree line in pixel space: parameterised along its own axis, not by rows
    c = np.arange(0, 80)
    r = np.rint(10 + np.tan(np.radians(20)) * c).astype(int)
    lines, _ = fault_polylines(r, c, np.ones(c.size), np.full(c.size, 3.0), PickConfig())
    assert len(lines) == 1
    pts = lines[0]
    np.testing.assert_allclose(pts[:, 0], 10 + np.tan(np.radians(20)) * pts[:, 1], atol=0.6)
