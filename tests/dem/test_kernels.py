"""Each DEM kernel against a slow, obvious NumPy reference on a small random assembly."""

from __future__ import annotations

import numpy as np
import pytest

from demseis.dem import _kernels as K


def _random_assembly(n=60, seed=1):
    rng = np.random.default_rng(seed)
    r = rng.uniform(12.5, 25.0, n)
    # jittered grid with spacing slightly below 2*mean radius -> many overlaps and gaps
    side = int(np.ceil(np.sqrt(n)))
    g = np.stack(np.meshgrid(np.arange(side), np.arange(side)), -1).reshape(-1, 2)[:n]
    pos = g * 36.0 + rng.uniform(-4, 4, (n, 2))
    vel = rng.normal(0, 1.0, (n, 2))
    return pos, vel, r, rng


def _build(pos, r, skin, cap=16):
    n = len(r)
    nbr = np.zeros((n, cap), np.int32)
    nn = np.zeros(n, np.int32)
    sh = np.zeros((n, cap))
    bo = np.zeros((n, cap), np.uint8)
    st = K.build_neighbours(pos, r, skin, nbr, nn, sh, bo, np.zeros_like(nbr), np.zeros_like(nn),
                            np.zeros_like(sh), np.zeros_like(bo), np.zeros(4 * n + 64, np.int64),
                            np.zeros(n, np.int64))
    assert st == 0
    return nbr, nn, sh, bo


def test_neighbour_list_matches_brute_force():
    pos, _, r, _ = _random_assembly()
    skin = 4.0
    nbr, nn, _, _ = _build(pos, r, skin)
    got = {(i, int(nbr[i, k])) for i in range(len(r)) for k in range(nn[i])}
    want = set()
    for i in range(len(r)):
        for j in range(i + 1, len(r)):
            if np.hypot(*(pos[j] - pos[i])) < r[i] + r[j] + skin:
                want.add((i, j))
    assert got == want
    assert len(want) > 50


def test_neighbour_rebuild_carries_history_and_reports_overflow():
    pos, _, r, _ = _random_assembly()
    nbr, nn, sh, bo = _build(pos, r, 4.0)
    sh[:] = np.arange(sh.size).reshape(sh.shape) * 1e-3
    bo[:] = 1
    old = {(i, int(nbr[i, k])): (sh[i, k], bo[i, k]) for i in range(len(r)) for k in range(nn[i])}
    pos2 = pos + 0.5
    n = len(r)
    st = K.build_neighbours(pos2, r, 4.0, nbr, nn, sh, bo, np.zeros_like(nbr), np.zeros_like(nn),
                            np.zeros_like(sh), np.zeros_like(bo), np.zeros(4 * n + 64, np.int64),
                            np.zeros(n, np.int64))
    assert st == 0
    for i in range(n):
        for k in range(nn[i]):
            assert old[(i, int(nbr[i, k]))] == (sh[i, k], bo[i, k])
    small = np.zeros((n, 1), np.int32)
    st = K.build_neighbours(pos, r, 4.0, small, np.zeros(n, np.int32), np.zeros((n, 1)),
                            np.zeros((n, 1), np.uint8), np.zeros_like(small),
                            np.zeros(n, np.int32), np.zeros((n, 1)), np.zeros((n, 1), np.uint8),
                            np.zeros(4 * n + 64, np.int64), np.zeros(n, np.int64))
    assert st == 1


def _pair_forces_ref(pos, vel, r, pairs, shear, bond, cmat, ks_ratio, c0_heal, dt):
    """Slow reference of the force law documented in demseis.dem._kernels."""
    f = np.zeros_like(pos)
    shear = dict(shear)
    bond = dict(bond)
    for (i, j) in pairs:
        kn, mu, c0, r0 = np.minimum(cmat[i], cmat[j])
        ks = ks_ratio * kn
        d_vec = pos[j] - pos[i]
        d = np.linalg.norm(d_vec)
        R = r[i] + r[j]
        if bond[(i, j)] and d - R > r0 * R:
            bond[(i, j)] = 0
        if not bond[(i, j)] and d >= R:
            shear[(i, j)] = 0.0
            bond[(i, j)] = 0
            continue
        n = d_vec / d
        t = np.array([-n[1], n[0]])
        fn = kn * (R - d)
        xs = shear[(i, j)] + np.dot(vel[j] - vel[i], t) * dt
        cohesion = c0 if bond[(i, j)] else c0_heal * c0
        if bond[(i, j)] == 2 and abs(ks * xs) > cohesion + mu * max(fn, 0.0):
            bond[(i, j)] = 0  # a brittle bond that slips breaks
            cohesion = c0_heal * c0
        cap = cohesion + mu * max(fn, 0.0)
        fs = float(np.clip(-ks * xs, -cap, cap))
        if abs(-ks * xs) > cap:
            xs = -fs / ks
        shear[(i, j)] = xs
        fj = fn * n + fs * t
        f[j] += fj
        f[i] -= fj
    return f, shear, bond


@pytest.mark.parametrize("c0,flag,heal,layered", [(0.0, 1, 1.0, False), (2e7, 1, 1.0, False),
                                                  (2e7, 2, 0.0, False), (2e7, 1, 1.0, True),
                                                  (2e7, 2, 0.3, True)])
def test_pair_forces_match_reference(c0, flag, heal, layered):
    pos, vel, r, rng = _random_assembly()
    nbr, nn, sh, bo = _build(pos, r, 4.0)
    n = len(r)
    pairs = [(i, int(nbr[i, k])) for i in range(n) for k in range(nn[i])]
    for i in range(n):
        for k in range(nn[i]):
            sh[i, k] = rng.normal(0, 0.05)
            bo[i, k] = flag if rng.random() < 0.5 else 0
    shear0 = {(i, int(nbr[i, k])): sh[i, k] for i in range(n) for k in range(nn[i])}
    bond0 = {(i, int(nbr[i, k])): int(bo[i, k]) for i in range(n) for k in range(nn[i])}
    cmat = np.tile([1e10, 0.4, c0, 0.02], (n, 1))
    if layered:  # two materials, strong and weak, in random elements
        weak = rng.random(n) < 0.5
        cmat[weak] = [3e9, 0.2, 0.2 * c0, 0.005]
    ks_ratio, dt = 0.5, 0.003
    f = np.zeros((n, 2))
    # uniform mechanics go in as one row, layered ones as one row per element
    K.pair_forces(pos, vel, r, nbr, nn, sh, bo, cmat if layered else cmat[:1], ks_ratio, heal,
                  dt, f)
    f_ref, sh_ref, bo_ref = _pair_forces_ref(pos, vel, r, pairs, shear0, bond0, cmat, ks_ratio,
                                             heal, dt)
    np.testing.assert_allclose(f, f_ref, rtol=1e-9, atol=1e-9 * np.abs(f_ref).max())
    for i in range(n):
        for k in range(nn[i]):
            key = (i, int(nbr[i, k]))
            assert sh[i, k] == pytest.approx(sh_ref[key], rel=1e-10, abs=1e-15)
            assert bo[i, k] == bo_ref[key]
    # the sample must exercise contacts, slip, bonds in tension and breaks (or lost cohesion)
    assert np.abs(f).max() > 1e8
    assert sum(bond0.values()) > sum(bo_ref.values()) > 0


@pytest.mark.parametrize("c0,flag,heal", [(2e7, 1, 1.0), (2e7, 2, 0.0)])
def test_uniform_pair_forces_equal_tiled_to_the_bit(c0, flag, heal):
    """One cmat row runs a loop compiled with the material constant: same bits as the row
    given to every element (the per-pair min of two equal values is that value)."""
    pos, vel, r, rng = _random_assembly(seed=3)
    nbr, nn, sh, bo = _build(pos, r, 4.0)
    n = len(r)
    for i in range(n):
        for k in range(nn[i]):
            sh[i, k] = rng.normal(0, 0.05)
            bo[i, k] = flag if rng.random() < 0.5 else 0
    row = np.array([[1e10, 0.4, c0, 0.02]])
    out = []
    for cmat in (row, np.tile(row, (n, 1))):
        f, s, b = np.zeros((n, 2)), sh.copy(), bo.copy()
        nb = K.pair_forces(pos, vel, r, nbr, nn, s, b, cmat, 0.5, heal, 0.003, f)
        out.append((f, s, b, nb))
    (f1, s1, b1, n1), (f2, s2, b2, n2) = out
    assert f1.tobytes() == f2.tobytes() and s1.tobytes() == s2.tobytes()
    assert np.array_equal(b1, b2) and n1 == n2 > 0
    assert not np.array_equal(b1, bo)  # bonds broke: the sample exercises the bond branch


def _walls_case():
    """A random assembly with three walls (vertical, sloping, short) and random wall velocities."""
    pos, vel, r, rng = _random_assembly()
    walls = np.array([[pos[:, 0].min() + 5, -100.0, pos[:, 0].min() + 5, 1000.0],
                      [-100.0, pos[:, 1].min() + 3, 1000.0, pos[:, 1].min() + 10],
                      [100.0, 100.0, 160.0, 150.0]])
    return pos, vel, r, rng, len(r), walls, rng.normal(0, 1, (3, 2))


def test_wall_forces_match_reference():
    pos, vel, r, rng, n, walls, wv = _walls_case()
    wsh = rng.normal(0, 0.05, (n, 3))
    wsh0 = wsh.copy()
    kn, ks, mu, dt = 1e10, 5e9, 0.5, 0.003
    f = np.zeros((n, 2))
    K.wall_forces(pos, vel, r, walls, wv, wsh, kn, ks, mu, dt, f)
    f_ref = np.zeros((n, 2))
    hits = 0
    for w in range(3):
        a, b = walls[w, :2], walls[w, 2:]
        for i in range(n):
            s = np.clip(np.dot(pos[i] - a, b - a) / np.dot(b - a, b - a), 0, 1)
            dv = pos[i] - (a + s * (b - a))
            d = np.linalg.norm(dv)
            if d >= r[i]:
                assert wsh[i, w] == 0.0
                continue
            hits += 1
            nrm = dv / d
            t = np.array([-nrm[1], nrm[0]])
            fn = kn * (r[i] - d)
            xs = wsh0[i, w] + np.dot(vel[i] - wv[w], t) * dt
            fs = float(np.clip(-ks * xs, -mu * fn, mu * fn))
            f_ref[i] += fn * nrm + fs * t
            if abs(ks * xs) > mu * fn:
                xs = -fs / ks
            assert wsh[i, w] == pytest.approx(xs, rel=1e-10, abs=1e-15)
    assert hits >= 5
    np.testing.assert_allclose(f, f_ref, rtol=1e-9, atol=1e-9 * np.abs(f_ref).max())


def test_listed_wall_forces_equal_full_scan():
    pos, vel, r, rng, n, walls, wv = _walls_case()
    sh0 = rng.normal(0, 0.05, (n, 3))
    skin = 4.0
    cand = np.zeros((3, n), np.int32)
    ncand = np.zeros(3, np.int32)
    K.build_wall_candidates(pos, r, walls, skin, cand, ncand)
    assert 0 < ncand.sum() < 3 * n
    # elements off the lists must be farther than the skin: give them zero history as the
    # engine guarantees, then both kernels must agree exactly
    for w in range(3):
        off = np.setdiff1d(np.arange(n), cand[w, : ncand[w]])
        sh0[off, w] = 0.0
    f1, f2 = np.zeros((n, 2)), np.zeros((n, 2))
    sh1, sh2 = sh0.copy(), sh0.copy()
    K.wall_forces(pos, vel, r, walls, wv, sh1, 1e10, 5e9, 0.5, 0.003, f1)
    K.wall_forces_listed(pos, vel, r, walls, wv, sh2, 1e10, 5e9, 0.5, 0.003, f2, cand, ncand)
    np.testing.assert_array_equal(f1, f2)
    np.testing.assert_array_equal(sh1, sh2)


def test_body_forces_and_check_state():
    rng = np.random.default_rng(3)
    vel = rng.normal(0, 1, (20, 2))
    mass = rng.uniform(1e6, 5e6, 20)
    eta = np.full(20, 7e6)
    f = np.zeros((20, 2))
    K.body_forces(vel, mass, eta, 9.81, f)
    np.testing.assert_allclose(f, -eta[:, None] * vel - np.c_[np.zeros(20), mass * 9.81])
    pos = rng.uniform(0, 100, (20, 2))
    box = np.array([0.0, 100.0, 0.0, 100.0])
    assert K.check_state(pos, vel, box, 50.0) == (K.STATUS_OK, -1)
    pos[7, 0] = 101.0
    assert K.check_state(pos, vel, box, 50.0) == (K.STATUS_BOX, 7)
    vel[3, 1] = 60.0
    assert K.check_state(pos, vel, box, 50.0) == (K.STATUS_KE, 3)
    pos[1, 1] = np.nan
    assert K.check_state(pos, vel, box, 50.0) == (K.STATUS_NAN, 1)
