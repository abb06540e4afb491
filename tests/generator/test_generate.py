"""End to end: ``demseis generate`` on the tiny preset, resume, determinism, the other commands."""

from __future__ import annotations

import numpy as np
import pytest
import zarr

from demseis.cli import main
from tests._helpers import params_of
from tests.generator._helpers import assert_same_bytes, tree_bytes


def test_tiny_store_contents(tiny_store):
    root = zarr.open_group(str(tiny_store), mode="r")
    seis, fault = root["seismic"], root["fault"]
    assert seis.dtype == np.float32 and fault.dtype == np.uint8
    n, h, w = seis.shape
    assert n >= 8
    for name in ("fault", "damage", "strain", "layer"):
        assert root[name].shape == (n, h, w)
    s = seis[:]
    assert not np.isnan(s).any()
    assert np.abs(s).max() > 0
    snap = params_of(root)["snapshot"]
    f = fault[:].reshape(n, -1).sum(axis=1)
    # slip-trace labels need a measured jump >= min_slip_m, so a faulted snapshot can hold none:
    # run 1 of `tiny` (60 deg) has a 55 m trace at 50 m throw and none at 100 m, where its shear
    # zone is wider than the jump window (a known limit, docs/labels.md). has_fault says which.
    assert np.array_equal(params_of(root)["has_fault"], (f > 0).astype(np.uint8))
    run = params_of(root)["run_id"]
    for r in np.unique(run):
        assert f[(run == r) & (snap > 0)].max() > 0, f"run {r}: no fault in any faulted snapshot"
    assert np.all(f[snap == 0] == 0), "fault mask non-empty before any faulting"
    assert set(np.unique(root["damage"][:])) <= {0, 1, 2}


def test_same_command_same_bytes(tiny_store, tmp_path):
    again = tmp_path / "again.zarr"
    assert main(["generate", "--preset", "tiny", "--out", str(again), "--workers", "0", "--quiet"]) == 0
    assert_same_bytes(tiny_store, again)


def test_rerun_on_complete_store_is_a_no_op(tiny_store, capsys):
    before = tree_bytes(tiny_store)
    assert main(["generate", "--preset", "tiny", "--out", str(tiny_store), "--workers", "0", "--quiet"]) == 0
    assert "3 already done, 0 written now" in capsys.readouterr().out
    assert tree_bytes(tiny_store) == before


def test_no_progress_bar_when_nothing_is_left(tiny_store, capsys):
    """A rerun on a complete store prints its summary, not an empty progress bar (twice)."""
    assert main(["generate", "--preset", "tiny", "--out", str(tiny_store), "--workers", "0"]) == 0
    captured = capsys.readouterr()
    assert "0 written now" in captured.out
    assert "generate:" not in captured.err and "sample/s" not in captured.err


def test_resume_removes_killed_writers_temporary_files(tiny_store, tmp_path):
    # zarr writes <file>.<uuid hex>.partial then renames it; kill -9 in between leaves it (the
    # kill test found one in a resumed store), and a half-made store beside it of a dead driver
    import shutil

    out = tmp_path / "copy.zarr"
    shutil.copytree(tiny_store, out)
    stale = [out / "params" / f"c.0.0.{'ab' * 16}.partial",
             out / "seismic" / "c" / "1" / "0" / f"0.{'0f' * 16}.partial"]
    for f in stale:
        f.write_bytes(b"half a chunk")
    keep = out / "seismic" / "c" / "notes.partial"  # not zarr's pattern: not ours to delete
    keep.write_text("x")
    orphan = tmp_path / ".other.zarr.creating-999999999"  # no such pid
    orphan.mkdir()
    assert main(["generate", "--preset", "tiny", "--out", str(out), "--workers", "0", "--quiet"]) == 0
    assert not any(f.exists() for f in stale)
    keep.unlink()
    assert_same_bytes(tiny_store, out)
    assert orphan.exists()  # another store's name: left alone
    assert main(["generate", "--preset", "tiny", "--out", str(tmp_path / "other.zarr"),
                 "--workers", "0", "--quiet"]) == 0
    assert not orphan.exists()


def test_finalize_removes_temporary_files_of_a_killed_worker(tiny_store, tmp_path):
    import shutil

    from demseis.datasets import finalize_store

    out = tmp_path / "copy.zarr"
    shutil.copytree(tiny_store, out)
    stale = out / "fault" / "c" / "0" / "0" / f"0.{'12' * 16}.partial"
    stale.write_bytes(b"x")
    finalize_store(out)
    assert not stale.exists()
    assert_same_bytes(tiny_store, out)


def test_different_config_refused_without_overwrite(tiny_store, tmp_path, capsys):
    cfg = tmp_path / "c.toml"
    cfg.write_text("[sweep]\nseed = 99\n")
    before = tree_bytes(tiny_store)
    code = main(["generate", str(cfg), "--preset", "tiny", "--out", str(tiny_store), "--workers", "0"])
    err = capsys.readouterr().err
    assert code == 2
    assert "different config" in err and "sweep.seed" in err and "--overwrite" in err
    assert tree_bytes(tiny_store) == before


def test_overwrite_replaces(tiny_store, tmp_path):
    copy = tmp_path / "copy.zarr"
    assert main(["generate", "--preset", "tiny", "--out", str(copy), "--workers", "0", "--quiet"]) == 0
    cfg = tmp_path / "c.toml"
    cfg.write_text("[sweep]\nseed = 5\nn_runs = 1\n")
    assert main(["generate", str(cfg), "--preset", "tiny", "--out", str(copy), "--workers", "0",
                 "--quiet", "--overwrite"]) == 0
    root = zarr.open_group(str(copy), mode="r")
    assert root.attrs["config"]["sweep"]["seed"] == 5
    assert root["seismic"].shape[0] == 6


def test_foreign_directory_refused(tmp_path, capsys):
    foreign = tmp_path / "mine"
    foreign.mkdir()
    (foreign / "precious.txt").write_text("keep me")
    code = main(["generate", "--preset", "tiny", "--out", str(foreign), "--workers", "0", "--overwrite"])
    assert code == 2
    assert (foreign / "precious.txt").read_text() == "keep me"
    assert len(capsys.readouterr().err.strip().splitlines()) == 1


def test_dry_run_writes_nothing(tmp_path, capsys):
    out = tmp_path / "d.zarr"
    assert main(["generate", "--preset", "quick", "--out", str(out), "--dry-run"]) == 0
    text = capsys.readouterr().out
    assert "dem runs: 4 to compute (of 4; a new store)" in text and "samples: 48" in text and "estimated time" in text and "MiB" in text
    assert not out.exists()


def test_dry_run_counts_only_what_a_partly_done_store_lacks(tiny_store, tmp_path, capsys):
    """issue 38: the plan of a store with 2 of its 3 runs done says 1 run to compute; another
    config is refused as generate refuses it; --overwrite plans all of them. Nothing is written."""
    import shutil

    out = tmp_path / "t.zarr"
    shutil.copytree(tiny_store, out)
    (out / "shard_done" / "c" / "1").unlink()           # run 1 not done (its flag chunk gone)
    before = tree_bytes(out)
    assert main(["generate", "--preset", "tiny", "--out", str(out), "--dry-run"]) == 0
    text = capsys.readouterr().out
    assert f"dem runs: 1 to compute (of 3; 2 done in {out})" in text and "samples: 6 " in text
    assert main(["generate", "--preset", "tiny", "--out", str(out), "--dry-run",
                 "--overwrite"]) == 0
    assert "dem runs: 3 to compute (of 3; --overwrite replaces the store)" in capsys.readouterr().out
    assert main(["generate", "--preset", "quick", "--out", str(out), "--dry-run"]) == 2
    assert "different config" in capsys.readouterr().err
    assert tree_bytes(out) == before


def test_info(tiny_store, capsys):
    assert main(["info", str(tiny_store)]) == 0
    text = capsys.readouterr().out
    assert "samples: 18 in 3 shards of 6; done shards: 3" in text
    assert "dip_deg" in text and "45, 60" in text
    assert main(["info", str(tiny_store.parent / "missing.zarr")]) == 2


def test_render_reuses_particles(tiny_store, tmp_path):
    out = tmp_path / "r.zarr"
    assert main(["render", str(tiny_store), "--freq", "25,50", "--snr", "inf", "--out", str(out), "--quiet"]) == 0
    src = zarr.open_group(str(tiny_store), mode="r")
    new = zarr.open_group(str(out), mode="r")
    n_snap = src.attrs["config"]["model"]["n_snapshots"]
    assert new["seismic"].shape[0] == 3 * n_snap * 2
    assert sorted(set(params_of(new)["freq_hz"].tolist())) == [25.0, 50.0]
    # the labels come from the same particles: identical to the source's, snapshot by snapshot
    for run in (0, 1, 2):
        for k in range(n_snap):
            a = src["fault"][np.flatnonzero((params_of(src)["run_id"] == run) & (params_of(src)["snapshot"] == k))[0]]
            b = new["fault"][np.flatnonzero((params_of(new)["run_id"] == run) & (params_of(new)["snapshot"] == k))[0]]
            np.testing.assert_array_equal(a, b)
    assert main(["validate", str(out)]) == 0


def test_bad_render_args(tiny_store, tmp_path, capsys):
    assert main(["render", str(tiny_store), "--freq", "20,abc", "--out", str(tmp_path / "x")]) == 2
    assert "'abc' is not a number" in capsys.readouterr().err
    assert main(["render", str(tiny_store), "--freq", "900", "--out", str(tmp_path / "x")]) == 2
    assert "--freq 900.0 is not allowed" in capsys.readouterr().err
    assert not (tmp_path / "x").exists()


def test_dataloader_two_workers(tiny_store):
    import torch
    from torch.utils.data import DataLoader

    from demseis.datasets import FaultSegDataset

    ds = FaultSegDataset(tiny_store, inputs=("seismic",), targets=("fault",), crop=(32, 32))
    loader = DataLoader(ds, batch_size=4, num_workers=2)
    seen = 0
    for x, y in loader:
        assert x.dtype == torch.float32 and x.shape[1:] == (1, 32, 32)
        assert y.shape[1:] == (32, 32)
        seen += x.shape[0]
    assert seen == len(ds) == 18


def test_preview_writes_figures(tiny_store, tmp_path):
    out = tmp_path / "figs"
    assert main(["preview", str(tiny_store), "--out", str(out), "--run", "1"]) == 0
    names = sorted(p.name for p in out.glob("*.png"))
    assert names == ["fig2_particles.png", "fig3_particle_properties.png", "fig4_gridded.png",
                     "fig5_section_overlay.png", "fig6_frequency.png"]
    assert all((out / n).stat().st_size > 10_000 for n in names)
    assert main(["preview", str(tiny_store), "--out", str(out), "--run", "7"]) == 2


@pytest.mark.slow
def test_one_and_two_workers_identical(tiny_store, tmp_path):
    one = tmp_path / "one.zarr"
    two = tmp_path / "two.zarr"
    assert main(["generate", "--preset", "tiny", "--out", str(one), "--workers", "1", "--quiet"]) == 0
    assert main(["generate", "--preset", "tiny", "--out", str(two), "--workers", "2", "--quiet"]) == 0
    assert_same_bytes(tiny_store, one)
    assert_same_bytes(tiny_store, two)


@pytest.mark.slow
def test_existing_scheduler(tiny_store, tmp_path):
    """--scheduler ADDRESS runs the same tasks on an existing cluster, same bytes."""
    from distributed import LocalCluster

    with LocalCluster(n_workers=1, threads_per_worker=1, processes=True, dashboard_address=None) as cluster:
        out = tmp_path / "s.zarr"
        assert main(["generate", "--preset", "tiny", "--out", str(out), "--scheduler",
                     cluster.scheduler_address, "--quiet"]) == 0
    assert_same_bytes(tiny_store, out)


def test_unreachable_scheduler_writes_nothing(tmp_path, capsys):
    out = tmp_path / "u.zarr"
    code = main(["generate", "--preset", "tiny", "--out", str(out), "--scheduler", "not-an-address"])
    assert code == 2
    assert "--scheduler 'not-an-address'" in capsys.readouterr().err
    assert not out.exists()


def test_time_domain_output(tmp_path):
    """domain = "time": sections and labels share one TWT axis; labels are the depth labels mapped."""
    from demseis.generator.config.layout import sample_shape
    from demseis.generator.config.settings import load_config

    cfg_file = tmp_path / "c.toml"
    cfg_file.write_text("[sweep]\nn_runs = 1\n[output]\ndomain = \"time\"\ndt_s = 0.002\n")
    out = tmp_path / "time.zarr"
    assert main(["generate", str(cfg_file), "--preset", "tiny", "--out", str(out), "--workers", "0", "--quiet"]) == 0
    root = zarr.open_group(str(out), mode="r")
    cfg = load_config(cfg_file, preset="tiny")
    nt, nx = sample_shape(cfg)
    grid = root.attrs["grid"]
    assert grid["domain"] == "time" and grid["dt_s"] == 0.002 and grid["nt"] == nt
    # the slowest column (vp >= lower bound) fits: 2 * depth / vp_min <= (nt - 1) * dt
    assert root["seismic"].shape == root["fault"].shape == (6, nt, nx)
    assert nt != grid["nz"]
    fault = root["fault"][:]
    snap = params_of(root)["snapshot"]
    assert fault[snap > 0].sum() > 0 and fault[snap == 0].sum() == 0
    assert main(["validate", str(out)]) == 0
    assert main(["export-segy", str(out), "--sample", "5", "--out", str(tmp_path / "t.sgy")]) == 0


def test_unstable_run_recorded_and_sweep_goes_on(tmp_path, monkeypatch, capsys):
    """A SimulationError in one run is recorded with its message; the other runs are written;
    a rerun retries only the failed run."""
    import demseis.generator.sweep.driver as sweep
    from demseis.errors import SimulationError

    real = sweep.run_shard

    def flaky(cfg, run, progress=None, **kw):
        if run == 1:
            raise SimulationError("kinetic energy blew up at step 123")
        return real(cfg, run, progress, **kw)

    monkeypatch.setattr(sweep, "run_shard", flaky)
    out = tmp_path / "f.zarr"
    code = main(["generate", "--preset", "tiny", "--out", str(out), "--workers", "0", "--quiet"])
    text = capsys.readouterr().out
    assert code == 1
    assert "2 written now, 1 failed" in text
    assert "run 1 failed: SimulationError: kinetic energy blew up at step 123" in text
    # the same seed fails the same way: the summary says what to change, not "rerun"
    assert "fails the same way" in text and "wall_speed_m_s" in text
    assert "rerun the same command" not in text
    assert main(["info", str(out)]) == 0
    assert "run 1: SimulationError" in capsys.readouterr().out
    monkeypatch.setattr(sweep, "run_shard", real)
    assert main(["generate", "--preset", "tiny", "--out", str(out), "--workers", "0", "--quiet"]) == 0
    assert "2 already done, 1 written now, 0 failed" in capsys.readouterr().out
    assert main(["validate", str(out)]) == 0
