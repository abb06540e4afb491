"""``[model] pack_library``: runs take one of K settled packs (built once, cached) and still
draw their own layering, rock and faults; K = 0 keeps the bytes and the resume of stores
written before the library existed."""

from __future__ import annotations

import dataclasses
import json
import runpy
from pathlib import Path

import numpy as np
import pytest

import demseis
from demseis.errors import ConfigError
from demseis.generator.config.params import Fixed
from demseis.generator.config.sampling import plan_run
from demseis.generator.config.settings import load_config, parse_config, stored_config
from demseis.generator.engines.dem import (ENGINE, library_material, pack_cache_dir, pack_index,
                                           run_pack)
from demseis.generator.sweep.driver import pending_runs

DIGEST = runpy.run_path(str(Path(__file__).resolve().parents[2] / "benchmarks" /
                            "store_digest.py"))["digest"]


def _tiny(k: int, n_runs: int | None = None, **sweep):
    cfg = load_config(preset="tiny")
    params = {**cfg.sweep.params, **{key: Fixed(v) for key, v in sweep.items()}}
    return dataclasses.replace(
        cfg, model=dataclasses.replace(cfg.model, pack_library=k),
        sweep=dataclasses.replace(cfg.sweep, params=params,
                                  n_runs=n_runs or cfg.sweep.n_runs))


def test_each_block_of_k_runs_takes_every_pack_once():
    cfg = _tiny(4)
    taken = [pack_index(cfg, r) for r in range(12)]
    for b in range(3):
        assert sorted(taken[4 * b:4 * b + 4]) == [0, 1, 2, 3]
    assert taken == [pack_index(cfg, r) for r in range(12)]           # deterministic
    assert taken[:4] != taken[4:8] or taken[4:8] != taken[8:]          # orders drawn per block
    reseeded = dataclasses.replace(cfg, sweep=dataclasses.replace(cfg.sweep, seed=7))
    assert [pack_index(reseeded, r) for r in range(12)] != taken
    with pytest.raises(ConfigError, match="pack_library"):
        pack_index(_tiny(0), 0)


def test_the_library_material_is_the_middle_of_the_sweep():
    field = load_config(preset="field")
    m = library_material(field)
    assert m.cohesion_n == pytest.approx(4.5e8)          # uniform 3e8 .. 6e8: the midpoint
    assert m.friction == 0.8 and m.model == "brittle"    # fixed values
    raw = field.to_dict()
    raw["sweep"]["cohesion_n"] = {"dist": "loguniform", "low": 1e8, "high": 1e9}
    raw["sweep"]["friction"] = [0.4, 0.6]
    m = library_material(parse_config(raw))
    assert m.cohesion_n == pytest.approx(10 ** 8.5) and m.friction == 0.4


def test_the_cache_defaults_to_the_user_cache(monkeypatch, tmp_path):
    monkeypatch.delenv("DEMSEIS_PACK_CACHE", raising=False)
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    assert pack_cache_dir() == tmp_path / "demseis" / "packs"
    monkeypatch.delenv("XDG_CACHE_HOME")
    assert pack_cache_dir() == Path("~/.cache/demseis/packs").expanduser()
    monkeypatch.setenv("DEMSEIS_PACK_CACHE", str(tmp_path / "p"))
    assert pack_cache_dir() == tmp_path / "p"


def test_runs_take_distinct_packs_but_their_own_layering(tmp_path, monkeypatch):
    monkeypatch.setenv("DEMSEIS_PACK_CACHE", str(tmp_path))
    cfg = _tiny(2, n_runs=3, layer_thickness_cv=0.5, n_layers=4)
    k = [pack_index(cfg, r) for r in range(3)]
    assert k[0] != k[1]
    packs = [run_pack(cfg, r) for r in range(3)]
    assert len(list(tmp_path.glob("pack_*.npz"))) == 2
    assert packs[0].xy.tobytes() != packs[1].xy.tobytes()
    same = next(r for r in (0, 1) if k[r] == k[2])
    assert packs[same].xy.tobytes() == packs[2].xy.tobytes()
    runs = [ENGINE.simulate(cfg, plan_run(cfg, r)) for r in (same, 2)]
    s0 = [run.snapshots[0] for run in runs]
    # the same disks (the shared pack, nothing deposited or eroded before snapshot 0) ...
    assert s0[0].radius.tobytes() == s0[1].radius.tobytes()
    # ... in each run's own layers, faulted by each run's own basement
    assert not np.array_equal(s0[0].layer, s0[1].layer)
    assert runs[0].info.values != runs[1].info.values


def test_the_library_gives_the_same_store_from_a_fresh_or_warm_cache(tmp_path, monkeypatch):
    cfg = _tiny(2)
    digests = []
    for cache, out in (("a", "1"), ("a", "2"), ("b", "3")):
        monkeypatch.setenv("DEMSEIS_PACK_CACHE", str(tmp_path / cache))
        store = demseis.generate(cfg, out=tmp_path / f"{out}.zarr", workers=0)
        assert not store.run_summary.failed
        digests.append(DIGEST(tmp_path / f"{out}.zarr")["sha256"])
    assert digests[0] == digests[1] == digests[2]
    assert json.loads(json.dumps(demseis.open(tmp_path / "1.zarr").attrs["config"])
                      )["model"]["pack_library"] == 2


def test_k0_keeps_the_bytes_and_the_resume_of_earlier_stores(tiny_store, tmp_path):
    """A store of a config that settles every run records no pack_library (the config and
    bytes it had before the library existed) and resumes; asking it for a library is refused,
    naming the key."""
    cfg = _tiny(0)
    assert "pack_library" not in cfg.to_dict()["model"]
    store = demseis.generate(cfg, out=tmp_path / "k0.zarr", workers=0)
    assert not store.run_summary.failed
    assert DIGEST(tmp_path / "k0.zarr")["sha256"] == DIGEST(tiny_store)["sha256"]
    raw = demseis.open(tiny_store).attrs["config"]
    assert "pack_library" not in raw["model"]
    assert stored_config(raw).model.pack_library == 0
    assert pending_runs(cfg, tiny_store)[0] == 0
    with pytest.raises(ConfigError, match="pack_library"):
        pending_runs(_tiny(4), tiny_store)


def test_engines_without_packs_do_not_record_the_key():
    field = load_config(preset="field")
    dem = dataclasses.replace(field, model=dataclasses.replace(field.model, pack_library=8))
    assert dem.to_dict()["model"]["pack_library"] == 8
    kin = dataclasses.replace(dem, model=dataclasses.replace(dem.model, engine="kinematic"))
    assert "pack_library" not in kin.to_dict()["model"]
