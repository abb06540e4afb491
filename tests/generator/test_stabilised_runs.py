"""A DEM run that goes unstable is run again stabilised (the basement at half the wall speed per
try, then the same with relaxed deposits), the try that finished is stored as ``dem_attempt``,
and only a run unstable on every try is recorded failed."""

from __future__ import annotations

import numpy as np
import pytest

from demseis.cli import main
from demseis.errors import SimulationError
from demseis.generator.config.settings import load_config, parse_config
from demseis.generator.engines import dem as dem_engine
from demseis.generator.sweep.pipeline import run_shard
from tests._helpers import params_of
from tests.datasets._helpers import drop_param

from ._helpers import generate_tiny

#: the minute model of the Numba warm-up (demseis.generator.sweep.driver.warm_numba_cache)
MINUTE = ('[sweep]\nn_runs = 2\nn_layers = 2\nthrow_m = 20.0\ndip_deg = 60.0\n'
          '[model]\nn_snapshots = 2\nwidth_m = 300.0\nheight_m = 200.0\nwall_speed_m_s = 1.0\n')


def _minute_cfg(**model):
    raw = load_config(preset="tiny").to_dict()
    raw["sweep"].update(n_runs=1, n_layers=2, throw_m=20.0, dip_deg=60.0)
    raw["model"].update({"n_snapshots": 2, "width_m": 300.0, "height_m": 200.0,
                         "wall_speed_m_s": 1.0, **model})
    return parse_config(raw)


def _unstable(monkeypatch, failing_tries: int, relaxed: list[bool] | None = None) -> list[float]:
    """Make the DEM's first ``failing_tries`` tries of every run go unstable (each after it
    drew from the run's generator, as a real try does); returns the wall speed of every try
    (and appends to ``relaxed`` whether each try relaxed its deposits)."""
    real = dem_engine.simulate
    speeds: list[float] = []
    tries = {"n": 0}

    def flaky(asm, fault, *args, **kw):
        speeds.append(fault.speed_m_s)
        if relaxed is not None:
            relaxed.append(kw["relax_deposits"])
        tries["n"] += 1
        if tries["n"] <= failing_tries:
            kw["rng"].random(100)
            raise SimulationError(f"kinetic-energy blow-up at step {100 * tries['n']}")
        tries["n"] = 0
        return real(asm, fault, *args, **kw)

    monkeypatch.setattr(dem_engine, "simulate", flaky)
    return speeds


def _same(a, b) -> None:
    assert a.arrays.keys() == b.arrays.keys() and a.params.keys() == b.params.keys()
    for k in a.arrays:
        assert a.arrays[k].tobytes() == b.arrays[k].tobytes(), k
    for k in a.params:
        assert np.asarray(a.params[k]).tobytes() == np.asarray(b.params[k]).tobytes(), k
    assert len(a.snapshots) == len(b.snapshots)
    for s, t in zip(a.snapshots, b.snapshots):
        assert s.step == t.step and s.xy.tobytes() == t.xy.tobytes()


def _same_as_first_try(data, first, attempt: int) -> None:
    """``data`` (finished on try ``attempt``) has the bytes of ``first``, a run that finished
    on its first try, but for ``dem_attempt``."""
    assert set(first.params["dem_attempt"].tolist()) == {0}
    first.params["dem_attempt"][:] = attempt
    _same(data, first)


def test_a_run_unstable_on_its_first_try_is_the_run_at_half_the_wall_speed(monkeypatch):
    cfg = _minute_cfg()
    speeds = _unstable(monkeypatch, 1)
    data = run_shard(cfg, 0)
    assert speeds == [1.0, 0.5]
    assert set(data.params["dem_attempt"].tolist()) == {1}
    again = run_shard(cfg, 0)                      # same config and seed: same bytes
    _same(data, again)
    # independent of the retry: the configured run at 0.5 m/s, which went stable at once
    monkeypatch.undo()
    _same_as_first_try(data, run_shard(_minute_cfg(wall_speed_m_s=0.5), 0), 1)


def test_a_run_unstable_on_every_try_fails_naming_each_cause(monkeypatch):
    relaxed: list[bool] = []
    speeds = _unstable(monkeypatch, 6, relaxed)
    with pytest.raises(SimulationError) as err:
        run_shard(_minute_cfg(), 0)
    assert speeds == [1.0, 0.5, 0.25, 1.0, 0.5, 0.25]
    assert relaxed == [False, False, False, True, True, True]
    text = str(err.value)
    assert text.startswith("every try went unstable")
    assert "as configured (1 m/s): kinetic-energy blow-up at step 100" in text
    assert "stabilised try 1 (wall speed 0.5 m/s): kinetic-energy blow-up at step 200" in text
    assert "stabilised try 2 (wall speed 0.25 m/s): kinetic-energy blow-up at step 300" in text
    assert ("stabilised try 3 (wall speed 1 m/s, relaxed deposits): kinetic-energy blow-up at "
            "step 400") in text
    assert ("stabilised try 5 (wall speed 0.25 m/s, relaxed deposits): kinetic-energy blow-up "
            "at step 600") in text


def test_a_run_unstable_on_the_slower_tries_finishes_with_relaxed_deposits(monkeypatch):
    """Try 3 is the run as configured with relaxed deposits: same wall speed, and the same
    bytes as a run of the DEM told to relax its deposits at once."""
    cfg = _minute_cfg()
    relaxed: list[bool] = []
    speeds = _unstable(monkeypatch, 3, relaxed)
    data = run_shard(cfg, 0)
    assert speeds == [1.0, 0.5, 0.25, 1.0] and relaxed == [False, False, False, True]
    assert set(data.params["dem_attempt"].tolist()) == {3}
    monkeypatch.undo()
    real = dem_engine.simulate
    monkeypatch.setattr(dem_engine, "simulate",
                        lambda *a, **kw: real(*a, **{**kw, "relax_deposits": True}))
    _same_as_first_try(data, run_shard(cfg, 0), 3)


def test_without_sedimentation_no_relaxed_try(monkeypatch):
    relaxed: list[bool] = []
    speeds = _unstable(monkeypatch, 6, relaxed)
    with pytest.raises(SimulationError, match="stabilised try 2 ") as err:
        run_shard(_minute_cfg(sedimentation=False), 0)
    assert speeds == [1.0, 0.5, 0.25] and relaxed == [False, False, False]
    assert "relaxed" not in str(err.value)


def test_no_stabilised_try_below_the_slowest_declared_wall_speed(monkeypatch):
    speeds = _unstable(monkeypatch, 6)
    with pytest.raises(SimulationError, match=r"\(as configured \(0.0015 m/s\): kinetic-energy "
                       r"blow-up at step 100; no stabilised try 1 \(wall speed 0.00075 m/s\): "
                       r"below the slowest wall speed 0.001 m/s; no stabilised try 2 .*; "
                       r"stabilised try 3 \(wall speed 0.0015 m/s, relaxed deposits\): "
                       r"kinetic-energy blow-up at step 200; no stabilised try 4 .*\)"):
        run_shard(_minute_cfg(wall_speed_m_s=0.0015), 0)
    assert speeds == [0.0015, 0.0015]


def test_sweep_reports_stabilised_runs_and_render_keeps_their_try(tmp_path, monkeypatch, capsys):
    """The sweep names the stabilised runs and exits 0; `demseis render` from their particles
    stores the source's dem_attempt, and a store from before the stabilised tries (no
    dem_attempt) re-renders with 0: its runs all ran as configured."""
    import demseis

    _unstable(monkeypatch, 1)
    src = generate_tiny(tmp_path, MINUTE, "s")
    assert "2 run(s) went unstable and finished on a stabilised try" in capsys.readouterr().out
    assert set(params_of(src)["dem_attempt"].tolist()) == {1}
    assert main(["validate", str(src)]) == 0
    monkeypatch.undo()
    out = tmp_path / "r.zarr"
    assert main(["render", str(src), "--freq", "30", "--out", str(out), "--quiet"]) == 0
    assert set(params_of(out)["dem_attempt"].tolist()) == {1}
    # a store of the previous version: no dem_attempt in its table, nor in its metadata
    drop_param(src, "dem_attempt")
    store = demseis.open(src)                                   # it still opens
    assert "dem_attempt" not in store.params and store.sample(0)["run_id"] == 0
    assert main(["validate", str(src)]) == 0
    old = tmp_path / "o.zarr"
    assert main(["render", str(src), "--freq", "30", "--out", str(old), "--quiet"]) == 0
    assert set(params_of(old)["dem_attempt"].tolist()) == {0}


def _finishes_on_try(preset: str, run: int, attempt: int) -> None:
    """Run ``run`` of ``preset``, simulated as a sweep does, finishes on try ``attempt``."""
    from demseis.generator.config.sampling import plan_run

    raw = load_config(preset=preset).to_dict()
    raw["sweep"]["n_runs"] = run + 2
    cfg = parse_config(raw)
    result = dem_engine.ENGINE.simulate(cfg, plan_run(cfg, run))
    assert result.info.values["dem_attempt"] == attempt
    assert len(result.snapshots) == cfg.model.n_snapshots


@pytest.mark.slow
def test_variety_run_46_is_stabilised_on_its_first_retry():
    """The run of the variety preset that went unstable (a reverse-fault horst whose flanks
    close in at 5 m/s; kinetic-energy blow-up at step 12,264) finishes at 2.5 m/s."""
    _finishes_on_try("variety", 46, 1)


@pytest.mark.slow
def test_seed_run_6_finishes_with_relaxed_deposits():
    """The seed preset's run 6 blows up at a deposited element at the surface (its template's
    overlaps released) at every wall speed tried (steps 42,136, 42,136 and 83,497); with relaxed
    deposits it finishes as configured (try 3)."""
    _finishes_on_try("seed", 6, 3)


def test_stability_benchmark_counts_the_tries(tmp_path, monkeypatch, capsys):
    """benchmarks/stability.py prints one JSON line counting runs by how they finished."""
    import json
    import runpy
    from pathlib import Path

    script = Path(__file__).resolve().parents[2] / "benchmarks" / "stability.py"
    main = runpy.run_path(str(script))["main"]
    cfg = tmp_path / "m.toml"
    cfg.write_text(MINUTE)
    _unstable(monkeypatch, 1)
    assert main(["--preset", "tiny", "--config", str(cfg), "--runs", "2"]) == 0
    line = json.loads(capsys.readouterr().out)
    assert line["runs"] == 2 and line["as_configured"] == 0 and line["failed"] == 0
    assert line["stabilised_runs"] == {"0": 1, "1": 1}
    monkeypatch.undo()
    _unstable(monkeypatch, 6)
    assert main(["--preset", "tiny", "--config", str(cfg), "--start", "1", "--runs", "1"]) == 0
    line = json.loads(capsys.readouterr().out)
    assert line["failed"] == 1 and "every try went unstable" in line["failed_runs"]["1"]
