"""Survey sampling: traces, labels at the traces, the strata points of a trace."""

from __future__ import annotations

import numpy as np
import pytest

from demseis.generator.config.layout import on_grid, sample_shape, trace_spacing, trace_x
from demseis.generator.config.settings import parse_config
from demseis.generator.render.survey import (damage_factor, fill_gaps, fine_depths,
                                             hold_small_steps, labels_at_traces, level_surface,
                                             reference_points, smooth_velocity, substeps,
                                             surface_window, velocity_window)
from demseis.seismic import coarse_velocity, interface_times


def _cfg(**output):
    return parse_config({"model": {"width_m": 1000.0, "height_m": 400.0},
                         "sweep": {"throw_m": 100.0, "n_layers": 8}, "output": output})


def test_traces_default_to_the_grid_columns():
    cfg = _cfg()
    assert on_grid(cfg) and trace_spacing(cfg) == 10.0
    np.testing.assert_allclose(trace_x(cfg), (np.arange(100) + 0.5) * 10.0)
    maps = {"fault": np.zeros((40, 100), np.uint8), "damage": np.zeros((40, 100), np.uint8)}
    assert labels_at_traces(cfg, maps)["fault"] is maps["fault"]


def test_trace_spacing_sets_the_sample_width():
    cfg = _cfg(trace_spacing_m=25.0)
    assert not on_grid(cfg)
    assert trace_x(cfg).size == 40 and sample_shape(cfg) == (40, 40)
    np.testing.assert_allclose(trace_x(cfg)[:2], [12.5, 37.5])


def test_a_one_cell_fault_line_stays_connected_at_any_spacing():
    """A 60-degree line one cell wide on the grid: every row keeps exactly one fault trace
    at 25 m spacing, and its other label arrays come from the same cell."""
    cfg = _cfg(trace_spacing_m=25.0)
    nz, nx = 40, 100
    fault = np.zeros((nz, nx), np.uint8)
    fid = np.zeros((nz, nx), np.int16)
    slip = np.zeros((nz, nx), np.float32)
    for i in range(nz):
        j = 20 + int(round(i / np.tan(np.radians(60.0))))
        fault[i, j] = 1
        fid[i, j] = 3
        slip[i, j] = 7.0 + i
    damage = np.where(fault > 0, 2, 0).astype(np.uint8)
    out = labels_at_traces(cfg, {"fault": fault, "damage": damage, "fault_id": fid,
                                 "slip_m": slip})
    assert out["fault"].shape == (nz, 40)
    assert (out["fault"].sum(axis=1) == 1).all()
    cols = np.argmax(out["fault"], axis=1)
    assert np.abs(np.diff(cols)).max() <= 1                # connected, one trace per row
    assert (out["fault_id"][out["fault"] > 0] == 3).all()
    np.testing.assert_array_equal(out["slip_m"][np.arange(nz), cols], 7.0 + np.arange(nz))


def test_substeps_are_odd_and_cell_centres_are_strata_points():
    cfg = _cfg(strata_dz_m=1.0)
    n = substeps(cfg)
    assert n == 11 and n % 2 == 1 and 10.0 / n <= 1.0
    z = fine_depths(cfg, 40)
    assert z.size == 440
    np.testing.assert_allclose(z[n // 2::n], (np.arange(40) + 0.5) * 10.0)
    assert substeps(_cfg(strata_dz_m=0.5)) == 21


def test_coarse_velocity_keeps_the_two_way_time_of_every_cell_bottom():
    rng = np.random.default_rng(0)
    n = 11
    vp = rng.uniform(2000, 4000, (40 * n, 3))
    coarse = coarse_velocity(vp, n)
    fine_t, _ = interface_times(vp, 10.0 / n)
    coarse_t, _ = interface_times(coarse, 10.0)
    np.testing.assert_allclose(coarse_t, fine_t[n - 1::n], rtol=1e-12)


def test_fill_gaps_takes_one_value_above_the_rock_and_the_nearest_rock_below():
    v = np.array([[np.nan, 1.0], [2.0, np.nan], [np.nan, np.nan], [np.nan, 3.0],
                  [5.0, np.nan]])
    out = fill_gaps(v)
    # above the rock: the median of the columns' first rock values (2 and 1)
    np.testing.assert_array_equal(out[:, 0], [1.5, 2.0, 2.0, 5.0, 5.0])
    np.testing.assert_array_equal(out[:, 1], [1.0, 1.0, 3.0, 3.0, 3.0])
    allnan = fill_gaps(np.array([[np.nan, 4.0], [np.nan, 4.0]]))
    np.testing.assert_array_equal(allnan[:, 0], [4.0, 4.0])


def test_damage_factor():
    np.testing.assert_allclose(damage_factor(np.array([0, 1, 2]), -0.2), [1.0, 0.9, 0.8])


def test_reference_points_interpolate_smooth_maps_and_keep_jumps():
    """A map with a 30 m jump at depth 50.2 m: evaluated every third row and interpolated,
    it equals the map evaluated everywhere, except the rows between the two evaluated rows
    that bracket the jump, which take the nearer side's map."""
    def ref(x, d):
        y = 1000.0 - d + 0.01 * x + np.where(d > 50.2, 30.0, 0.0)
        return x + 0.1 * d, y, np.where(d > 80.0, 2, -1)

    x = np.array([0.0, 25.0])
    z = (np.arange(100) + 0.5) * 1.0
    x0, y0, unit = reference_points(ref, x, z, step=3)
    X, D = np.meshgrid(x, z)
    want = ref(X, D)
    exact = np.ones(100, bool)
    exact[49:51] = False        # rows 48 and 51 are evaluated: the jump lies between
    exact[79:81] = False        # rows 78 and 81: the unit changes between
    np.testing.assert_allclose(x0[exact], want[0][exact], atol=1e-9)
    np.testing.assert_allclose(y0[exact], want[1][exact], atol=1e-9)
    # between: the nearer evaluated row's map, moved by the depth: one side or the other
    for r in (49, 50):
        assert min(abs(y0[r, 0] - want[1][r, 0]), abs(y0[r, 0] - want[1][r, 0] + 30.0)) < 0.2
    np.testing.assert_array_equal(unit[np.abs(z - 80.0) > 3.0], want[2][np.abs(z - 80.0) > 3.0])


def test_hold_small_steps_drops_drifts_below_the_tolerance_only():
    rng = np.random.default_rng(1)
    beds = np.repeat(rng.uniform(2000.0, 4000.0, 20), 10)          # 20 beds of 10 points
    drift = 1.0 + 2e-5 * np.arange(beds.size)                       # a slow drift in each
    vp = np.stack([beds * drift, beds], axis=1)
    rho = 310.0 * vp ** 0.25
    held_vp, held_rho = vp.copy(), rho.copy()
    hold_small_steps(held_vp, held_rho, 1e-4)
    assert np.abs(held_vp / vp - 1).max() <= 1e-4 and np.abs(held_rho / rho - 1).max() <= 1e-4
    # 199 changes before; after: the 19 bed boundaries and one drift step per 10-point bed
    # (the drift reaches 1e-4 after 5 points)
    assert np.count_nonzero(np.diff(vp[:, 0])) == 199
    assert np.count_nonzero(np.diff(held_vp[:, 0])) <= 40
    np.testing.assert_array_equal(held_vp[:, 1], vp[:, 1])          # no drift: unchanged


def test_rock_time_window_is_the_height_at_the_fastest_vp_and_every_column_fills_it(tmp_path):
    import demseis
    from demseis.errors import ConfigError
    from demseis.generator.config.layout import time_axis_of

    whole = _cfg(domain="time", dt_s=0.004)
    rock = _cfg(domain="time", dt_s=0.004, time_window="rock")
    t_whole, t_rock = time_axis_of(whole), time_axis_of(rock)
    # 400 m at the fastest Vp: 5500 m/s * (1 + 3 * 0.03) * (1 + 0.05 * 0.4) = 6115 m/s
    assert t_rock.size == int(np.floor(2 * 400.0 / (5500 * 1.09 * 1.02) / 0.004))
    assert t_rock.size < t_whole.size
    np.testing.assert_allclose(t_rock, t_whole[: t_rock.size])
    raw = {"model": {"width_m": 1000.0, "height_m": 400.0, "engine": "kinematic",
                     "n_snapshots": 2},
           "sweep": {"throw_m": 100.0, "n_layers": 8, "n_runs": 2, "snr_db": "inf"},
           "output": {"domain": "time", "dt_s": 0.004, "time_window": "rock"}}
    store = demseis.generate(raw, out=tmp_path / "r.zarr", workers=0, progress=False)
    for i in range(len(store.params["run_id"])):
        s = store.sample(i)
        assert s["seismic"].shape[0] == t_rock.size
        assert (s["layer"] >= 0).all()                 # rock down to the last sample
    from demseis.plotting import _deformation, plot_sample

    assert plot_sample(tmp_path / "r.zarr", 1, tmp_path / "s.png").stat().st_size > 10_000
    assert _deformation({"n_basement_faults": 0, "base_stretch": 0.029}) == \
        "base stretched by 2.9 %"
    assert _deformation({"n_basement_faults": 1, "dip_deg": 60.0, "throw_m": 50.0,
                         "base_stretch": -0.1}) == \
        "dip 60°, throw so far 50 m, base shortened by 10.0 %"
    with pytest.raises(ConfigError, match="time_window"):
        _cfg(domain="time", time_window="survey")


def _running_median(v: np.ndarray, window: int) -> np.ndarray:
    """The slow, obvious running median along each row, edges repeated."""
    h = window // 2
    pad = np.concatenate([np.repeat(v[:, :1], h, axis=1), v, np.repeat(v[:, -1:], h, axis=1)],
                         axis=1)
    return np.stack([np.median(pad[:, j:j + window], axis=1) for j in range(v.shape[1])],
                    axis=1)


def test_velocity_window_is_an_odd_count_of_traces():
    assert velocity_window(_cfg()) == 1                                    # 0: off
    assert velocity_window(_cfg(trace_spacing_m=25.0, velocity_median_m=200.0)) == 9
    assert velocity_window(_cfg(trace_spacing_m=25.0, velocity_median_m=225.0)) == 9
    assert velocity_window(_cfg(velocity_median_m=100.0)) == 11           # 10 m grid columns
    assert velocity_window(_cfg(trace_spacing_m=25.0, velocity_median_m=5.0)) == 1


def test_smoothed_velocity_is_a_running_median_that_keeps_the_impedance():
    rng = np.random.default_rng(3)
    vp = rng.uniform(1800.0, 3000.0, (60, 23))
    rho = rng.uniform(2000.0, 2500.0, (60, 23))
    v, r = smooth_velocity(vp, rho, 5)
    np.testing.assert_array_equal(v, _running_median(vp, 5))
    np.testing.assert_allclose(v * r, vp * rho, rtol=1e-15)
    same_v, same_r = smooth_velocity(vp, rho, 1)
    assert same_v is vp and same_r is rho


def test_a_narrow_slow_column_shifts_no_trace_and_a_wide_block_does():
    """Flat beds (1 m rows); trace 10 holds a 60 m column of slow fill at the top (a pit
    between elements), traces 20-39 are 10 % slower throughout (a wide block). Without the
    median, trace 10's times below the pit are late by 2 * 60 m * (1/1800 - 1/v); with it they
    equal its neighbours'. The wide block keeps its own times away from its edge."""
    nz, nx = 300, 40
    beds = 2000.0 + 400.0 * ((np.arange(nz) // 7) % 3)
    vp = np.repeat(beds[:, None], nx, axis=1)
    vp[:, 20:] *= 0.9
    slow = vp.copy()
    slow[:60, 10] = 1800.0
    rho = np.full_like(vp, 2200.0)
    t_raw = interface_times(slow, 1.0)[0]
    late = 2.0 * np.sum(1.0 / 1800.0 - 1.0 / vp[:60, 10])
    assert t_raw[-1, 10] - t_raw[-1, 9] == pytest.approx(late, rel=1e-9)
    assert late > 0.008                                        # two samples at 4 ms
    v, r = smooth_velocity(slow, rho, 5)
    t = interface_times(v, 1.0)[0]
    np.testing.assert_allclose(t[:, 8:13], np.repeat(t[:, 9:10], 5, axis=1), rtol=1e-12)
    t_block = interface_times(vp, 1.0)[0]
    np.testing.assert_allclose(t[:, 24:], t_block[:, 24:], rtol=1e-12)
    np.testing.assert_allclose(t[:, :8], t_block[:, :8], rtol=1e-12)
    np.testing.assert_allclose(v * r, slow * rho, rtol=1e-15)   # the reflections are the rock's


def test_surface_window_follows_its_own_width():
    assert surface_window(_cfg()) == 1
    assert surface_window(_cfg(trace_spacing_m=25.0, surface_median_m=200.0)) == 9


def test_levelled_surface_drops_bumps_fills_pits_and_keeps_a_scarp():
    """Rock from row 10 on the left half and row 30 on the right (a scarp), one trace with a
    bump of 4 rows and one with a pit of 5 rows: the bump becomes no rock, the pit takes its
    trace's first rock values, the scarp stays where it is."""
    nr, nc = 60, 24
    first = np.where(np.arange(nc) < 12, 10, 30)
    first[5] = 6                                               # a bump
    first[18] = 35                                             # a pit
    rows = np.arange(nr)[:, None]
    rock = rows >= first[None, :]
    vp = np.where(rock, 2000.0 + rows, np.nan)
    rho = np.where(rock, 2200.0 + rows, np.nan)
    level_surface(vp, rho, rock, 5)
    top = np.argmax(np.isfinite(vp), axis=0)
    want = np.where(np.arange(nc) < 12, 10, 30)
    np.testing.assert_array_equal(top, want)
    np.testing.assert_array_equal(vp[30:35, 18], 2035.0)       # the pit: the first rock's
    np.testing.assert_array_equal(rho[30:35, 18], 2235.0)
    np.testing.assert_array_equal(vp[10:, 5], 2000.0 + np.arange(10, nr))   # rock kept below
    untouched = np.ones(nc, bool)
    untouched[[5, 18]] = False
    np.testing.assert_array_equal(np.isfinite(vp[:, untouched]), rock[:, untouched])
    before = vp.copy()
    level_surface(vp, rho, np.isfinite(vp), 1)                 # window 1: nothing changes
    np.testing.assert_array_equal(vp, before)
