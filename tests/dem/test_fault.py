"""build_assembly / simulate at the tiny scale: contract of docs/interfaces.md."""

from __future__ import annotations

import numpy as np
import pytest

from demseis.dem import Material, NormalFault, build_assembly, settle_pack, simulate
from demseis.errors import InputError, SimulationError

from ._helpers import overlaps, pair_overlaps

W, H = 1000.0, 500.0


@pytest.fixture(scope="module")
def pack():
    return settle_pack(W, H, rng=0)


@pytest.fixture(scope="module")
def run(pack):
    asm = build_assembly(W, H, n_layers=5, pack=pack)
    calls = []
    snaps = simulate(asm, NormalFault(x_m=500.0, throw_m=100.0), Material(), n_snapshots=4,
                     rng=np.random.default_rng(1), progress=calls.append)
    return asm, snaps, calls


def test_pack_is_dense_and_inside_box(pack):
    phi = np.pi * np.sum(pack.radius**2) / (W * H)
    assert 0.78 < phi < 0.9
    assert pack.xy[:, 0].min() - pack.radius.min() > -1 and pack.xy[:, 0].max() < W + 1
    assert pack.xy[:, 1].max() <= H and pack.xy[:, 1].min() > 0


def test_layers_by_height(pack):
    asm = build_assembly(W, H, n_layers=5, pack=pack)
    assert set(np.unique(asm.layer)) == set(range(5))
    for k in range(5):
        y = asm.xy[asm.layer == k, 1]
        assert y.min() >= k * 100 - 1e-9 and y.max() < (k + 1) * 100 + 1e-9
    thick = [50.0, 150.0, 300.0]
    asm2 = build_assembly(W, H, n_layers=3, layer_thickness_m=thick, pack=pack)
    assert np.all(asm2.xy[asm2.layer == 0, 1] < 50.0)
    with pytest.raises(InputError, match="layer_thickness_m"):
        build_assembly(W, H, n_layers=3, layer_thickness_m=[1.0, 2.0, 3.0], pack=pack)


def test_snapshots_contract(run):
    asm, snaps, calls = run
    assert len(snaps) == 4
    for k, s in enumerate(snaps):
        assert s.index == k
        assert s.throw_m == pytest.approx(k / 3 * 100.0, abs=1e-6)
        assert s.xy.shape == (s.n, 2) and s.layer.dtype == np.int16
        # original elements keep their ids in order; deposited ones are new
        np.testing.assert_array_equal(s.ids[: asm.n], asm.ids)
        assert len(np.unique(s.ids)) == s.n
        assert not s.deposited[: asm.n].any() and s.deposited[asm.n:].all()
        assert np.all(s.layer[s.deposited] >= asm.n_layers)
    assert snaps[-1].deposited.any()
    assert calls and calls[-1] == pytest.approx(1.0)


def test_hanging_wall_subsides_footwall_stays(run):
    asm, snaps, _ = run
    d = snaps[-1].xy[: asm.n] - snaps[0].xy[: asm.n]
    x0 = snaps[0].xy[: asm.n]
    deep = x0[:, 1] < 100
    fw = deep & (x0[:, 0] < 350)
    hw = deep & (x0[:, 0] > 700)
    assert np.median(np.abs(d[fw, 1])) < 5.0
    assert np.median(d[hw, 1]) == pytest.approx(-100.0, abs=15.0)


def test_deterministic(pack):
    asm = build_assembly(W, H, n_layers=5, pack=pack)
    f = NormalFault(x_m=500.0, throw_m=40.0)
    a = simulate(asm, f, n_snapshots=2, rng=3)
    b = simulate(asm, f, n_snapshots=2, rng=3)
    assert a[-1].xy.tobytes() == b[-1].xy.tobytes()


def test_left_dip_mirrors(pack):
    asm = build_assembly(W, H, n_layers=5, pack=pack)
    s = simulate(asm, NormalFault(x_m=500.0, throw_m=60.0, dip_direction="left"),
                 n_snapshots=2, rng=0)
    d = s[-1].xy[: asm.n] - s[0].xy[: asm.n]
    x0 = s[0].xy[: asm.n]
    deep = x0[:, 1] < 100
    assert np.median(d[deep & (x0[:, 0] < 300), 1]) < -40
    assert abs(np.median(d[deep & (x0[:, 0] > 650), 1])) < 5


def test_bad_input_and_instability(pack):
    asm = build_assembly(W, H, n_layers=5, pack=pack)
    with pytest.raises(InputError, match="dip_deg"):
        simulate(asm, NormalFault(x_m=500.0, dip_deg=95.0))
    with pytest.raises(InputError, match="x_m"):
        simulate(asm, NormalFault(x_m=-5.0))
    with pytest.raises(InputError, match="n_snapshots"):
        simulate(asm, NormalFault(x_m=500.0), n_snapshots=1)
    with pytest.raises(InputError, match="radius_max_m"):
        build_assembly(W, H, radius_min_m=30.0, radius_max_m=20.0)
    # a 100x too stiff contact with the Eq. 5 step of the nominal stiffness blows up
    from demseis.dem import Integrator
    eng = Integrator(asm.xy, asm.radius, Material(kn_n_m=1e12), dt_s=0.01)
    with pytest.raises(SimulationError, match="unstable"):
        eng.run(2000)


@pytest.mark.parametrize("cause", ["nan", "ke", "box"])
def test_instability_names_its_cause(pack, cause):
    from demseis.dem import Integrator
    eng = Integrator(pack.xy, pack.radius, Material())
    eng.box = np.array([-100.0, W + 100.0, -100.0, 3 * H])
    eng.vmax_limit = 100.0
    k = int(np.argmax(pack.xy[:, 1]))  # the top element: free above
    if cause == "nan":
        eng.vel[k] = np.nan
        match = "NaN"
    elif cause == "ke":
        eng.vel[k] = (0.0, 150.0)
        match = "kinetic-energy blow-up"
    else:
        eng.vel[k] = (0.0, 90.0)  # below the speed limit, but it flies out of the top
        eng.box[3] = pack.xy[k, 1] + 50.0
        match = "left the box"
    with pytest.raises(SimulationError, match=match):
        eng.run(500)


def test_relaxed_deposits_add_disks_that_overlap_nothing(pack, run, monkeypatch):
    """simulate(relax_deposits=True): every deposit, as it is added, overlaps neither itself
    nor the assembly; the run still deposits growth layers, and its pre-kinematic elements
    start where the default run's do."""
    from demseis.dem.integrator import Integrator

    added = []
    real = Integrator.add_elements

    def spy(self, xy, r):
        xy, r = np.asarray(xy), np.asarray(r)
        old = float(overlaps(xy, r, self.pos[:self.n], self.radius[:self.n]).max())
        new = pair_overlaps(xy, r)
        added.append((r.size, old, float(new.max()) if new.size else -np.inf))
        return real(self, xy, r)

    monkeypatch.setattr(Integrator, "add_elements", spy)
    asm = build_assembly(W, H, n_layers=5, pack=pack)
    snaps = simulate(asm, NormalFault(x_m=500.0, throw_m=100.0), Material(), n_snapshots=4,
                     rng=np.random.default_rng(1), relax_deposits=True)
    assert added and sum(n for n, _, _ in added) == snaps[-1].deposited.sum()
    assert max(old for _, old, _ in added) <= 0.0
    assert max(new for _, _, new in added) <= 1e-9
    np.testing.assert_array_equal(snaps[0].xy, run[1][0].xy)
