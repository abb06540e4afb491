"""Particle measures against hand-built snapshots with known answers."""

from __future__ import annotations

import numpy as np
import pytest

from demseis.types import Snapshot
from demseis_dev.measure import (displacement_jump, horizon_profile, horizon_step, section_length,
                                 slip_sense)


def snapshot(xy, layer, ids=None):
    n = len(xy)
    return Snapshot(index=0, step=0, throw_m=0.0,
                    ids=np.arange(n, dtype=np.int64) if ids is None else ids,
                    xy=np.asarray(xy, float), radius=np.full(n, 10.0),
                    layer=np.asarray(layer, np.int16), deposited=np.zeros(n, bool))


def horizon(shape, throw=200.0, x_f=1000.0):
    """A layer-3 horizon at y = 500 - shape(x) * throw, sampled every 5 m, with layer-2
    elements below it (which must be ignored)."""
    x = np.arange(0.0, 2000.0, 5.0)
    y = 500.0 - throw * shape(x - x_f)
    xy = np.r_[np.c_[x, y], np.c_[x, y - 60.0]]
    return snapshot(xy, np.r_[np.full(x.size, 3), np.full(x.size, 2)])


def test_step_of_a_discrete_offset_is_the_throw():
    s = horizon(lambda u: (u > 0).astype(float))
    assert horizon_step(s, 3, 1000.0) == pytest.approx(200.0)
    # seen with the hanging wall on the other side it is a rise, not a drop
    assert horizon_step(s, 3, 1000.0, dip_direction="left") == pytest.approx(0.0, abs=1e-9)


@pytest.mark.parametrize("width", [400.0, 1000.0])
def test_step_of_a_monocline_is_throw_times_window_over_width(width):
    s = horizon(lambda u: np.clip(u / width + 0.5, 0.0, 1.0))
    assert horizon_step(s, 3, 1000.0, window_m=100.0) == pytest.approx(200.0 * 100.0 / width,
                                                                      rel=0.02)


def test_profile_is_the_median_per_column():
    s = snapshot([[10, 1.0], [20, 3.0], [30, 2.0], [60, 9.0]], [0, 0, 0, 0])
    np.testing.assert_allclose(horizon_profile(s, 0, np.array([0.0, 50.0, 100.0, 150.0])),
                               [2.0, 9.0, np.nan])


def test_displacement_jump_of_rigid_blocks():
    rng = np.random.default_rng(0)
    p = np.c_[rng.uniform(0, 2000, 4000), rng.uniform(0, 400, 4000)]
    dip, xf = 60.0, 1000.0
    hw = p[:, 0] > xf - p[:, 1] / np.tan(np.radians(dip))
    slip = 50.0
    d = np.where(hw[:, None], slip * np.array([np.cos(np.radians(dip)),
                                               -np.sin(np.radians(dip))]), 0.0)
    s0, s1 = snapshot(p, np.zeros(4000)), snapshot(p + d, np.zeros(4000))
    j = displacement_jump(s0, s1, xf, dip, "right", (0.0, 400.0))
    assert slip_sense(j, dip, "right") == pytest.approx(slip)
    # the same motion read as a reverse fault on a left-dipping plane is negative
    s2 = snapshot(p - d, np.zeros(4000))
    assert slip_sense(displacement_jump(s0, s2, xf, dip, "right", (0.0, 400.0)), dip,
                      "right") == pytest.approx(-slip)


def test_section_length():
    s = snapshot([[5, 1], [700, 2], [300, 900]], [0, 0, 0])
    assert section_length(s, 100.0) == 695.0
    assert section_length(s, 1000.0, n_original=1) == 0.0


def test_fault_crossings_follow_a_dipping_fault():
    # horizons 3 and 5 offset by 150 m across a 60-degree fault through (1000, 0)
    from demseis_dev.measure import fault_crossings

    x = np.arange(0.0, 2000.0, 5.0)
    xy, layer = [], []
    for k, y0 in ((3, 300.0), (5, 600.0)):
        xf = 1000.0 - y0 / np.tan(np.radians(60.0))
        xy.append(np.c_[x, y0 - 150.0 * (x > xf)])
        layer.append(np.full(x.size, k))
    s = snapshot(np.concatenate(xy), np.concatenate(layer))
    xs, ys = fault_crossings(s, [3, 5], 800.0)
    np.testing.assert_allclose(xs, 1000.0 - np.array([300.0, 600.0]) / np.tan(np.radians(60.0)),
                               atol=13.0)
    dip = np.degrees(np.arctan2(ys[1] - ys[0], abs(xs[1] - xs[0])))
    assert dip == pytest.approx(60.0, abs=5.0)


# ---- dip of a fault per unit of layers (refraction), on a kinematic fault whose dip is imposed

def _refracted(dips, zone_m, throw_m=100.0, x_m=3500.0, n_layers=24, unit=2, seed=1):
    from demseis_dev.toys import layered_pack, refracted_fault

    h = 2770.0
    ref = layered_pack(5000.0, h, n_layers, rng=np.random.default_rng(seed))
    edges = np.linspace(0.0, h, n_layers // unit + 1)
    xy = refracted_fault(ref.xy, x_m=x_m, y_edges_m=edges, dips_deg=dips, throw_m=throw_m,
                         zone_width_m=zone_m)
    cur = Snapshot(1, 0, throw_m, ref.ids, xy, ref.radius, ref.layer, ref.deposited)
    units = [tuple(range(k, k + unit)) for k in range(0, n_layers, unit)]
    return ref, cur, units


@pytest.mark.parametrize("zone_m", [60.0, 150.0])
def test_unit_dips_recover_an_imposed_refraction(zone_m):
    from demseis_dev.measure import unit_dips

    dips = np.where(np.arange(12) % 2 == 0, 65.0, 50.0)  # strong units first, from the base
    ref, cur, units = _refracted(dips, zone_m)
    got, x_mid, misfit = unit_dips(ref, cur, units, 3500.0)
    assert np.all(np.isfinite(got)) and np.all(misfit < 0.05)
    strong, weak = got[0::2].mean(), got[1::2].mean()
    assert strong == pytest.approx(65.0, abs=2.0)
    assert weak == pytest.approx(50.0, abs=2.0)
    assert strong - weak == pytest.approx(15.0, abs=2.5)
    assert np.all(np.abs(got - dips) < 6.0)  # each unit on its own (about 7 rows of elements)


def test_unit_dips_of_a_straight_fault_show_no_refraction():
    from demseis_dev.measure import unit_dips

    ref, cur, units = _refracted(np.full(12, 55.0), 60.0)
    got, _, _ = unit_dips(ref, cur, units, 3500.0)
    assert got.mean() == pytest.approx(55.0, abs=1.5)
    assert abs(got[0::2].mean() - got[1::2].mean()) < 2.0


def test_step_line_mirrors_for_a_left_dipping_fault():
    from demseis_dev.measure import step_line

    ref, cur, units = _refracted(np.full(12, 60.0), 60.0)
    sel = np.isin(ref.layer, (10, 11)) & (np.abs(ref.xy[:, 0] - 3000.0) < 400.0)
    dip_r, x_r, _ = step_line(ref.xy[sel], cur.xy[sel] - ref.xy[sel], "right")
    mirror = np.array([-1.0, 1.0])
    dip_l, x_l, _ = step_line(ref.xy[sel] * mirror, (cur.xy[sel] - ref.xy[sel]) * mirror, "left")
    assert dip_r == pytest.approx(60.0, abs=3.0)
    assert dip_l == pytest.approx(dip_r, abs=1e-9) and x_l == pytest.approx(-x_r, abs=1e-6)


def test_step_line_refuses_a_field_without_a_jump():
    from demseis.errors import InputError
    from demseis_dev.measure import step_line

    xy = np.random.default_rng(0).uniform(0, 500, (200, 2))
    with pytest.raises(InputError, match="no displacement jump"):
        step_line(xy, np.zeros_like(xy))
