"""Rasterisation, nearest-element search and smoothing against slow references."""

import numpy as np
import pytest
import scipy.ndimage as ndi
from hypothesis import given, settings
from hypothesis import strategies as st

from demseis.seismic import rasterise
from demseis.types import Grid
from demseis.seismic import _kernels
from demseis.seismic.properties import (PropertyModel, gaussian_weights, nearest_element_index,
                                        smooth)


def slow_rasterise(xy, radius, values, grid):
    """Loop over every cell and every element."""
    nz, nx = grid.shape
    mean = np.full((nz, nx), np.nan)
    count = np.zeros((nz, nx), dtype=np.int32)
    for i in range(nz):
        yc = grid.top_m - (i + 0.5) * grid.cell_m
        for j in range(nx):
            xc = grid.x0_m + (j + 0.5) * grid.cell_m
            acc = []
            for e in range(len(radius)):
                if (xc - xy[e, 0]) ** 2 + (yc - xy[e, 1]) ** 2 <= radius[e] ** 2:
                    acc.append(values[e])
            if acc:
                mean[i, j] = sum(acc) / len(acc)
                count[i, j] = len(acc)
    return mean, count


def test_rasterise_matches_slow_reference_random_pack():
    rng = np.random.default_rng(0)
    grid = Grid(x0_m=-15.0, top_m=230.0, cell_m=10.0, nz=22, nx=31)
    n = 150
    xy = np.column_stack([rng.uniform(-60, 350, n), rng.uniform(-30, 260, n)])
    radius = rng.uniform(5, 25, n)
    vals = rng.uniform(2000, 4000, n)
    mean, count = rasterise(xy, radius, vals, grid)
    ref_mean, ref_count = slow_rasterise(xy, radius, vals, grid)
    np.testing.assert_array_equal(count, ref_count)
    np.testing.assert_allclose(mean, ref_mean, rtol=1e-12, equal_nan=True)
    assert 0 < np.isnan(mean).sum() < mean.size


@settings(max_examples=60, deadline=None)
@given(st.lists(st.tuples(st.integers(-3, 14), st.integers(-3, 10), st.integers(0, 6),
                          st.floats(1.0, 9.0)), min_size=1, max_size=12),
       st.sampled_from([1.0, 0.1, 0.3]))
def test_rasterise_rim_cases(elems, cell):
    """Centres and radii on multiples of half a cell put cell centres exactly on disk rims."""
    grid = Grid(x0_m=0.0, top_m=8 * cell, cell_m=cell, nz=8, nx=12)
    xy = np.array([[ex * cell / 2 + cell / 2, ey * cell / 2] for ex, ey, _, _ in elems])
    radius = np.array([r * cell / 2 for _, _, r, _ in elems])
    vals = np.array([v for *_, v in elems])
    mean, count = rasterise(xy, radius, vals, grid)
    ref_mean, ref_count = slow_rasterise(xy, radius, vals, grid)
    np.testing.assert_array_equal(count, ref_count)
    np.testing.assert_allclose(mean, ref_mean, rtol=1e-12, equal_nan=True)


def test_rasterise_multi_value_and_far_elements():
    grid = Grid.covering(100.0, 50.0, 10.0)
    xy = np.array([[25.0, 25.0], [1e12, -1e12], [55.0, 25.0]])
    radius = np.array([12.0, 5.0, 12.0])
    vals = np.array([[1.0, 10.0], [99.0, 99.0], [3.0, 30.0]])
    mean, count = rasterise(xy, radius, vals, grid)
    assert mean.shape == (5, 10, 2)
    ref, ref_count = slow_rasterise(xy, radius, vals[:, 1], grid)
    np.testing.assert_array_equal(count, ref_count)
    np.testing.assert_allclose(mean[:, :, 1], ref, equal_nan=True)


def test_nearest_element_matches_brute_force():
    rng = np.random.default_rng(1)
    grid = Grid(x0_m=0.0, top_m=300.0, cell_m=10.0, nz=30, nx=40)
    xy = np.column_stack([rng.uniform(0, 400, 120), rng.uniform(0, 200, 120)])  # none near top
    want = rng.random(grid.shape) < 0.4
    xy[:10] = np.round(xy[:10] / 5.0) * 5.0  # some exact ties
    ii, jj = np.nonzero(want)
    cx = grid.x_centres()[jj]
    cy = grid.y_centres()[ii]
    d2 = (cx[:, None] - xy[None, :, 0]) ** 2 + (cy[:, None] - xy[None, :, 1]) ** 2
    for bucket in (None, 17.0, 3.0, 900.0):
        idx = nearest_element_index(xy, grid, want, bucket_m=bucket)
        np.testing.assert_array_equal(idx[ii, jj], np.argmin(d2, axis=1))
        assert np.all(idx[~want] == -1)


@pytest.mark.parametrize("sigma", [0.5, 0.7, 1.3])
def test_gaussian_kernel_matches_scipy(sigma):
    a = np.random.default_rng(2).random((37, 53))
    out = np.empty_like(a)
    _kernels.correlate_rows_cols(a, gaussian_weights(sigma), out)
    np.testing.assert_allclose(out, ndi.gaussian_filter(a, sigma, mode="nearest"), atol=1e-13)


@pytest.mark.parametrize("size", [3, 5, 7])
def test_median_kernel_matches_scipy(size):
    rng = np.random.default_rng(size)
    for a in (rng.random((29, 41)), np.round(rng.random((29, 41)) * 3), rng.random((1, 5)),
              rng.random((2, 2))):
        out = np.empty_like(a)
        _kernels.median_filter_square(a, size, out)
        np.testing.assert_array_equal(out, ndi.median_filter(a, size, mode="nearest"))


def test_smooth_is_gaussian_then_median():
    a = np.random.default_rng(3).random((40, 60)) * 1000 + 2000
    m = PropertyModel(gaussian_sigma_cells=0.9, median_size_cells=5)
    ref = ndi.median_filter(ndi.gaussian_filter(a, 0.9, mode="nearest"), 5, mode="nearest")
    np.testing.assert_allclose(smooth(a, m), ref, atol=1e-10)
    off = PropertyModel(gaussian_sigma_cells=0.0, median_size_cells=1)
    np.testing.assert_array_equal(smooth(a, off), a)


def test_grid_and_rasterise_reject_bad_input():
    from demseis.errors import InputError

    with pytest.raises(InputError, match="cell_m"):
        Grid.covering(100.0, 100.0, cell_m=0.0)
    with pytest.raises(InputError, match="nz"):
        Grid(x0_m=0.0, top_m=10.0, cell_m=1.0, nz=0, nx=3)
    grid = Grid.covering(100.0, 100.0)
    assert grid.shape == (10, 10)
    with pytest.raises(InputError, match="radius"):
        rasterise(np.zeros((1, 2)), np.array([-1.0]), np.ones(1), grid)
    with pytest.raises(InputError, match="expected xy"):
        rasterise(np.zeros((2, 3)), np.ones(2), np.ones(2), grid)
