"""element_strain: analytic homogeneous deformations, kernel vs slow NumPy reference, flags."""

from __future__ import annotations

import numpy as np
import pytest

from demseis.errors import InputError
from demseis.labels import element_strain, neighbour_lists
from demseis_dev.toys import fault_signed_distance, kinematic_fault


def gamma_simple_shear(g: float) -> float:
    """gamma_max of simple shear F = [[1, g], [0, 1]]: C has trace 2 + g^2, det 1."""
    lam_sum, lam_prod = 2.0 + g * g, 1.0
    diff = np.sqrt(lam_sum**2 - 4 * lam_prod)
    return diff / (2.0 * np.sqrt(lam_prod))


def gamma_from_svd(f: np.ndarray) -> float:
    """Independent route: principal stretches s1 >= s2 are the singular values of F."""
    s = np.linalg.svd(f, compute_uv=False)
    return (s[0] ** 2 - s[1] ** 2) / (2 * s[0] * s[1])


def apply(f: np.ndarray, xy: np.ndarray, shift=(0.0, 0.0)) -> np.ndarray:
    return xy @ np.asarray(f).T + np.asarray(shift)


CASES = [
    ("simple shear 0.1", np.array([[1.0, 0.1], [0.0, 1.0]]), gamma_simple_shear(0.1)),
    ("simple shear 1.0", np.array([[1.0, 1.0], [0.0, 1.0]]), gamma_simple_shear(1.0)),
    ("pure shear k=1.25", np.diag([1.25, 1 / 1.25]), (1.25**2 - 1.25**-2) / 2),
    ("pure shear k=0.8 with dilation", np.diag([0.8 * 1.1, 1.1 / 0.8]), (0.8**-2 - 0.8**2) / 2),
    ("rotation 30 deg", np.array([[np.cos(0.5236), -np.sin(0.5236)],
                                  [np.sin(0.5236), np.cos(0.5236)]]), 0.0),
]


@pytest.mark.parametrize("method", ["radius", "knn"])
@pytest.mark.parametrize("name,f,expected", CASES, ids=[c[0] for c in CASES])
def test_homogeneous_deformation_matches_analytic(pack_small, method, name, f, expected):
    xy, r = pack_small
    res = element_strain(xy, apply(f, xy, shift=(123.0, -45.0)), r, method=method)
    assert res.valid.mean() > 0.97
    g = res.gamma_max[res.valid]
    assert np.isclose(expected, gamma_from_svd(f), rtol=1e-12, atol=1e-12)
    if expected == 0.0:
        assert np.max(np.abs(g)) < 1e-9
    else:
        assert np.max(np.abs(g / expected - 1.0)) < 0.01
    vol = res.volumetric[res.valid]
    assert np.allclose(vol, np.linalg.det(f) - 1.0, atol=1e-9)
    assert np.allclose(res.deformation_gradient[res.valid], f, atol=1e-9)


def test_simple_shear_gamma_max_is_not_gamma():
    # the paper's gamma_max is gamma * sqrt(1 + gamma^2 / 4), not the engineering shear gamma
    assert gamma_simple_shear(1.0) == pytest.approx(np.sqrt(1.25))
    assert gamma_simple_shear(0.3) == pytest.approx(0.3 * np.sqrt(1 + 0.09 / 4))


def _reference_strain(ref, cur, r, method, factor=1.5, k=10, min_nb=3):
    """Slow, obvious NumPy reference: brute-force neighbours, lstsq F, eigvalsh of C."""
    n = ref.shape[0]
    d = np.sqrt(((ref[:, None, :] - ref[None, :, :]) ** 2).sum(-1))
    gam = np.full(n, np.nan)
    vol = np.full(n, np.nan)
    nbrs = []
    for i in range(n):
        if method == "radius":
            nb = np.nonzero((d[i] <= factor * (r[i] + r)) & (np.arange(n) != i))[0]
        else:
            order = np.lexsort((np.arange(n), d[i]))
            nb = np.sort(order[order != i][:k])
        nbrs.append(set(nb.tolist()))
        if nb.size < min_nb:
            continue
        dX = ref[nb] - ref[i]
        dx = cur[nb] - cur[i]
        ft, *_ = np.linalg.lstsq(dX, dx, rcond=None)  # dx = dX F^T
        f = ft.T
        if np.linalg.det(f) <= 0:
            continue
        lam = np.linalg.eigvalsh(f.T @ f)
        gam[i] = (lam[1] - lam[0]) / (2 * np.sqrt(lam[0] * lam[1]))
        vol[i] = np.linalg.det(f) - 1.0
    return nbrs, gam, vol


@pytest.mark.parametrize("method", ["radius", "knn"])
def test_kernel_matches_slow_numpy_reference(pack_small, method):
    xy, r = pack_small
    rng = np.random.default_rng(5)
    cur = kinematic_fault(xy, x_m=500.0, dip_deg=55.0, slip_m=60.0, zone_width_m=40.0)
    cur = cur + rng.normal(0.0, 2.0, size=cur.shape)  # non-affine noise
    nbrs, gam_ref, vol_ref = _reference_strain(xy, cur, r, method)
    off, idx = neighbour_lists(xy, r, method=method, radius_factor=1.5, k=10)
    got = [set(idx[off[i]:off[i + 1]].tolist()) for i in range(xy.shape[0])]
    assert got == nbrs
    res = element_strain(xy, cur, r, method=method, radius_factor=1.5, k=10)
    ok = np.isfinite(gam_ref)
    assert np.array_equal(ok, res.valid)
    np.testing.assert_allclose(res.gamma_max[ok], gam_ref[ok], rtol=1e-8, atol=1e-12)
    np.testing.assert_allclose(res.volumetric[ok], vol_ref[ok], rtol=1e-8, atol=1e-12)
    assert np.array_equal(res.n_neighbours, [len(s) for s in nbrs])


def test_knn_matches_scikit_learn(pack_small):
    from sklearn.neighbors import NearestNeighbors  # optional dev dependency, heavy to import

    xy, r = pack_small
    off, idx = neighbour_lists(xy, r, method="knn", k=8)
    nn = NearestNeighbors(n_neighbors=9).fit(xy)
    _, ind = nn.kneighbors(xy)
    for i in range(xy.shape[0]):
        assert set(idx[off[i]:off[i + 1]].tolist()) == set(ind[i, 1:].tolist())


def test_shear_zone_interior_is_simple_shear(pack_small):
    # a 200 m wide band of simple shear gamma = slip / width; interior elements see it exactly
    xy, r = pack_small
    cur = kinematic_fault(xy, x_m=600.0, dip_deg=60.0, slip_m=100.0, zone_width_m=200.0)
    res = element_strain(xy, cur, r)
    d = fault_signed_distance(xy, 600.0, 60.0)
    inner = (np.abs(d) < 100.0 - 60.0) & res.valid & (xy[:, 1] > 60) & (xy[:, 1] < 440)
    assert inner.sum() > 20
    np.testing.assert_allclose(res.gamma_max[inner], gamma_simple_shear(0.5), rtol=1e-9)
    outer = (np.abs(d) > 100.0 + 60.0) & res.valid
    assert np.max(res.gamma_max[outer]) < 1e-9


def test_too_few_neighbours_are_flagged():
    xy = np.array([[0.0, 0.0], [30.0, 0.0], [0.0, 30.0], [30.0, 30.0], [15.0, 15.0],
                   [1000.0, 1000.0],                        # isolated
                   [2000.0, 0.0], [2030.0, 0.0], [2060.0, 0.0]])  # collinear trio
    r = np.full(xy.shape[0], 15.0)
    res = element_strain(xy, xy * 1.01, r, min_neighbours=2)
    assert res.n_neighbours[5] == 0 and not res.valid[5] and np.isnan(res.gamma_max[5])
    assert not res.valid[6:].any()
    assert res.valid[:5].all()
    np.testing.assert_allclose(res.volumetric[:5], 1.01**2 - 1)
    assert res["gamma_max"] is res.gamma_max


@pytest.mark.parametrize(
    "ref,cur,r",
    [
        (np.zeros((4, 3)), np.zeros((4, 3)), np.ones(4)),
        (np.zeros((4, 2)), np.zeros((5, 2)), np.ones(4)),
        (np.zeros((4, 2)), np.zeros((4, 2)), np.ones(3)),
        (np.zeros((4, 2)), np.full((4, 2), np.nan), np.ones(4)),
        (np.zeros((4, 2)), np.zeros((4, 2)), np.array([1.0, 0.0, 1.0, 1.0])),
    ],
)
def test_bad_input_raises(ref, cur, r):
    with pytest.raises(InputError):
        element_strain(ref, cur, r)


def test_bad_method_raises(pack_small):
    xy, r = pack_small
    with pytest.raises(InputError, match="method"):
        element_strain(xy, xy, r, method="delaunay")


from hypothesis import given, settings  # noqa: E402
from hypothesis import strategies as st  # noqa: E402


@settings(max_examples=25, deadline=None)
@given(angle=st.floats(-np.pi, np.pi), tx=st.floats(-1e4, 1e4), seed=st.integers(0, 2**31 - 1))
def test_objectivity_and_permutation(pack_small, angle, tx, seed):
    """gamma_max is unchanged by a rigid motion of the current state and follows a permutation."""
    xy, r = pack_small
    rng = np.random.default_rng(seed)
    cur = xy + rng.normal(0.0, 5.0, size=xy.shape)
    base = element_strain(xy, cur, r)
    rot = np.array([[np.cos(angle), -np.sin(angle)], [np.sin(angle), np.cos(angle)]])
    moved = element_strain(xy, cur @ rot.T + [tx, -tx], r)
    np.testing.assert_array_equal(moved.valid, base.valid)
    np.testing.assert_allclose(moved.gamma_max[base.valid], base.gamma_max[base.valid],
                               rtol=1e-7, atol=1e-9)
    perm = rng.permutation(xy.shape[0])
    permuted = element_strain(xy[perm], cur[perm], r[perm])
    np.testing.assert_allclose(permuted.gamma_max, base.gamma_max[perm], rtol=1e-9, atol=1e-12)
