"""strain_history: total vs reference, incremental, cumulative, deposited elements, id alignment."""

from __future__ import annotations

import numpy as np
import pytest

from demseis.errors import ConfigError, InputError
from demseis.labels import LabelConfig, element_strain, strain_history
from demseis.types import Snapshot
from demseis_dev.toys import kinematic_fault


def gss(g):
    return g * np.sqrt(1 + g * g / 4)


def shear(g):
    return np.array([[1.0, g], [0.0, 1.0]])


def make_snapshots(xy, r, g_step, n_snap, rng, deposit_at=2):
    """Progressive simple shear x += k*g_step*y; a second pack deposited at snapshot
    ``deposit_at`` (placed above, then sheared with everything). Element order is shuffled
    in every snapshot."""
    n = xy.shape[0]
    ids = np.arange(n, dtype=np.int64)
    top = xy.copy()
    top[:, 1] += xy[:, 1].max() + 40.0
    new_ids = np.arange(n, 2 * n, dtype=np.int64) + 1000
    snaps = []
    for k in range(n_snap):
        f = shear(k * g_step)
        xs = xy @ f.T
        layer = np.zeros(n, np.int16)
        all_ids, all_xy, all_r, dep = ids, xs, r, np.zeros(n, bool)
        if k >= deposit_at:
            # deposited pack: reference = its first appearance, then sheared by (k - t) g_step
            xt0 = top @ shear(deposit_at * g_step).T
            xt = xt0 @ shear((k - deposit_at) * g_step).T
            all_ids = np.concatenate([ids, new_ids])
            all_xy = np.vstack([xs, xt])
            all_r = np.concatenate([r, r])
            layer = np.concatenate([layer, np.ones(n, np.int16)])
            dep = np.concatenate([dep, np.ones(n, bool)])
        perm = rng.permutation(all_ids.shape[0])
        snaps.append(Snapshot(index=k, step=100 * k, throw_m=10.0 * k, ids=all_ids[perm],
                              xy=all_xy[perm], radius=all_r[perm], layer=layer[perm],
                              deposited=dep[perm]))
    return snaps


@pytest.mark.parametrize("measure_cfg", [LabelConfig(), LabelConfig(neighbour_method="knn")])
def test_history_progressive_simple_shear(pack_small, measure_cfg):
    xy, r = pack_small
    g = 0.1
    snaps = make_snapshots(xy, r, g, 5, np.random.default_rng(3))
    hist = strain_history(snaps, measure_cfg)
    assert [h.index for h in hist] == [0, 1, 2, 3, 4]
    for k, (s, h) in enumerate(zip(snaps, hist)):
        assert np.array_equal(h.ids, s.ids)
        orig = s.ids < xy.shape[0]
        ok = h.valid
        # total: shear k*g for originals, (k - 2)*g for the deposited pack
        exp_total = np.where(orig, gss(k * g), gss(max(k - 2, 0) * g))
        assert ok.mean() > 0.97
        np.testing.assert_allclose(h.total[ok], exp_total[ok], rtol=1e-6, atol=1e-9)
        # incremental: a simple shear g each step, 0 for elements new in this snapshot
        new_now = (~orig) & (k == 2)
        exp_inc = np.where(new_now | (k == 0), 0.0, gss(g))
        fin = np.isfinite(h.incremental)
        assert fin.mean() > 0.97
        np.testing.assert_allclose(h.incremental[fin], exp_inc[fin], rtol=1e-6, atol=1e-9)
        # cumulative: sum of increments since the first appearance
        n_inc = np.where(orig, k, max(k - 2, 0))
        exp_cum = n_inc * gss(g)
        good = np.abs(h.cumulative - exp_cum) < 1e-6
        assert good.mean() > 0.9  # an invalid increment adds 0 for the few edge elements
        assert np.all(h.cumulative <= exp_cum + 1e-6)
        assert h.measure("cumulative") is h.cumulative and h.measure("total") is h.total
    # progressive simple shear: the sum of increments is below the total (gss is convex)
    assert 4 * gss(g) < gss(4 * g)


def test_history_rigid_motion_is_zero(pack_small):
    xy, r = pack_small
    snaps = []
    for k in range(3):
        a = 0.2 * k
        rot = np.array([[np.cos(a), -np.sin(a)], [np.sin(a), np.cos(a)]])
        snaps.append(Snapshot(k, k, 0.0, np.arange(xy.shape[0]), xy @ rot.T + 50 * k, r,
                              np.zeros(xy.shape[0], np.int16), np.zeros(xy.shape[0], bool)))
    for h in strain_history(snaps):
        assert np.nanmax(h.total) < 1e-9 and np.nanmax(h.cumulative) < 1e-9


def test_history_errors(pack_small):
    xy, r = pack_small
    with pytest.raises(InputError):
        strain_history([])
    bad = Snapshot(0, 0, 0.0, np.zeros(xy.shape[0], np.int64), xy, r,
                   np.zeros(xy.shape[0], np.int16), np.zeros(xy.shape[0], bool))
    with pytest.raises(InputError, match="unique"):
        strain_history([bad])
    with pytest.raises(InputError):
        strain_history([object()])
    good = Snapshot(0, 0, 0.0, np.arange(xy.shape[0]), xy, r,
                    np.zeros(xy.shape[0], np.int16), np.zeros(xy.shape[0], bool))
    with pytest.raises(ConfigError, match="neighbour_method"):
        strain_history([good], LabelConfig(neighbour_method="voronoi"))


def test_history_with_lost_elements_matches_direct_fit(pack_small):
    """Elements missing from a later snapshot: the rest is fitted against the common set."""
    xy, r = pack_small
    n = xy.shape[0]
    cur1 = kinematic_fault(xy, x_m=500.0, dip_deg=60.0, slip_m=40.0, zone_width_m=80.0)
    cur2 = kinematic_fault(xy, x_m=500.0, dip_deg=60.0, slip_m=90.0, zone_width_m=80.0)
    keep = np.ones(n, bool)
    keep[::9] = False  # lost before snapshot 2
    ids = np.arange(n, dtype=np.int64)
    z16, zb = np.zeros(n, np.int16), np.zeros(n, bool)
    snaps = [Snapshot(0, 0, 0.0, ids, xy, r, z16, zb),
             Snapshot(1, 1, 1.0, ids[::-1], cur1[::-1], r[::-1], z16, zb),
             Snapshot(2, 2, 2.0, ids[keep], cur2[keep], r[keep], z16[keep], zb[keep])]
    hist = strain_history(snaps)
    direct_total = element_strain(xy[keep], cur2[keep], r[keep])
    np.testing.assert_allclose(hist[2].total, direct_total.gamma_max, rtol=1e-10, atol=1e-12)
    inc1 = element_strain(xy, cur1, r)
    inc2 = element_strain(cur1[keep], cur2[keep], r[keep])
    np.testing.assert_allclose(hist[1].incremental, inc1.gamma_max[::-1], rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(hist[2].incremental, inc2.gamma_max, rtol=1e-10, atol=1e-12)
    exp_cum = np.nan_to_num(inc1.gamma_max[keep]) + np.nan_to_num(inc2.gamma_max)
    np.testing.assert_allclose(hist[2].cumulative, exp_cum, rtol=1e-10, atol=1e-12)
