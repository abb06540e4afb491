"""`python -m demseis_dev.bench`: dem (pack files and the settled-pack cache) and seismic print
one JSON line."""

from __future__ import annotations

import json

import numpy as np
import pytest

from demseis.dem import settle_pack
from demseis.errors import InputError
from demseis_dev.bench import dem_benchmark, load_pack, main


@pytest.fixture(scope="module")
def small_pack(tmp_path_factory):
    cache = tmp_path_factory.mktemp("cache")
    p = settle_pack(600.0, 300.0, rng=4, cache_dir=cache)
    return p, cache


def test_pack_cache_hit_is_identical(small_pack):
    p, cache = small_pack
    files = list(cache.glob("pack_*.npz"))
    assert len(files) == 1
    again = settle_pack(600.0, 300.0, rng=4, cache_dir=cache)
    assert again.xy.tobytes() == p.xy.tobytes()
    other = settle_pack(600.0, 300.0, rng=5, cache_dir=cache)
    assert len(list(cache.glob("pack_*.npz"))) == 2
    assert other.xy.shape != p.xy.shape or not np.array_equal(other.xy, p.xy)


def test_run_bench_reports_throughput(small_pack):
    p, _ = small_pack
    res = dem_benchmark(p.xy, p.radius, n_steps=50)
    assert res["n_elements"] == p.radius.size and res["steps"] == 50
    assert res["element_steps_per_s"] == pytest.approx(p.radius.size * 50 / res["wall_s"],
                                                       rel=0.01)


def test_cli_bench_dem_with_pack(small_pack, tmp_path, capsys):
    p, _ = small_pack
    f = tmp_path / "pack.npz"
    np.savez(f, x=p.xy[:, 0], y=p.xy[:, 1], radius=p.radius)
    assert main(["dem", "--pack", str(f), "--steps", "20"]) == 0
    out = capsys.readouterr().out.strip().splitlines()
    assert len(out) == 1
    rec = json.loads(out[0])
    assert rec["element_steps_per_s"] > 0 and rec["n_elements"] == p.radius.size


def test_bad_pack_files(tmp_path, capsys):
    with pytest.raises(InputError, match="no such file"):
        load_pack(tmp_path / "nope.npz")
    f = tmp_path / "a.npz"
    np.savez(f, x=np.zeros(3), y=np.zeros(3))
    with pytest.raises(InputError, match="radius"):
        load_pack(f)
    np.savez(f, x=np.zeros(3), y=np.zeros(2), radius=np.ones(3))
    with pytest.raises(InputError, match="equal length"):
        load_pack(f)
    g = tmp_path / "b.npz"
    g.write_text("not a zip")
    with pytest.raises(InputError, match="readable"):
        load_pack(g)
    assert main(["dem", "--pack", str(tmp_path / "nope.npz")]) == 2
    assert "no such file" in capsys.readouterr().err


def test_bench_seismic_prints_one_json_line(capsys):
    assert main(["seismic", "--nx", "64", "--nz", "36", "--repeats", "1"]) == 0
    lines = capsys.readouterr().out.strip().splitlines()
    assert len(lines) == 1
    rec = json.loads(lines[0])
    assert rec["nx"] == 64 and rec["nz"] == 36
    assert rec["ms_snapshot_1f"] > 0 and rec["ms_snapshot_3f"] > 0
    assert set(rec["components_ms"]) >= {"rasterise", "background", "smooth_vp_rho",
                                         "convolution_1f", "convolution_3f"}
    assert main(["seismic", "--repeats", "0"]) == 2
