"""The 2-D PSF imaging: flat reflectors as in 1-D, steep ones removed, FFT = direct convolution."""

import math

import numpy as np
import pytest

from demseis.errors import InputError
from demseis.seismic.forward import synthetic_sections, time_axis
from demseis.seismic.psf import (dip_filter, dip_weight, node_angles_deg, node_weights,
                                 padded_shape, psf_plan, psf_sections)
from demseis.seismic.wavelet import ricker_half_width_s, ricker_value

# ------------------------------------------------------------------ the mask and the nodes


def test_dip_weight_edges_and_taper():
    th, dl = 30.0, 5.0
    phi = np.radians([0.0, 10.0, 25.0, 27.5, 29.999, 30.0, 45.0, 89.0])
    w = dip_weight(phi, th, dl)
    np.testing.assert_allclose(w[:3], 1.0)
    assert w[3] == pytest.approx(0.5)             # the raised cosine's midpoint
    assert 0.0 < w[4] < 1e-6
    np.testing.assert_array_equal(w[5:], 0.0)
    fine = dip_weight(np.radians(np.linspace(0, 90, 901)), th, dl)
    assert np.all(np.diff(fine) <= 0)             # monotone in the dip
    np.testing.assert_array_equal(dip_weight(phi, 90.0), 1.0)
    np.testing.assert_array_equal(dip_weight(phi, 30.0, 0.0), (phi < math.radians(30)) * 1.0)


@pytest.mark.parametrize("k", [1, 2, 5])
def test_node_weights_partition_of_unity(k):
    nodes, w = node_weights(37, k)
    assert nodes.shape == (k,) and w.shape == (k, 37)
    np.testing.assert_allclose(w.sum(axis=0), 1.0, atol=1e-15)
    assert np.all(w >= 0)
    if k > 1:
        np.testing.assert_allclose(w[:, np.round(nodes).astype(int)], np.eye(k), atol=1e-15)


def test_aperture_angle_decreases_with_depth():
    z = np.array([0.0, 500.0, 1000.0, 2000.0])
    a = node_angles_deg(z, 40.0, 1000.0)
    np.testing.assert_allclose(a, [40.0, 40.0, 40.0, math.degrees(math.atan(0.5))])
    np.testing.assert_array_equal(node_angles_deg(z, 40.0, math.inf), 40.0)


# ------------------------------------------------------------------ flat reflectors


def _flat_layers(nz, nx, cell_m, rng):
    """Laterally invariant layered Vp/rho (v increasing with depth on average, layer jumps)."""
    edges = np.sort(rng.choice(np.arange(8, nz - 8), size=10, replace=False))
    lay = np.searchsorted(edges, np.arange(nz), side="right")
    vp_l = np.sort(rng.uniform(2200.0, 4500.0, edges.size + 1))
    rng.shuffle(vp_l[3:7])
    vp = np.repeat(vp_l[lay][:, None], nx, axis=1)
    return vp, 310.0 * vp ** 0.25


@pytest.mark.parametrize("domain", ["depth", "time"])
@pytest.mark.parametrize("aperture_m", [math.inf, 800.0])
def test_flat_reflectors_equal_the_1d_section(domain, aperture_m):
    rng = np.random.default_rng(3)
    nz, nx, cell = 150, 90, 10.0
    vp, rho = _flat_layers(nz, nx, cell, rng)
    t_s = time_axis(nz, cell, 2200.0, 0.002) if domain == "time" else None
    freqs = [20.0, 45.0]
    one_d = synthetic_sections(vp, rho, cell, freqs, domain, t_s=t_s)
    for angle in (10.0, 30.0, 60.0):
        psf = psf_sections(vp, rho, cell, freqs, angle, domain, t_s=t_s, aperture_m=aperture_m)
        assert psf.shape == one_d.shape and psf.dtype == np.float32
        err = np.abs(psf - one_d).max() / np.abs(one_d).max()
        assert err < 0.01                 # the bound; the model makes it float round-off
        assert err < 1e-5


# ------------------------------------------------------------------ steep reflectors


def _plane_interface(nz, nx, cell, dip_deg, v1=2500.0, v2=3500.0):
    """A planar interface through the grid centre, anti-aliased: each cell takes the fraction
    of its area below the plane (8 x 8 sub-samples); constant density. (A raster staircase
    is a different reflector: its flat treads are imaged; see benchmarks/seismic_psf_dip.py.)"""
    z = (np.arange(nz) + 0.5)[:, None] * cell
    x = (np.arange(nx) + 0.5)[None, :] * cell
    tan = math.tan(math.radians(dip_deg))
    sub = (np.arange(8) + 0.5) / 8.0 - 0.5
    frac = np.zeros((nz, nx))
    for dz in sub:
        for dx in sub:
            zi = 0.5 * nz * cell + (x + dx * cell - 0.5 * nx * cell) * tan
            frac += (z + dz * cell > zi) / 64.0
    return v1 + (v2 - v1) * frac, np.full((nz, nx), 2300.0)


def _interior_ratios(vp, rho, cell, freq, angle, domain):
    """(peak, rms) of the PSF section over those of the 1-D section, central half of the rows
    and columns (away from the lateral mirrors and the top and bottom)."""
    nz, nx = vp.shape
    t_s = time_axis(nz, cell, float(vp.min()), 0.002) if domain == "time" else None
    a = synthetic_sections(vp, rho, cell, [freq], domain, t_s=t_s)[0]
    b = psf_sections(vp, rho, cell, [freq], angle, domain, t_s=t_s)[0]
    sl = (slice(a.shape[0] // 4, 3 * a.shape[0] // 4), slice(nx // 4, 3 * nx // 4))
    a, b = a[sl].astype(np.float64), b[sl].astype(np.float64)
    return float(np.abs(b).max() / np.abs(a).max()), float(np.sqrt((b**2).sum() / (a**2).sum()))


@pytest.mark.parametrize("domain, dip_deg", [
    ("depth", 40.0), ("depth", 45.0), ("depth", 50.0), ("depth", 60.0), ("depth", 70.0),
    ("time", 40.0), ("time", 45.0), ("time", 50.0), ("time", 60.0),
])
def test_reflector_steeper_than_the_angle_loses_90_percent(domain, dip_deg):
    vp, rho = _plane_interface(200, 240, 10.0, dip_deg)
    peak, rms = _interior_ratios(vp, rho, 10.0, 30.0, 30.0, domain)
    assert peak <= 0.10 and rms <= 0.10


@pytest.mark.parametrize("domain", ["depth", "time"])
def test_reflector_within_the_angle_is_kept(domain):
    vp, rho = _plane_interface(200, 240, 10.0, 15.0)
    # rms, not peak: the sampled 1-D section's peak wobbles from column to column (the
    # interface's sub-cell position), a steep-wavenumber ripple the PSF smooths out
    assert _interior_ratios(vp, rho, 10.0, 30.0, 30.0, domain)[1] >= 0.98


# ------------------------------------------------------------------ fast == direct convolution


def _mask_full(shape, row_step, col_step, angle, scale, taper):
    """The mask on the full (not half) DFT grid, from the frequencies written out."""
    n, m = shape
    fz = np.where(np.arange(n) <= n // 2, np.arange(n), np.arange(n) - n) / (n * row_step)
    kx = np.where(np.arange(m) <= m // 2, np.arange(m), np.arange(m) - m) / (m * col_step)
    return dip_weight(np.arctan2(np.abs(kx)[None, :], scale * np.abs(fz)[:, None]), angle, taper)


def _kernel(mask):
    """Spatial kernel of a real, even mask by an explicit inverse DFT sum (no FFT)."""
    n, m = mask.shape
    en = np.exp(2j * np.pi * np.outer(np.arange(n), np.arange(n)) / n)
    em = np.exp(2j * np.pi * np.outer(np.arange(m), np.arange(m)) / m)
    return np.real(en @ mask @ em) / (n * m)


def _mirror_pad(a, shape, pad_cols):
    """Columns mirrored (edge sample repeated) on both sides, zero rows below, by index maps."""
    n, m = a.shape
    out = np.zeros(shape)
    for q in range(shape[1]):
        c = q - pad_cols
        while not 0 <= c < m:                  # reflect about -0.5 and m - 0.5
            c = -1 - c if c < 0 else 2 * m - 1 - c
        out[:n, q] = a[:, c]
    return out


def _circular_direct(field, kernel):
    """sum_{i,j} field[i, j] kernel[(n - i) mod N, (m - j) mod M], one shifted kernel per
    non-zero sample."""
    out = np.zeros(field.shape)
    for i, j in zip(*np.nonzero(field)):
        out += field[i, j] * np.roll(np.roll(kernel, i, axis=0), j, axis=1)
    return out


def _direct_reference(field_padded, n_rows, n_cols, plan, wavelet_rows=None):
    """Blended direct convolution: sum_k g_k(row) (h_k ** field), cropped; h_k = a_k, or
    w * a_k (along the rows) when the sampled wavelet ``wavelet_rows`` (circular) is given."""
    shape = field_padded.shape
    _, g = node_weights(n_rows, len(plan.angles_deg))
    out = np.zeros((n_rows, n_cols))
    for k, (ang, sc) in enumerate(zip(plan.angles_deg, plan.kz_scale)):
        h = _kernel(_mask_full(shape, plan.row_step, plan.col_step_m, ang, sc, plan.taper_deg))
        if wavelet_rows is not None:
            h = sum(wavelet_rows[p] * np.roll(h, p, axis=0) for p in np.nonzero(wavelet_rows)[0])
        img = _circular_direct(field_padded, h)
        out += g[k][:, None] * img[:n_rows, plan.pad_cols:plan.pad_cols + n_cols]
    return out


def test_time_psf_equals_direct_convolution_of_the_reflectivity_with_the_psf():
    """Constant Vp and dt = 2 cell / Vp: every interface falls on a time sample, so the PSF
    image is the direct 2-D convolution of the gridded reflectivity with h = w * a."""
    rng = np.random.default_rng(7)
    nz, nx, cell, v, freq = 64, 40, 3.0, 3000.0, 30.0
    dt = 2.0 * cell / v
    rho = np.full((nz, nx), 2300.0)
    rho[24:40] *= 1.0 + 0.2 * rng.random((16, nx))        # reflectors away from top and bottom
    vp = np.full((nz, nx), v)
    t_s = time_axis(nz, cell, v, dt)
    plan = psf_plan(vp, cell, [freq], 40.0, "time", t_s=t_s, aperture_m=60.0, n_windows=3)
    assert len(set(plan.angles_deg)) == 3                   # the angle does vary with depth
    fast = psf_sections(vp, rho, cell, [freq], 40.0, "time", t_s=t_s, aperture_m=60.0,
                        n_windows=3)[0]
    z = rho * vp
    refl = np.zeros((t_s.size, nx))
    refl[1:nz] = (z[1:] - z[:-1]) / (z[1:] + z[:-1])        # interface i at t = (i + 1) dt
    shape = padded_shape(t_s.size, nx, plan.pad_rows, plan.pad_cols)
    lag = np.where(np.arange(shape[0]) <= shape[0] // 2, np.arange(shape[0]),
                   np.arange(shape[0]) - shape[0]) * dt
    w = np.where(np.abs(lag) < ricker_half_width_s(freq), ricker_value(freq, lag), 0.0)
    ref = _direct_reference(_mirror_pad(refl, shape, plan.pad_cols), t_s.size, nx, plan, w)
    assert np.abs(ref).max() > 0.01
    assert np.abs(fast - ref).max() <= 1e-5 * np.abs(ref).max()


def test_depth_dip_filter_equals_direct_convolution_with_its_kernel():
    rng = np.random.default_rng(8)
    nz, nx, cell = 40, 36, 10.0
    vp = np.full((nz, nx), 3000.0)
    plan = psf_plan(vp, cell, [40.0], 35.0, "depth", aperture_m=150.0, n_windows=3)
    section = rng.standard_normal((nz, nx))
    fast = dip_filter(section, plan)
    shape = padded_shape(nz, nx, plan.pad_rows, plan.pad_cols)
    ref = _direct_reference(_mirror_pad(section, shape, plan.pad_cols), nz, nx, plan)
    assert np.abs(fast - ref).max() <= 1e-5 * np.abs(ref).max()
    # a bank of sections is filtered section by section
    bank = dip_filter(np.stack([section, 2 * section]), plan)
    np.testing.assert_allclose(bank[1], 2 * fast, atol=1e-12)


# ------------------------------------------------------------------ options and errors


@pytest.mark.parametrize("kw, msg", [
    ({"max_angle_deg": 0.0}, "max_angle_deg"),
    ({"max_angle_deg": 91.0}, "max_angle_deg"),
    ({"max_angle_deg": float("nan")}, "max_angle_deg"),
    ({"taper_deg": -1.0}, "taper_deg"),
    ({"aperture_m": 0.0}, "aperture_m"),
    ({"n_windows": 0}, "n_windows"),
    ({"domain": "time"}, "t_s"),
    ({"domain": "time", "t_s": np.array([0.0, 0.002, 0.005])}, "regular"),
    ({"domain": "offset"}, "domain"),
])
def test_bad_options_are_input_errors(kw, msg):
    vp = np.full((20, 10), 3000.0)
    with pytest.raises(InputError, match=msg):
        psf_sections(vp, vp * 0 + 2300.0, 10.0, [30.0], **kw)
