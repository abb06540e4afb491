"""Scenario sampling: grids crossed and cycled, distributions seeded per run, order-free."""

from __future__ import annotations

import numpy as np
import pytest

from demseis.generator.config.sampling import plan_run, run_params
from demseis.generator.config.settings import load_config, parse_config


def _cfg(**sweep):
    return parse_config({"sweep": {"seed": 7, "n_runs": 6, **sweep}})


def test_run_grid_cycles_over_runs():
    cfg = _cfg(dip_deg=[30, 45, 60], throw_m=[100, 200])
    combos = [(run_params(cfg, r)["dip_deg"], run_params(cfg, r)["throw_m"]) for r in range(6)]
    assert sorted(combos) == sorted((d, t) for d in (30.0, 45.0, 60.0) for t in (100.0, 200.0))


def test_distribution_draws_depend_only_on_seed_and_run():
    cfg = _cfg(dip_deg={"dist": "uniform", "low": 30, "high": 70})
    a = [run_params(cfg, r)["dip_deg"] for r in range(6)]
    b = [run_params(cfg, r)["dip_deg"] for r in reversed(range(6))][::-1]
    assert a == b
    assert len(set(a)) == 6
    assert all(30 <= d <= 70 for d in a)
    other = parse_config({"sweep": {"seed": 8, "n_runs": 6, "dip_deg": {"dist": "uniform", "low": 30, "high": 70}}})
    assert [run_params(other, r)["dip_deg"] for r in range(6)] != a


def test_truncnormal_and_loguniform_within_bounds():
    cfg = _cfg(friction={"dist": "truncnormal", "mean": 0.4, "std": 0.3, "low": 0.3, "high": 0.5},
               kn_n_m={"dist": "loguniform", "low": 5e9, "high": 3e10})
    vals = np.array([[run_params(cfg, r)["friction"], run_params(cfg, r)["kn_n_m"]] for r in range(6)])
    assert np.all((vals[:, 0] >= 0.3) & (vals[:, 0] <= 0.5))
    assert np.all((vals[:, 1] >= 5e9) & (vals[:, 1] <= 3e10))


def test_render_grid_is_crossed_per_snapshot():
    cfg = parse_config({"sweep": {"freq_hz": [20, 40, 60], "snr_db": ["inf", 10]},
                        "model": {"n_snapshots": 3}})
    spec = plan_run(cfg, 0)
    assert len(spec.renders) == cfg.samples_per_run == 3 * 6
    for snap in range(3):
        pairs = {(r.freq_hz, r.snr_db) for r in spec.renders if r.snapshot == snap}
        assert len(pairs) == 6
    assert len({r.seed for r in spec.renders}) == len(spec.renders)


def test_truncnormal_inversion_matches_scipy():
    """DistSpec's inverse-CDF truncated normal equals scipy.stats.truncnorm.ppf at the same u."""
    from scipy import stats

    from demseis.generator.config.params import DistSpec

    class FixedU:
        def __init__(self, u):
            self.u = u

        def uniform(self):
            return self.u

    for mean, std, low, high in ((0.4, 0.1, 0.2, 0.6), (0.4, 0.3, 0.3, 0.5), (45.0, 10.0, 30.0, 50.0)):
        spec = DistSpec("truncnormal", low=low, high=high, mean=mean, std=std)
        ref = stats.truncnorm((low - mean) / std, (high - mean) / std, loc=mean, scale=std)
        for u in (0.001, 0.1, 0.37, 0.5, 0.9, 0.999):
            assert abs(spec.sample(FixedU(u)) - ref.ppf(u)) < 1e-9 * max(1.0, abs(mean))


def test_run_params_are_one_typed_frozen_object_that_reads_as_a_mapping():
    """A run's parameters: one field per run-level declaration with its declared type, the
    same values through attributes and keys, frozen, and pickled by reference to the workers."""
    import dataclasses
    import pickle

    from demseis.generator.config.sampling import RUN_KEYS, RunParams, RunSpec
    from demseis.parameters import SCENARIO

    cfg = load_config(preset="variety")
    p = run_params(cfg, 3)
    assert isinstance(p, RunParams)
    fields = [f for f in dataclasses.fields(p) if f.name != "engine_values"]
    assert [f.name for f in fields] == list(RUN_KEYS) == list(p) and p.engine_values == ()
    assert set(RUN_KEYS) == {k for k, d in SCENARIO.items() if d.level == "run"}
    for f in fields:
        assert f.type is SCENARIO[f.name].kind
        assert type(getattr(p, f.name)) is SCENARIO[f.name].kind, f.name
        assert p[f.name] == getattr(p, f.name)
    assert dict(p) == {k: getattr(p, k) for k in RUN_KEYS} and len(p) == len(RUN_KEYS)
    with pytest.raises(dataclasses.FrozenInstanceError):
        p.dip_deg = 10.0
    with pytest.raises(KeyError):
        p["freq_hz"]                       # a sample-level parameter: not a run's
    assert pickle.loads(pickle.dumps(p)) == p
    q = p.replace(n_layers=7.0, dip_deg=30)            # coerced to the declared kinds
    assert (q.n_layers, type(q.n_layers), q.dip_deg, type(q.dip_deg)) == (7, int, 30.0, float)
    assert q.throw_m == p.throw_m and p == run_params(cfg, 3)          # p itself unchanged
    with pytest.raises(KeyError, match="freq_hz"):
        RunParams.of({"freq_hz": 20.0})
    spec = RunSpec(run=0, params={**p, "dip_deg": 20.0}, renders=())    # a dict is made one
    assert isinstance(spec.params, RunParams) and spec.params.dip_deg == 20.0
