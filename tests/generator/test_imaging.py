"""The imaging option in the sweep: drawn per sample, recorded, shown, and re-renderable."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import zarr

from demseis.cli import main
from tests.generator._helpers import generate_tiny
from tests._helpers import params_of


@pytest.fixture(scope="module")
def both_store(tmp_path_factory) -> Path:
    """The tiny preset, no noise, every snapshot imaged in 1-D and with the PSF at 25 deg."""
    return generate_tiny(tmp_path_factory.mktemp("img"),
                         '[sweep]\nsnr_db = inf\nimaging = ["1d", "psf"]\npsf_max_angle_deg = 25\n',
                         "both")


def _pairs(root):
    """(1-D index, PSF index) of the samples of the same run and snapshot."""
    run, snap = params_of(root)["run_id"], params_of(root)["snapshot"]
    img = params_of(root)["imaging"]
    out = []
    for i in np.flatnonzero(img == 0):
        j = np.flatnonzero((img == 1) & (run == run[i]) & (snap == snap[i]))
        assert j.size == 1
        out.append((int(i), int(j[0])))
    return out


def test_imaging_is_drawn_and_recorded_per_sample(both_store):
    root = zarr.open_group(str(both_store), mode="r")
    assert list(root.attrs["param_codes"]["imaging"]) == ["1d", "psf"]
    img = params_of(root)["imaging"]
    assert root["seismic"].shape[0] == 3 * 3 * 2               # runs x snapshots x imaging
    assert sorted(set(img.tolist())) == [0, 1]
    np.testing.assert_array_equal(params_of(root)["psf_max_angle_deg"], 25.0)
    pairs = _pairs(root)
    assert len(pairs) == 9
    for i, j in pairs:
        a, b = root["seismic"][i].astype(np.float64), root["seismic"][j].astype(np.float64)
        np.testing.assert_array_equal(root["fault"][i], root["fault"][j])   # same labels
        ratio = np.sqrt((b ** 2).sum() / (a ** 2).sum())
        assert 0.3 < ratio < 1.0                    # steep energy removed, flat energy kept
        assert np.abs(a - b).max() > 0.05 * np.abs(a).max()
    assert main(["validate", str(both_store)]) == 0


def test_the_1d_samples_are_the_default_render(both_store, tmp_path):
    """Adding imaging = psf leaves the 1-D samples byte-identical to a 1-D-only sweep."""
    out = generate_tiny(tmp_path, "[sweep]\nsnr_db = inf\n", "one")
    one = zarr.open_group(str(out), mode="r")
    both = zarr.open_group(str(both_store), mode="r")
    np.testing.assert_array_equal(params_of(one)["imaging"], 0)
    i1d = [i for i, _ in _pairs(both)]
    np.testing.assert_array_equal(both["seismic"][i1d], one["seismic"][:])


def test_info_shows_the_imaging(both_store, capsys):
    assert main(["info", str(both_store)]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert any(ln.split() == ["imaging", "1d", "(9),", "psf", "(9)"] for ln in lines)
    assert any(ln.split() == ["psf_max_angle_deg", "25"] for ln in lines)


def test_render_an_existing_store_with_the_psf(both_store, tmp_path):
    out = tmp_path / "r.zarr"
    assert main(["render", str(both_store), "--freq", "30", "--imaging", "psf",
                 "--psf-max-angle", "20,45", "--psf-aperture", "500", "--out", str(out),
                 "--quiet"]) == 0
    new = zarr.open_group(str(out), mode="r")
    assert new["seismic"].shape[0] == 3 * 3 * 2               # runs x snapshots x angles
    np.testing.assert_array_equal(params_of(new)["imaging"], 1)
    assert sorted(set(params_of(new)["psf_max_angle_deg"].tolist())) == [20.0, 45.0]
    np.testing.assert_array_equal(params_of(new)["psf_aperture_m"], 500.0)
    # a narrower angle removes more of the energy
    ang = params_of(new)["psf_max_angle_deg"]
    r20 = np.sqrt(np.mean(new["seismic"][np.flatnonzero(ang == 20)].astype(np.float64) ** 2))
    r45 = np.sqrt(np.mean(new["seismic"][np.flatnonzero(ang == 45)].astype(np.float64) ** 2))
    assert r20 < r45
    assert main(["validate", str(out)]) == 0


def test_render_keeps_the_source_imaging_by_default(both_store, tmp_path):
    out = tmp_path / "k.zarr"
    assert main(["render", str(both_store), "--freq", "30", "--out", str(out), "--quiet"]) == 0
    src = zarr.open_group(str(both_store), mode="r")
    new = zarr.open_group(str(out), mode="r")
    np.testing.assert_array_equal(params_of(new)["imaging"], params_of(src)["imaging"])
    np.testing.assert_array_equal(new["seismic"][:], src["seismic"][:])


@pytest.mark.parametrize("args, msg", [
    (["--imaging", "2d"], "'2d' is not one of"),
    (["--psf-max-angle", "120"], "--psf-max-angle 120.0 is not allowed"),
    (["--psf-aperture", "100,200"], "give one value"),
])
def test_bad_imaging_args(both_store, tmp_path, capsys, args, msg):
    out = tmp_path / "x.zarr"
    assert main(["render", str(both_store), "--freq", "30", *args, "--out", str(out)]) == 2
    assert msg in capsys.readouterr().err
    assert not out.exists()
