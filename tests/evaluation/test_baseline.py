"""The semblance baseline: kernel vs a NumPy reference, better than chance on Ricker sections."""

from __future__ import annotations

import json

import numpy as np
import pytest

from demseis.cli import main
from demseis.errors import InputError
from demseis.evaluation._kernels import dip_scan_semblance
from demseis.evaluation.baseline import SemblanceBaseline, semblance_fault_probability
from demseis.evaluation.scoring import score
from demseis_dev.toys import faulted_section
from demseis_dev.toys import ricker_pulse as ricker
from tests.evaluation._helpers import make_store


def _reference_semblance(u, slopes, ht, hs, eps):
    nz, nx = u.shape
    out = np.zeros((nz, nx))
    zz = np.arange(nz)
    for iz in range(nz):
        for ix in range(nx):
            best = 0.0
            for p in slopes:
                num = den = 0.0
                for dz in range(-hs, hs + 1):
                    vals = []
                    for dx in range(-ht, ht + 1):
                        jx, z = ix + dx, iz + dz + p * dx
                        if 0 <= jx < nx and 0 <= z <= nz - 1:
                            vals.append(np.interp(z, zz, u[:, jx]))
                    vals = np.array(vals)
                    num += vals.sum() ** 2
                    den += len(vals) * (vals ** 2).sum()
                best = max(best, (num + eps) / (den + eps))
            out[iz, ix] = best
    return out


def test_kernel_matches_numpy_reference():
    rng = np.random.default_rng(0)
    u = rng.normal(size=(13, 11))
    slopes = np.linspace(-1, 1, 5)
    got = dip_scan_semblance(u, slopes, 2, 3, 0.1)
    ref = _reference_semblance(u, slopes, 2, 3, 0.1)
    assert np.allclose(got, ref, atol=1e-5)
    assert got.min() >= 0 and got.max() <= 1 + 1e-6


def test_identical_dipping_traces_have_semblance_one():
    trace = np.convolve(np.random.default_rng(1).normal(size=60), ricker(25, 0.004, 21), "same")
    z = np.arange(40)[:, None]
    u = np.interp(z + 20 - 1.0 * np.arange(20)[None, :], np.arange(60), trace)
    c = dip_scan_semblance(u, np.linspace(-1, 1, 9), 2, 3, 0.0)
    assert np.all(c[5:-5, 3:-3] > 0.999)  # 45-degree reflectors, slope 1.0 is on the grid
    c0 = dip_scan_semblance(u, np.zeros(1), 2, 3, 0.0)  # without the dip scan they decorrelate
    assert np.median(c0[5:-5, 3:-3]) < 0.9


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_better_than_chance_on_faulted_sections(seed):
    sec, truth = faulted_section(seed=seed)
    prob = semblance_fault_probability(sec)
    assert prob.shape == sec.shape and prob.dtype == np.float32
    assert 0 <= prob.min() and prob.max() <= 1
    base_rate = truth.mean()
    r = score(prob, truth, tolerance_px=2)
    # chance (random scores) gives AP ~ base rate (~2 %); the detector finds the fault
    assert r.ap > 10 * base_rate and r.ap > 0.5
    assert r.recall > 0.6 and r.precision > 0.5
    # unfaulted section: next to nothing is called a fault at the default threshold
    clean, _ = faulted_section(seed=seed, fault=False)
    assert (semblance_fault_probability(clean) >= 0.5).mean() < 0.01


def test_noisy_section_still_beats_chance():
    sec, truth = faulted_section(seed=4, noise=0.3)  # about 10 dB SNR
    r = score(semblance_fault_probability(sec), truth, tolerance_px=2)
    assert r.ap > 10 * truth.mean()


def test_stack_and_errors():
    sec, _ = faulted_section(seed=0, nz=40, nx=40)
    both = semblance_fault_probability(np.stack([sec, sec]))
    assert np.array_equal(both[0], semblance_fault_probability(sec))
    assert np.all(semblance_fault_probability(np.zeros((10, 10))) == 0)
    with pytest.raises(InputError, match="NaN"):
        semblance_fault_probability(np.full((5, 5), np.nan))
    with pytest.raises(InputError, match="half_traces"):
        SemblanceBaseline(half_traces=0)


def test_cli_baseline_then_score(tmp_path, capsys):
    secs, truths = zip(*(faulted_section(nz=32, nx=32, seed=s) for s in range(6)))
    seismic = np.stack(secs)
    make_store(tmp_path / "s.zarr", n_shards=3, per_shard=2, h=32, w=32, seismic=seismic,
               done=[1, 1, 0])
    import zarr

    zarr.open_group(str(tmp_path / "s.zarr"), mode="r+")["fault"][:] = np.stack(truths)
    out = tmp_path / "base.npy"
    assert main(["baseline", str(tmp_path / "s.zarr"), "--out", str(out), "--method",
                 "semblance"]) == 0
    pred = np.load(out)
    assert pred.shape == (6, 32, 32)
    assert np.all(pred[4:] == 0)  # incomplete shard left empty
    assert np.allclose(pred[0], semblance_fault_probability(seismic[0]))
    assert main(["baseline", str(tmp_path / "s.zarr"), "--out", str(out)]) == 2  # exists
    from demseis.evaluation.baseline import dip_fault_probability

    dip = tmp_path / "dip.npy"
    assert main(["baseline", str(tmp_path / "s.zarr"), "--out", str(dip)]) == 0  # default dip
    assert np.allclose(np.load(dip)[1], dip_fault_probability(seismic[1]))
    capsys.readouterr()
    assert main(["score", str(out), str(tmp_path / "s.zarr"), "--tolerance", "2"]) == 0
    rep = json.loads((tmp_path / "base.score.json").read_text())
    assert rep["overall"]["n_samples"] == 4 and rep["overall"]["ap"] > 0.3


def test_cli_baseline_needs_no_labels_but_seismic(tmp_path, capsys):
    make_store(tmp_path / "s.zarr", n_shards=2, per_shard=2, h=16, w=16, with_fault=False)
    assert main(["baseline", str(tmp_path / "s.zarr"), "--out", str(tmp_path / "p.zarr")]) == 0
    assert zarr_shape(tmp_path / "p.zarr") == (4, 16, 16)
    capsys.readouterr()
    rc = main(["baseline", str(tmp_path / "s.zarr"), "--out", str(tmp_path / "q.npy"),
               "--input", "impedance"])
    assert rc == 2 and "'impedance'" in capsys.readouterr().err
    assert not (tmp_path / "q.npy").exists()


def zarr_shape(path):
    import zarr

    return tuple(zarr.open_array(str(path), mode="r").shape)


@pytest.mark.parametrize("seed", [0, 1])
def test_dip_attribute_beats_chance_and_ignores_gentle_dip(seed):
    from demseis.evaluation.baseline import dip_fault_probability

    sec, truth = faulted_section(seed=seed)
    prob = dip_fault_probability(sec)
    assert prob.shape == sec.shape and 0 <= prob.min() and prob.max() <= 1
    r = score(prob, truth, tolerance_px=2)
    assert r.ap > 2 * r.chance_ap
    clean, _ = faulted_section(seed=seed, fault=False)  # 0.1 samples/trace regional dip
    assert (dip_fault_probability(clean) >= 0.5).mean() == 0.0


def test_dip_attribute_reads_reflector_dip():
    from demseis.evaluation.baseline import dip_fault_probability

    trace = np.convolve(np.random.default_rng(2).normal(size=200), ricker(25, 0.004, 21), "same")
    z = np.arange(80)[:, None]
    x = np.arange(60)[None, :]
    for slope, expect in ((0.0, 0.0), (np.tan(np.radians(30)), 1.0)):
        u = np.interp(z + 60 - slope * x, np.arange(200), trace)
        p = dip_fault_probability(u, dip_scale=0.5)[15:-15, 15:-15]
        assert np.median(p) == pytest.approx(expect, abs=0.15)
    with pytest.raises(InputError, match="dip_scale"):
        dip_fault_probability(u, dip_scale=0)


@pytest.mark.parametrize("suffix", [".npy", ".zarr"])
def test_cli_baseline_on_a_damaged_store_leaves_nothing_behind(tiny_store, tmp_path, capsys,
                                                               suffix):
    """issue 38: a sample whose chunk fails its checksum stops `baseline` with one line, and
    neither the output nor its ``.part`` file is left behind."""
    import shutil

    store = tmp_path / "s.zarr"
    shutil.copytree(tiny_store, store)
    shard = store / "seismic" / "c" / "1" / "0" / "0"       # shard 1: 6 raw inner chunks
    data = bytearray(shard.read_bytes())
    index = np.frombuffer(bytes(data[-(6 * 16 + 4):-4]), dtype="<u8").reshape(6, 2)
    data[int(index[2, 0]) + int(index[2, 1]) // 2] ^= 0x10   # a bit in sample 8's values
    shard.write_bytes(bytes(data))
    out = tmp_path / f"base{suffix}"
    assert main(["baseline", str(store), "--out", str(out)]) != 0
    err = capsys.readouterr().err
    # the checksum mismatch in words, not zarr's raw bytes (issue 38)
    assert len(err.strip().splitlines()) == 1 and "crc32c checksum mismatch" in err, err
    assert "b'" not in err and "Stored:" not in err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["s.zarr"]
