"""Block reference map (demseis.dem.reference.block_reference_map): linear motions exact,
jumps only at the barrier, granular jitter smoothed, and the grid traversal against a dense
sampling of each segment."""

from __future__ import annotations

import numpy as np
import pytest

from demseis.dem._reference_kernels import crosses_barrier
from demseis.dem.reference import block_reference_map, reference_map
from demseis.errors import InputError
from demseis.types import Grid, Snapshot
from demseis_dev.toys import disk_pack, down_dip_vector, fault_signed_distance, kinematic_fault

R_MIN, R_MAX = 8.0, 16.0
W, H = 1200.0, 600.0
GRID = Grid.covering(W, H, 10.0)


@pytest.fixture(scope="module")
def pack():
    return disk_pack(W, H, np.random.default_rng(1), radius_min_m=R_MIN, radius_max_m=R_MAX)


def _snap(cur: np.ndarray, r: np.ndarray) -> Snapshot:
    n = cur.shape[0]
    return Snapshot(index=1, step=0, throw_m=0.0, ids=np.arange(n, dtype=np.int64), xy=cur,
                    radius=r, layer=np.zeros(n, np.int16), deposited=np.zeros(n, bool))


def _map(cur, r, ref, points, barrier=None, smooth=80.0, band=0.0):
    disp = (cur - ref, np.zeros(cur.shape[0], np.int64))
    b = np.zeros(GRID.shape, np.uint8) if barrier is None else barrier
    return block_reference_map([_snap(cur, r)], 0, points, b, GRID, smooth, band_m=band,
                               displacement=disp)


def _points(step=7.3, margin=20.0):
    xs = np.arange(margin, W - margin, step)
    ys = np.arange(margin, H - margin, step)
    return np.column_stack([np.repeat(xs, ys.size), np.tile(ys, xs.size)])


def _fault_barrier(x_m: float, dip_deg: float) -> np.ndarray:
    """Every cell of GRID that a planar fault through (x_m, 0) dipping right passes through
    (its x at elevation y is x_m - y cot(dip), as in demseis_dev.toys)."""
    b = np.zeros(GRID.shape, np.uint8)
    cot = 1.0 / np.tan(np.radians(dip_deg))
    for i in range(GRID.nz):
        y_top, y_bot = GRID.top_m - i * GRID.cell_m, GRID.top_m - (i + 1) * GRID.cell_m
        j0, j1 = (int(np.floor((x_m - y * cot - GRID.x0_m) / GRID.cell_m)) for y in (y_top, y_bot))
        lo, hi = max(min(j0, j1), 0), min(max(j0, j1), GRID.nx - 1)
        b[i, lo:hi + 1] = 1
    return b


def test_an_affine_motion_is_recovered_exactly_everywhere(pack):
    """The moving least-squares fit is linear, so a uniform strain with rotation is exact,
    also near the edges where the neighbourhood is one-sided."""
    xy, r = pack
    f = np.array([[1.01, 0.04], [-0.02, 0.98]])
    cur = xy @ f.T + np.array([30.0, -12.0])
    pts = _points() @ f.T + np.array([30.0, -12.0])
    got = _map(cur, r, xy, pts).ref_xy
    inside = np.isfinite(got[:, 0])
    assert inside.mean() > 0.95
    want = (pts - np.array([30.0, -12.0])) @ np.linalg.inv(f).T
    assert np.abs(got[inside] - want[inside]).max() < 1e-8


def test_a_barrier_keeps_the_slip_and_nothing_else_jumps(pack):
    """A 60-degree fault with 20 m of slip: with its line as the barrier, every point more
    than two cells from the line maps onto its own block exactly; without it, the slip is
    smeared over the smoothing radius."""
    xy, r = pack
    slip = 20.0 * down_dip_vector(60.0)
    cur = kinematic_fault(xy, x_m=500.0, dip_deg=60.0, slip_m=20.0)
    pts = _points(step=5.1)
    d = fault_signed_distance(pts, 500.0, 60.0)
    truth = np.where((d > 0)[:, None], pts - slip, pts)
    got = _map(cur, r, xy, pts, _fault_barrier(500.0, 60.0)).ref_xy
    inside = np.isfinite(got[:, 0])
    # the barrier acts inside its raster only: the hanging wall has slid below y = 0, and a
    # footwall point within the smoothing radius of the bottom reaches it around the raster
    far = inside & (np.abs(d) > 2.5 * GRID.cell_m) & (pts[:, 1] > 80.0)
    assert far.sum() > 0.75 * inside.sum()
    assert np.abs(got[far] - truth[far]).max() < 1e-8
    smeared = _map(cur, r, xy, pts).ref_xy
    near = inside & (np.abs(d) > 2.5 * GRID.cell_m) & (np.abs(d) < 40.0)
    assert np.abs(smeared[near] - truth[near]).max() > 2.0           # a tenth of the slip


def test_a_band_gives_the_whole_slip_of_a_shear_zone_at_the_barrier(pack):
    """20 m of slip spread over a 60 m zone of simple shear: with the zone's centre line as
    the barrier and a 40 m band, a vertical line's reference y jumps once, at the line, by the
    whole throw, and is rigid on either side; without the band the zone's ramp stays."""
    xy, r = pack
    cur = kinematic_fault(xy, x_m=700.0, dip_deg=60.0, slip_m=20.0, zone_width_m=60.0)
    y = np.arange(150.0, 450.0, 1.0)
    x = 700.0 - 300.0 / np.tan(np.radians(60.0))                # the plane at y = 300
    line = np.column_stack([np.full_like(y, x), y])
    barrier = _fault_barrier(700.0, 60.0)
    throw = 20.0 * np.sin(np.radians(60.0))
    sharp = _map(cur, r, xy, line, barrier, smooth=120.0, band=40.0).ref_xy[:, 1] - y
    ramp = _map(cur, r, xy, line, barrier, smooth=120.0).ref_xy[:, 1] - y
    d = fault_signed_distance(line, 700.0, 60.0)
    side = np.abs(d) > 15.0
    hw, fw = side & (d > 0), side & (d < 0)
    np.testing.assert_allclose(sharp[fw], 0.0, atol=1e-6)
    np.testing.assert_allclose(sharp[hw], throw, atol=1e-6)
    assert np.abs(ramp[fw & (np.abs(d) < 25.0)]).max() > 1.0        # the ramp of the zone


def test_granular_jitter_is_smoothed_and_the_element_maps_keep_it(pack):
    """Each element moved by its own random 3 m on top of a smooth flexure (granular
    rearrangement): along a horizontal line the block map's reference y stays within a few
    decimetres of the flexure's, where the element maps cut the line into the elements'
    steps."""
    xy, r = pack
    rng = np.random.default_rng(5)
    bend = 4.0 * np.sin(2 * np.pi * xy[:, 0] / 900.0)
    cur = xy + np.column_stack([np.zeros_like(bend), bend]) + rng.normal(0.0, 3.0, xy.shape)
    x = np.arange(150.0, W - 150.0, 2.0)
    line = np.column_stack([x, np.full_like(x, 300.0)])
    truth = 300.0 - 4.0 * np.sin(2 * np.pi * x / 900.0)
    block = _map(cur, r, xy, line, smooth=100.0).ref_xy[:, 1]
    elem = reference_map([_snap(cur, r)], 0, line,
                         displacement=(cur - xy, np.zeros(xy.shape[0], np.int64))).ref_xy[:, 1]
    rms_block = float(np.sqrt(np.mean((block - truth) ** 2)))
    rms_elem = float(np.sqrt(np.mean((elem - truth) ** 2)))
    assert rms_block < 0.6
    assert rms_elem > 2.0 * rms_block
    assert np.abs(np.diff(block)).max() < 0.2                # no step between 2 m points


def test_owner_layer_and_outside_points_match_the_element_map(pack):
    xy, r = pack
    cur = xy + np.array([3.0, -2.0])
    pts = np.vstack([_points(step=23.0), [[W / 2, H + 200.0]]])
    disp = (cur - xy, np.zeros(xy.shape[0], np.int64))
    a = _map(cur, r, xy, pts)
    b = reference_map([_snap(cur, r)], 0, pts, displacement=disp)
    np.testing.assert_array_equal(a.element, b.element)
    np.testing.assert_array_equal(a.layer, b.layer)
    assert np.isnan(a.ref_xy[-1]).all() and a.element[-1] == -1


def test_bad_barrier_and_smoothing_are_refused(pack):
    xy, r = pack
    snap = _snap(xy, r)
    disp = (np.zeros_like(xy), np.zeros(xy.shape[0], np.int64))
    with pytest.raises(InputError, match="barrier must have the shape"):
        block_reference_map([snap], 0, xy[:3], np.zeros((2, 2)), GRID, 50.0, displacement=disp)
    with pytest.raises(InputError, match="band_m"):
        block_reference_map([snap], 0, xy[:3], np.zeros(GRID.shape), GRID, 50.0, band_m=-1.0,
                            displacement=disp)
    with pytest.raises(InputError, match="smooth_m"):
        block_reference_map([snap], 0, xy[:3], np.zeros(GRID.shape), GRID, 0.0,
                            displacement=disp)


def _crosses_dense(ax, ay, bx, by, barrier, x0, top, cell, n=20000):
    """The slow, obvious check: sample the segment densely and look at every cell visited
    after a's own cell."""
    t = np.linspace(0.0, 1.0, n)
    i = np.floor((top - (ay + t * (by - ay))) / cell).astype(int)
    j = np.floor((ax + t * (bx - ax) - x0) / cell).astype(int)
    start = (i == i[0]) & (j == j[0])
    first_out = np.argmax(~start) if (~start).any() else n
    i, j = i[first_out:], j[first_out:]
    ok = (i >= 0) & (i < barrier.shape[0]) & (j >= 0) & (j < barrier.shape[1])
    return bool(barrier[i[ok], j[ok]].any())


def test_grid_traversal_agrees_with_dense_sampling():
    rng = np.random.default_rng(11)
    barrier = (rng.random((30, 40)) < 0.04).astype(np.uint8)
    x0, top, cell = 5.0, 300.0, 10.0
    agree = 0
    for _ in range(400):
        ax, bx = rng.uniform(0.0, 420.0, 2)
        ay, by = rng.uniform(-10.0, 310.0, 2)
        a = crosses_barrier(ax, ay, bx, by, barrier, x0, top, cell)
        b = _crosses_dense(ax, ay, bx, by, barrier, x0, top, cell)
        agree += a == b
    assert agree == 400
