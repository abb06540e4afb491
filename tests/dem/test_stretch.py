"""A stretching base (``base_stretch``): its wall kinematics against the analytic rubber sheet,
the fault population it grows in brittle cover, shortening, combinations and bad input."""

from __future__ import annotations

import hashlib
import os

import numpy as np
import pytest

from demseis.dem import BasementFault, FaultSystem, Material, build_assembly, simulate
from demseis.dem.basement import block_kinematics, single
from demseis.dem.fault import basement_walls, stretch_shift, wall_ends
from demseis.dem.integrator import time_step
from demseis.errors import ConfigError, InputError

W, H, RMAX = 2500.0, 1100.0, 25.0
NONE = FaultSystem((), structure="none")


def _base(system, stretch_m, slip_m=0.0):
    """(pieces before, pieces after ``stretch_m`` of end shift) of the block tops, by x."""
    motions = block_kinematics(system, W)
    walls, owner, anchor = basement_walls(system, motions, W, H, RMAX, 4 * RMAX)
    base = np.flatnonzero(np.isnan(anchor))
    after = np.array([wall_ends(walls[w], motions[owner[w]], anchor[w], W, slip_m,
                                stretch_m).ravel() for w in base])
    order = np.argsort(walls[base, 0])
    return walls[base][order], after[order], walls, owner, anchor


@pytest.mark.parametrize("stretch", [0.3, 0.1, -0.1, -0.3])
def test_base_velocity_is_linear_in_x(stretch):
    """Every base point moves by e x0 (left end fixed, right end by e W): its velocity is linear
    in its initial and in its present x, v(x) = v_end x / (W + end shift)."""
    end = stretch * W
    before, after, walls, _, anchor = _base(NONE, end)
    x0 = np.clip(before[:, [0, 2]], 0.0, W)
    np.testing.assert_allclose(after[:, [0, 2]] - before[:, [0, 2]], end * x0 / W, atol=1e-9)
    assert np.all(after[:, [1, 3]] == 0.0)                    # the base stays at y = 0
    # velocity over a short step of the end, against the present x: v = v_end x / (W + end)
    frac = 0.5
    mid = np.array([wall_ends(w, block_kinematics(NONE, W)[0], np.nan, W, 0.0, frac * end)
                    for w in before])
    x_now = mid[:, :, 0]
    dv = stretch_shift(np.clip(before[:, [0, 2]], 0, W), W, 1.0)   # per metre of end shift
    inside = (before[:, [0, 2]] >= 0) & (before[:, [0, 2]] <= W)
    np.testing.assert_allclose(dv[inside], (x_now / (W + frac * end))[inside], rtol=1e-12)
    # side walls: the left one fixed, the right one with the base's end
    right = np.flatnonzero(anchor == W)
    assert right.size and np.all(walls[right, 0] == W)
    np.testing.assert_allclose(stretch_shift(anchor[right], W, end), end)
    assert np.all(stretch_shift(anchor[anchor == 0.0], W, end) == 0.0)


@pytest.mark.parametrize("stretch", [0.3, -0.3])
def test_base_pieces_are_short_and_leave_no_gap(stretch):
    """Pieces of at most 4 r_max, end to end from -r_max to W + r_max, still end to end once
    stretched; moving each at its mean velocity for one wall update (50 steps at the quick
    box's dt) opens at most 1% of r_min between neighbours."""
    end = stretch * W
    before, after, *_ = _base(NONE, end)
    lengths = before[:, 2] - before[:, 0]
    assert np.all(lengths <= 4 * RMAX + 1e-9) and np.all(lengths > 0)
    assert before[0, 0] == -RMAX and before[-1, 2] == W + RMAX
    np.testing.assert_array_equal(before[1:, 0], before[:-1, 2])
    np.testing.assert_allclose(after[1:, 0], after[:-1, 2], atol=1e-9)
    np.testing.assert_allclose(after[-1, 2] - after[0, 0], 2 * RMAX + W + end, atol=1e-9)
    v_end, dt, rmin = 5.0, time_step(12.5, 2500.0, 1.0e10), 12.5
    mean_v = v_end * 0.5 * (np.clip(before[:, 0], 0, W) + np.clip(before[:, 2], 0, W)) / W
    span = 50 * dt
    moved = before[:, [0, 2]] + (mean_v * span)[:, None]
    assert np.abs(moved[1:, 0] - moved[:-1, 1]).max() < 0.01 * rmin


def test_stretch_rides_on_the_blocks():
    """With a basement fault, every wall moves with its block plus the base's stretch at its
    anchor: the base stays continuous across the fault (fault face and hanging-wall top move
    with the stretch at the fault)."""
    system = single(1000.0, 60.0, 100.0)
    slip = system.master_slip_m
    end = 0.1 * W
    motions = block_kinematics(system, W)
    walls, owner, anchor = basement_walls(system, motions, W, H, RMAX, 4 * RMAX)
    face = np.flatnonzero(anchor == 1000.0)
    assert face.size == 1
    p = wall_ends(walls[face[0]], motions[owner[face[0]]], anchor[face[0]], W, slip, end)
    q = wall_ends(walls[face[0]], motions[owner[face[0]]], anchor[face[0]], W, slip, 0.0)
    np.testing.assert_allclose(p[:, 0] - q[:, 0], end * 1000.0 / W)


def _brittle_cfg(stretch, structure="none", **sweep):
    from demseis.generator.config.settings import parse_config

    raw = {"name": "s", "sweep": {"n_runs": 1, "structure": structure, "base_stretch": stretch,
                                  "contact_model": "brittle", "bond_strain": 0.005,
                                  "cohesion_n": 2e8, "n_layers": 8, "freq_hz": 30,
                                  "throw_m": 60.0, "dip_deg": 60.0, **sweep},
           "model": {"width_m": 1500.0, "height_m": 500.0, "n_snapshots": 3,
                     "radius_min_m": 12.5, "radius_max_m": 25.0}}
    return parse_config(raw)


def _render(cfg):
    from demseis.generator.config.sampling import plan_run
    from demseis.generator.engines import get_engine
    from demseis.generator.render.section import render_run

    engine = get_engine(cfg.model.engine)
    run = engine.simulate(cfg, plan_run(cfg, 0))
    return run, render_run(cfg, run, engine).params


@pytest.fixture(scope="module")
def stretched():
    return _render(_brittle_cfg(0.1))


def test_brittle_cover_over_a_stretching_base_grows_a_fault_population(stretched):
    """1500 x 500 m, r 12.5-25 m, brittle: base_stretch 0.1 labels >= 3 fault instances at the
    last snapshot (the engine's labels); the same box undeformed (no stretch, a 1 m basement
    throw) labels none."""
    _, p = stretched
    last = p["snapshot"] == p["snapshot"].max()
    assert p["n_faults"][last].max() >= 3
    assert np.all(p["n_basement_faults"] == 0) and np.all(p["fault_x_m"] == -1)
    assert np.all(p["throw_m"] == 0) and np.all(p["fault0_kind"] == -1)
    # the same run with neither stretch nor basement throw (below the config's throw range,
    # so the spec is edited after the config checks)
    import dataclasses

    from demseis.generator.config.sampling import plan_run
    from demseis.generator.engines import get_engine
    from demseis.generator.render.section import render_run

    cfg = _brittle_cfg(0.1)
    spec = plan_run(cfg, 0)
    spec = dataclasses.replace(spec, params={**spec.params, "base_stretch": 0.0,
                                             "structure": "single", "throw_m": 0.0})
    engine = get_engine("dem")
    q = render_run(cfg, engine.simulate(cfg, spec), engine).params
    assert q["n_faults"].max() == 0


def test_total_extension_is_base_stretch_times_width(stretched):
    """The cover is carried out to the right wall, which has moved base_stretch * width."""
    run, _ = stretched
    first, last = run.snapshots[0], run.snapshots[-1]
    right0 = (first.xy[:, 0] + first.radius).max()
    right = (last.xy[:, 0] + last.radius).max()
    assert right - right0 == pytest.approx(0.1 * 1500.0, abs=2.5)
    assert [s.throw_m for s in run.snapshots] == [0.0, 0.0, 0.0]


def test_shortening_pushes_the_right_wall_in():
    run, p = _render(_brittle_cfg(-0.1))
    first, last = run.snapshots[0], run.snapshots[-1]
    shift = (last.xy[:, 0] + last.radius).max() - (first.xy[:, 0] + first.radius).max()
    assert shift == pytest.approx(-0.1 * 1500.0, abs=2.5)
    assert last.xy[:, 1].max() <= 500.0                       # uplift eroded at the top
    assert p["n_faults"].max() >= 1


@pytest.fixture
def engines(monkeypatch) -> list:
    """Every DEM Integrator that ``simulate`` builds during the test, in order (their walls are
    what the basement was at the end of the run)."""
    import demseis.dem.fault as fault_module

    made = []

    class Recording(fault_module.Integrator):
        def __init__(self, *args, **kwargs):
            super().__init__(*args, **kwargs)
            made.append(self)

    monkeypatch.setattr(fault_module, "Integrator", Recording)
    return made


def test_stretch_combines_with_a_basement_fault(engines):
    """A normal fault and a stretching base: at the last snapshot the right wall has moved by
    the fault's heave plus the stretch (and dropped by the throw), the left wall not at all; the
    throw is reached in proportion (half at snapshot 1 of 3)."""
    asm = build_assembly(1000.0, 400.0, radius_min_m=12.5, radius_max_m=25.0, n_layers=4, rng=1)
    f = BasementFault(500.0, 60.0, 60.0)
    snaps = simulate(asm, FaultSystem((f,)), Material(), n_snapshots=3, rng=2, base_stretch=0.1)
    walls = engines[-1].walls
    heave = 60.0 / np.tan(np.radians(60.0))
    np.testing.assert_allclose(walls[-1, [0, 2]], 1000.0 + heave + 100.0, atol=1e-6)
    np.testing.assert_allclose(walls[-1, 1], -60.0, atol=1e-6)
    np.testing.assert_array_equal(walls[0, [0, 2]], 0.0)
    assert snaps[-1].throw_m == pytest.approx(60.0)
    assert snaps[1].throw_m == pytest.approx(30.0)
    right = [float((s.xy[:, 0] + s.radius).max()) for s in snaps]
    assert right[-1] - right[0] > 0.95 * (heave + 100.0)     # the cover follows


@pytest.mark.parametrize("stretch", [0.2, -0.2])
def test_no_gap_opens_in_a_run(engines, stretch):
    """After a whole run with a rotating (listric) hanging wall and a stretching base, the
    block-top pieces the engine holds still meet end to end (within 1% of r_min)."""
    from demseis.dem.basement import half_graben

    asm = build_assembly(1000.0, 400.0, radius_min_m=12.5, radius_max_m=25.0, n_layers=4, rng=1)
    system = half_graben(600.0, 55.0, 60.0, "right", 3000.0)
    simulate(asm, system, Material(), n_snapshots=2, rng=2, base_stretch=stretch)
    motions = block_kinematics(system, 1000.0)
    walls0, owner, anchor = basement_walls(system, motions, 1000.0, 400.0, 25.0, 100.0)
    for b in range(len(motions)):
        mine = np.flatnonzero(np.isnan(anchor) & (owner == b))
        mine = mine[np.argsort(walls0[mine, 0])]
        now = engines[-1].walls[mine]
        gaps = np.hypot(now[1:, 0] - now[:-1, 2], now[1:, 1] - now[:-1, 3])
        assert gaps.max() < 0.01 * 12.5, (b, gaps.max())
    assert engines[-1].walls.shape == walls0.shape


def stretch_digest() -> str:
    """SHA-256 of the snapshots of one small stretched brittle run (fixed seeds)."""
    asm = build_assembly(600.0, 300.0, radius_min_m=10.0, radius_max_m=20.0, n_layers=4, rng=1)
    snaps = simulate(asm, NONE, Material(model="brittle", cohesion_n=6e8), n_snapshots=2,
                     rng=2, base_stretch=0.15)
    return hashlib.sha256(b"".join(s.xy.tobytes() + s.ids.tobytes() for s in snaps)).hexdigest()


def test_same_seed_same_bytes():
    """The same run in this process and in a fresh one (its own hash seed, its own Numba
    state) gives the same bytes; another packing seed gives others."""
    import subprocess
    import sys

    from tests._helpers import ROOT

    here = stretch_digest()
    there = subprocess.run([sys.executable, "-c", "from tests.dem.test_stretch import "
                            "stretch_digest; print(stretch_digest())"], cwd=ROOT, check=True,
                           capture_output=True, text=True, env={**os.environ,
                                                                "PYTHONHASHSEED": "123"})
    assert there.stdout.strip() == here
    asm = build_assembly(600.0, 300.0, radius_min_m=10.0, radius_max_m=20.0, n_layers=4, rng=3)
    other = simulate(asm, NONE, Material(model="brittle", cohesion_n=6e8), n_snapshots=2,
                     rng=2, base_stretch=0.15)
    assert hashlib.sha256(b"".join(s.xy.tobytes() + s.ids.tobytes()
                                   for s in other)).hexdigest() != here


def test_bad_input_is_refused():
    from demseis.generator.config.sampling import RunParams
    from demseis.generator.config.settings import parse_config
    from demseis.generator.engines.runsetup import fault_system_of

    asm = build_assembly(600.0, 300.0, radius_min_m=10.0, radius_max_m=20.0, n_layers=2, rng=1)
    with pytest.raises(InputError, match="base_stretch"):
        simulate(asm, NONE, n_snapshots=2, base_stretch=0.0)
    with pytest.raises(InputError, match="base_stretch"):
        simulate(asm, NONE, n_snapshots=2, base_stretch=0.5)
    with pytest.raises(InputError, match="structure='none'"):
        simulate(asm, FaultSystem((BasementFault(300.0),), structure="none"), n_snapshots=2,
                 base_stretch=0.1)
    with pytest.raises(InputError, match="1-5"):
        simulate(asm, FaultSystem(()), n_snapshots=2, base_stretch=0.1)
    with pytest.raises(ConfigError, match=r"structure.*base_stretch"):
        parse_config({"sweep": {"structure": "none"}})
    with pytest.raises(ConfigError, match=r"structure.*base_stretch"):
        parse_config({"sweep": {"structure": {"dist": "choice", "values": ["single", "none"]},
                                "base_stretch": [0.0, 0.1]}})
    with pytest.raises(ConfigError, match=r"sweep.base_stretch = 0.4"):
        parse_config({"sweep": {"base_stretch": 0.4}})
    cfg = parse_config({"sweep": {"structure": "none", "base_stretch": 0.1}})
    with pytest.raises(ConfigError, match=r"structure.*base_stretch"):
        fault_system_of(cfg, RunParams.of({"structure": "none", "base_stretch": 0.0}), 0)


def test_kinematic_engine_runs_structure_none():
    """The kinematic engine takes a run without basement faults (it draws none of its own)."""
    from demseis.generator.config.settings import parse_config

    cfg = parse_config({"sweep": {"n_runs": 1, "structure": "none", "base_stretch": 0.1,
                                  "n_layers": 8, "freq_hz": 30, "throw_m": 100.0},
                        "model": {"engine": "kinematic", "width_m": 1000.0, "height_m": 400.0,
                                  "n_snapshots": 3}})
    _, p = _render(cfg)
    assert np.all(p["n_basement_faults"] == 0) and np.all(p["throw_m"] == 0)
    assert np.all(p["throw_target_m"] == 0)
