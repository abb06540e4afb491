"""Reflectivity, convolution and the depth -> time -> depth path against bruges and theory."""

import numpy as np
import pytest

from demseis.errors import InputError
from demseis.seismic import (convolve, depth_to_time, interface_times, reflectivity, ricker,
                             synthetic_sections, time_axis)
from demseis.seismic.wavelet import ricker_half_width_s


def _layered(nz, nx, rng, vmin=2000.0, vmax=4500.0):
    """Blocky layered Vp/rho grids with lateral scatter."""
    edges = np.sort(rng.choice(np.arange(1, nz), size=nz // 6, replace=False))
    vp_l = rng.uniform(vmin, vmax, edges.size + 1)
    rho_l = 310.0 * vp_l ** 0.25
    lay = np.searchsorted(edges, np.arange(nz), side="right")
    vp = vp_l[lay][:, None] * (1 + 0.02 * rng.standard_normal((nz, nx)))
    rho = rho_l[lay][:, None] * (1 + 0.01 * rng.standard_normal((nz, nx)))
    return vp, rho


# ---------------------------------------------------------------- reflectivity


@pytest.mark.parametrize("axis", [0, 1, -1])
def test_reflectivity_matches_bruges(bruges, axis):
    rng = np.random.default_rng(1)
    z = rng.uniform(4e6, 1.2e7, (40, 30))
    ours = reflectivity(z, axis=axis)
    ref = bruges.reflection.acoustic_reflectivity(z, axis=axis)
    assert ours.shape == z.shape
    np.testing.assert_allclose(ours, ref, rtol=1e-12, atol=1e-15)


def test_reflectivity_of_vp_rho_matches_bruges_vp_rho(bruges):
    rng = np.random.default_rng(2)
    vp, rho = _layered(60, 5, rng)
    np.testing.assert_allclose(reflectivity(vp * rho),
                               bruges.reflection.acoustic_reflectivity(vp, rho), atol=1e-15)


def test_reflectivity_is_a_reflection_coefficient():
    z = np.array([1.0, 3.0, 3.0, 1.0])
    np.testing.assert_allclose(reflectivity(z), [0.5, 0.0, -0.5, 0.0])
    with pytest.raises(InputError, match="positive"):
        reflectivity(np.array([1.0, -1.0]))


# ---------------------------------------------------------------- convolution


def test_convolve_matches_bruges_trace_and_bank(bruges):
    rng = np.random.default_rng(3)
    r = rng.uniform(-0.2, 0.2, 500)
    w = ricker(30.0, 0.002, 0.2)
    np.testing.assert_allclose(convolve(r, w), bruges.filters.convolve(r, w), atol=1e-12)
    bank = ricker([20.0, 40.0, 60.0], 0.002, 0.2)
    sec = rng.uniform(-0.2, 0.2, (300, 12))
    ours = convolve(sec, bank, axis=0)
    ref = bruges.filters.convolve(sec, bank, axis=0)
    assert ours.shape == ref.shape == (3, 300, 12)
    np.testing.assert_allclose(ours, ref, atol=1e-12)


@pytest.mark.parametrize("freqs", [[20.0], [20.0, 40.0, 60.0]])
def test_time_domain_render_matches_bruges_convolve_on_same_trace(bruges, freqs):
    """Constant Vp makes every cell one time sample: the rendered time section must be
    bruges' convolution of the same reflectivity trace with bruges' Ricker."""
    rng = np.random.default_rng(4)
    nz, nx, cell, v = 400, 3, 3.0, 3000.0
    dt = 2 * cell / v  # 2 ms per cell
    vp = np.full((nz, nx), v)
    rho = rng.uniform(2000.0, 2600.0, (nz, nx))
    t_s = np.arange(nz) * dt
    ours = synthetic_sections(vp, rho, cell, freqs, domain="time", t_s=t_s)
    rc = bruges.reflection.acoustic_reflectivity(vp, rho)  # rc[i]: interface below cell i
    r_time = np.zeros_like(rc)
    r_time[1:] = rc[:-1]        # that interface is at two-way time (i + 1) dt
    for k, f in enumerate(freqs):
        half = ricker_half_width_s(f)
        w = bruges.filters.ricker(2 * half, dt, f).amplitude
        ref = bruges.filters.convolve(r_time, w, axis=0)
        np.testing.assert_allclose(ours[k], ref, rtol=0, atol=2e-6)
        assert np.max(np.abs(ref)) > 0.05


@pytest.mark.parametrize("f", [20.0, 60.0])
def test_depth_render_converges_to_regular_time_resampling(bruges, f):
    """The depth-domain path equals the classic path (impedance resampled to a fine regular
    time grid, bruges reflectivity and convolution, interpolation back to cell-centre times)
    in the limit dt -> 0, with first-order convergence."""
    rng = np.random.default_rng(5)
    nz, nx, cell = 200, 4, 10.0
    vp, rho = _layered(nz, nx, rng)
    ours = synthetic_sections(vp, rho, cell, [f])[0].astype(np.float64)
    t_bottom, t_centre = interface_times(vp, cell)
    errs = []
    for dt in (2e-4, 1e-4, 5e-5):
        t = np.arange(0, t_bottom[-1].max() + 0.2, dt)
        w = bruges.filters.ricker(2 * ricker_half_width_s(f), dt, f).amplitude
        ref = np.empty_like(ours)
        for j in range(nx):
            idx = np.minimum(np.searchsorted(t_bottom[:, j], t, side="right"), nz - 1)
            z_t = (vp[:, j] * rho[:, j])[idx]
            r_t = bruges.reflection.acoustic_reflectivity(z_t)
            s_t = bruges.filters.convolve(r_t, w)
            # bruges puts an interface at the last sample above it: on average dt/2 early
            ref[:, j] = np.interp(t_centre[:, j] - 0.5 * dt, t, s_t)
        errs.append(np.max(np.abs(ref - ours)) / np.max(np.abs(ours)))
    assert errs[-1] < 2e-2
    assert errs[0] > errs[1] > errs[2]


def _wedge(cell, v, top_row, max_cells):
    nz = top_row + max_cells + top_row
    nx = max_cells + 1
    vp = np.full((nz, nx), v)
    rho = np.full((nz, nx), 2400.0)
    for j in range(nx):
        rho[top_row:top_row + j, j] = 2100.0   # wedge j cells thick
    return vp, rho


@pytest.mark.parametrize("f", [20.0, 40.0, 60.0])
def test_wedge_tuning_default_cell(f):
    """Peak |amplitude| of a wedge (equal and opposite reflections) on the default 10 m grid is
    at lambda/4 = V/(4f) within one cell. The wedge is rendered by the generator's path; the
    peak of each trace is read on a 0.05 ms time axis (domain="time"), because cell-centre
    samples 6.7 ms apart only bracket it (thicknesses n and n + 1 cells then share the same
    sampled maximum exactly, see the next test)."""
    v, cell = 3000.0, 10.0
    vp, rho = _wedge(cell, v, 40, 20)
    t_s = np.arange(0.0, 0.6, 5e-5)
    sec = synthetic_sections(vp, rho, cell, [f], domain="time", t_s=t_s)[0]
    peak = np.max(np.abs(sec), axis=0)
    thick = np.arange(sec.shape[1]) * cell
    assert abs(thick[np.argmax(peak)] - v / (4 * f)) <= cell
    # the depth-domain section of the same wedge has its largest sample at a thickness
    # adjacent to that one
    depth = synthetic_sections(vp, rho, cell, [f])[0]
    pd = np.max(np.abs(depth), axis=0)
    best = np.flatnonzero(pd >= pd.max() * (1 - 1e-6)) * cell
    assert np.min(np.abs(best - thick[np.argmax(peak)])) <= cell


@pytest.mark.parametrize("f", [20.0, 40.0, 60.0])
def test_wedge_tuning_matches_ricker_theory_fine_cells(f):
    """With 1 m cells the tuning thickness is the Ricker's analytic one: two-way thickness
    0.3898/f (where the wavelet has its trough, Kallweit & Wood 1982), i.e. lambda_d/4 for the
    wavelet's apparent dominant frequency 1.2826 f; within one cell."""
    v, cell = 3000.0, 1.0
    vp, rho = _wedge(cell, v, 120, 60 if f > 20 else 90)
    sec = synthetic_sections(vp, rho, cell, [f])[0]
    peak = np.max(np.abs(sec), axis=0)
    t_trough = np.sqrt(1.5) / (np.pi * f)  # w'(t) = 0 at (pi f t)^2 = 3/2
    h_theory = v * t_trough / 2
    assert abs(np.argmax(peak) * cell - h_theory) <= cell
    assert abs(v / (4 * 1.2826 * f) - h_theory) < 0.01
    # and the tuned amplitude is 1.446 x a single reflection
    r = (2100 - 2400) / (2100 + 2400)
    assert np.max(peak) / abs(r) == pytest.approx(1.446, abs=0.02)


# ---------------------------------------------------------------- time domain


def test_interface_times():
    vp = np.array([[1000.0], [2000.0], [4000.0]])
    tb, tc = interface_times(vp, 10.0)
    np.testing.assert_allclose(tb[:, 0], [0.02, 0.03, 0.035])
    np.testing.assert_allclose(tc[:, 0], [0.01, 0.025, 0.0325])


def test_time_axis_covers_slowest_column():
    t = time_axis(100, 10.0, 1500.0, 0.002)
    assert t[1] - t[0] == pytest.approx(0.002)
    assert t[-1] >= 2 * 100 * 10.0 / 1500.0 > t[-2]
    with pytest.raises(InputError, match="dt_s"):
        time_axis(100, 10.0, 1500.0, 0.0)


def test_depth_to_time_nearest_matches_slow_reference():
    rng = np.random.default_rng(6)
    nz, nx, cell = 30, 5, 10.0
    vp = rng.uniform(1800, 5000, (nz, nx))
    labels = rng.integers(0, 9, (nz, nx)).astype(np.int16)
    t = time_axis(nz, cell, 1800.0, 0.001)
    out = depth_to_time(labels, vp, cell, t, "nearest", fill=-1)
    assert out.dtype == np.int16 and out.shape == (t.size, nx)
    for j in range(nx):
        top = 0.0
        ref = np.full(t.size, -1)
        for i in range(nz):
            bottom = top + 2 * cell / vp[i, j]
            ref[(t >= top) & (t < bottom)] = labels[i, j]
            top = bottom
        np.testing.assert_array_equal(out[:, j], ref)


def test_depth_to_time_linear_is_exact_for_linear_field():
    vp = np.full((20, 2), 2000.0)
    field = np.arange(20.0)[:, None] * np.ones((1, 2))
    t = np.linspace(0.011, 0.19, 50)  # within [first centre, last centre], 10 ms per cell
    out = depth_to_time(field, vp, 10.0, t, "linear")
    np.testing.assert_allclose(out[:, 0], t / 0.01 - 0.5, atol=1e-12)


def test_time_section_agrees_with_depth_section_at_centre_times():
    rng = np.random.default_rng(7)
    vp, rho = _layered(80, 6, rng)
    depth = synthetic_sections(vp, rho, 10.0, [30.0, 50.0])
    _, tc = interface_times(vp, 10.0)
    for j in range(6):
        tj = synthetic_sections(vp, rho, 10.0, [30.0, 50.0], "time", t_s=tc[:, j])
        np.testing.assert_allclose(tj[:, :, j], depth[:, :, j], atol=1e-7)


def test_synthetic_sections_shapes_and_errors():
    vp = np.full((50, 8), 3000.0)
    rho = np.full((50, 8), 2300.0)
    rho[25:] = 2500.0
    out = synthetic_sections(vp, rho, 10.0, 40.0)
    assert out.shape == (1, 50, 8) and out.dtype == np.float32
    # one interface at the bottom of row 24: peak between rows 24 and 25, symmetric
    np.testing.assert_allclose(out[0, 24], out[0, 25], rtol=1e-6)
    r = (2500.0 - 2300.0) / (2500.0 + 2300.0)
    a = (np.pi * 40.0 * (10.0 / 3000.0)) ** 2   # half a cell of two-way time from the interface
    assert out[0, 24, 0] == pytest.approx(r * (1 - 2 * a) * np.exp(-a), rel=1e-5)
    with pytest.raises(InputError, match="t_s"):
        synthetic_sections(vp, rho, 10.0, [40.0], domain="time")
    with pytest.raises(InputError, match="domain"):
        synthetic_sections(vp, rho, 10.0, [40.0], domain="freq")
    with pytest.raises(InputError, match="vp_g"):
        synthetic_sections(-vp, rho, 10.0, [40.0])
    with pytest.raises(InputError, match="freq_hz"):
        synthetic_sections(vp, rho, 10.0, [0.0])
