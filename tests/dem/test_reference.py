"""Reference coordinates (demseis.dem.reference): exact for rigid and affine motions, a jump
across a slip surface, no element-scale jitter in intact rock, and the same on a DEM run."""

from __future__ import annotations

import numpy as np
import pytest

from demseis.dem import (NormalFault, build_assembly, element_maps, reference_coordinates,
                         reference_map, settle_pack, simulate)
from demseis.errors import InputError
from demseis.labels import displacement_history
from demseis_dev.toys import disk_pack, down_dip_vector, fault_signed_distance, kinematic_fault

R_MIN, R_MAX = 5.0, 25.0


@pytest.fixture(scope="module")
def pack():
    return disk_pack(1000.0, 600.0, np.random.default_rng(0), radius_min_m=R_MIN,
                     radius_max_m=R_MAX)


def _grid_points(x0, x1, y0, y1, step):
    xs, ys = np.arange(x0, x1, step), np.arange(y0, y1, step)
    return np.column_stack([np.repeat(xs, ys.size), np.tile(ys, xs.size)])


def _smooth_rms(x, y, deg=8):
    """RMS deviation of y(x) from a least-squares polynomial of degree ``deg``."""
    c = np.polynomial.Polynomial.fit(x, y, deg)
    return float(np.sqrt(np.mean((y - c(x)) ** 2)))


def test_rigid_motion_is_recovered_exactly(pack):
    xy, r = pack
    th = np.radians(7.0)
    rot = np.array([[np.cos(th), -np.sin(th)], [np.sin(th), np.cos(th)]])
    shift = np.array([123.4, -56.7])
    cur = xy @ rot.T + shift
    maps = element_maps(xy, cur, r)
    p_ref = _grid_points(0.0, 1000.0, 0.0, 600.0, 3.7)
    got = reference_coordinates(cur, r, maps, p_ref @ rot.T + shift)
    inside = np.isfinite(got[:, 0])
    assert inside.mean() > 0.95
    assert np.abs(got[inside] - p_ref[inside]).max() < 1e-9


def test_affine_strain_is_recovered_exactly(pack):
    xy, r = pack
    f = np.array([[1.02, 0.03], [0.01, 0.99]])    # 2 % stretch, shear
    cur = xy @ f.T + np.array([5.0, -3.0])
    maps, info = element_maps(xy, cur, r, return_info=True)
    assert (info.kind == 2).mean() > 0.99
    p_ref = _grid_points(20.0, 980.0, 20.0, 580.0, 4.1)
    got = reference_coordinates(cur, r, maps, p_ref @ f.T + np.array([5.0, -3.0]))
    inside = np.isfinite(got[:, 0])
    assert inside.mean() > 0.95
    assert np.abs(got[inside] - p_ref[inside]).max() < 1e-9


@pytest.fixture(scope="module")
def faulted(pack):
    xy, r = pack
    slip = 20.0
    cur = kinematic_fault(xy, x_m=500.0, dip_deg=60.0, slip_m=slip)
    maps, info = element_maps(xy, cur, r, return_info=True)
    return xy, cur, r, maps, info, slip * down_dip_vector(60.0)


def test_fault_element_fits_stay_on_their_side(faulted):
    xy, cur, r, maps, info, _ = faulted
    pred = np.einsum("nij,nj->ni", maps[:, :, :2], cur) + maps[:, :, 2]
    # a neighbour from across the fault in a fit would bias it by a fraction of the 20 m slip
    assert np.abs(pred - xy).max() < 1e-9
    assert (info.kind == 2).mean() > 0.95


def test_fault_jumps_by_the_slip(faulted):
    xy, cur, r, maps, info, slip_vec = faulted
    pts = _grid_points(0.0, 1000.0, 0.0, 600.0, 2.3)
    got = reference_coordinates(cur, r, maps, pts)
    inside = np.isfinite(got[:, 0])
    d = fault_signed_distance(pts, 500.0, 60.0)   # the plane is the same in both states
    truth_hw = pts - slip_vec
    err_fw = np.linalg.norm(got - pts, axis=1)
    err_hw = np.linalg.norm(got - truth_hw, axis=1)
    # every point maps exactly onto one of the two blocks (no mixing of their maps) ...
    assert np.all(np.minimum(err_fw, err_hw)[inside] < 1e-9)
    # ... and onto its own block beyond a band of one element diameter
    far = inside & (np.abs(d) > 2 * R_MAX)
    assert far.sum() > 0.8 * inside.sum()
    assert np.all(np.where(d > 0, err_hw, err_fw)[far] < 1e-9)
    wrong = inside & (np.where(d > 0, err_hw, err_fw) > 1e-9)
    assert np.abs(d[wrong]).max() < R_MAX
    # a vertical line through the fault: reference y jumps by the throw (20 m sin 60)
    y = np.arange(20.0, 580.0, 1.0)
    line = np.column_stack([np.full_like(y, 400.0), y])
    ry = reference_coordinates(cur, r, maps, line)[:, 1]
    assert np.all(np.isfinite(ry))
    jump = np.diff(ry - y)
    big = np.abs(jump) > 1e-6
    assert big.sum() <= 3
    assert jump[big].sum() == pytest.approx(-slip_vec[1], abs=1e-9)
    assert -slip_vec[1] == pytest.approx(20.0 * np.sin(np.radians(60.0)))


def _flexure(xy, amp=10.0, length=2000.0, y0=200.0):
    """Plane sections stay plane: w(x) = amp cos(2 pi x / L), u_x = -(y - y0) w'(x)."""
    k = 2 * np.pi / length
    w = amp * np.cos(k * xy[:, 0])
    dw = -amp * k * np.sin(k * xy[:, 0])
    return xy + np.column_stack([-(xy[:, 1] - y0) * dw, w])


def test_no_jitter_in_intact_rock():
    xy, r = disk_pack(1000.0, 400.0, np.random.default_rng(2), radius_min_m=R_MIN,
                      radius_max_m=R_MAX)
    cur = _flexure(xy) + np.random.default_rng(3).normal(0.0, 1e-3, xy.shape)
    maps = element_maps(xy, cur, r)
    x = np.arange(100.0, 900.0, 1.0)
    for y_line in (200.0, 300.0):
        line = np.column_stack([x, np.full_like(x, y_line)])
        ref, owner = reference_coordinates(cur, r, maps, line, return_element=True)
        assert np.all(owner >= 0)
        rms = _smooth_rms(x, ref[:, 1])
        # the translation of the owner alone: steps at every element boundary
        nearest = line[:, 1] + (xy - cur)[owner, 1]
        rms_nearest = _smooth_rms(x, nearest)
        assert rms < 0.05, (y_line, rms)
        assert rms_nearest > 0.1, (y_line, rms_nearest)
        assert rms_nearest > 5 * rms


def test_deterministic_and_checked(faulted):
    xy, cur, r, maps, _, _ = faulted
    assert element_maps(xy, cur, r).tobytes() == maps.tobytes()
    pts = _grid_points(0.0, 1000.0, 0.0, 600.0, 9.1)
    a = reference_coordinates(cur, r, maps, pts)
    assert reference_coordinates(cur, r, maps, pts).tobytes() == a.tobytes()
    # far outside: NaN, owner -1
    ref, owner = reference_coordinates(cur, r, maps, np.array([[500.0, 2000.0]]),
                                       return_element=True)
    assert np.isnan(ref).all() and owner[0] == -1
    with pytest.raises(InputError, match="ref_xy"):
        element_maps(xy[:, :1], cur, r)
    with pytest.raises(InputError, match="radius"):
        element_maps(xy, cur, r[:-1])
    with pytest.raises(InputError, match="maps"):
        reference_coordinates(cur, r, maps[:-1], pts)
    with pytest.raises(InputError, match="points_xy"):
        reference_coordinates(cur, r, maps, pts[:, 0])
    with pytest.raises(InputError, match="reach"):
        reference_coordinates(cur, r, maps, pts, reach=3.0, support=2.0)
    with pytest.raises(InputError, match="tol_m"):
        element_maps(xy, cur, r, tol_m=-1.0)


@pytest.fixture(scope="module")
def dem_run():
    pack_ = settle_pack(1000.0, 500.0, radius_min_m=8.0, radius_max_m=16.0, rng=0)
    asm = build_assembly(1000.0, 500.0, radius_min_m=8.0, radius_max_m=16.0, n_layers=5,
                         pack=pack_)
    return simulate(asm, NormalFault(x_m=500.0, dip_deg=60.0, throw_m=60.0), n_snapshots=3,
                    rng=2)


def test_dem_run_smooth_away_from_fault_and_offset_across(dem_run):
    snaps = dem_run
    x = np.arange(0.0, 1000.0, 1.0)
    for y in (100.0, 250.0):
        rm = reference_map(snaps, -1, np.column_stack([x, np.full_like(x, y)]))
        ry = rm.ref_xy[:, 1]
        assert np.all(rm.layer[rm.element >= 0] >= 0)
        fw = (x >= 20) & (x <= 330)
        hw = (x >= 700) & (x <= 980)
        assert np.isfinite(ry[fw | hw]).all()
        assert _smooth_rms(x[fw], ry[fw], 4) < 0.3
        assert _smooth_rms(x[hw], ry[hw], 4) < 0.3
        # no steps at element boundaries (the owner's translation alone steps by up to ~1 m)
        disp = displacement_history(snaps)[-1][0]
        nearest = y - disp[rm.element, 1]
        steps = [np.abs(np.diff(ry[s])).max() for s in (fw, hw)]
        steps_nearest = [np.abs(np.diff(nearest[s])).max() for s in (fw, hw)]
        assert max(steps) < 0.15, steps
        assert max(steps_nearest) > 0.3, steps_nearest
        # the hanging wall came down by the throw: its rock came from 60 m higher
        offset = np.median(ry[hw] - y) - np.median(ry[fw] - y)
        assert offset == pytest.approx(snaps[-1].throw_m, rel=0.15)


def test_dem_run_growth_strata_keep_their_deposition_frame(dem_run):
    snaps = dem_run
    s = snaps[-1]
    assert s.deposited.any()
    disp, birth = displacement_history(snaps)[-1]
    pts = s.xy[s.deposited]            # centres of growth elements: owned by themselves
    rm = reference_map(snaps, -1, pts)
    assert rm.deposited.all() and (rm.birth == birth[s.deposited]).all()
    assert np.array_equal(rm.layer, s.layer[s.deposited])
    # their reference is near where they were deposited (not the original pack's frame)
    assert np.abs(rm.ref_xy - (pts - disp[s.deposited])).max() < 0.5 * s.radius.max()
    rm0 = reference_map(snaps, 0, snaps[0].xy)
    assert np.abs(rm0.ref_xy - snaps[0].xy).max() < 1e-9
    assert not rm0.deposited.any() and (rm0.birth == 0).all()
