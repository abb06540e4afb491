"""The ``strata`` rendering and survey sampling, end to end on small stores."""

from __future__ import annotations

import numpy as np
import pytest
import zarr

from demseis.cli import main
from demseis.evaluation.realism import (adjacent_trace_correlation, expected_lags, intact_mask,
                                        offset_agreement)
from tests.generator._helpers import assert_same_bytes, generate_tiny
from tests._helpers import params_of

SURVEY = """
[sweep]
n_runs = 1
snr_db = inf
{extra}
[model]
engine = "{engine}"
[output]
domain = "time"
dt_s = 0.004
trace_spacing_m = 25.0
impedance = true
rendering = "{rendering}"
"""


def survey(engine: str, rendering: str, extra: str = "") -> str:
    """A `tiny` config sampled like a survey (4 ms, 25 m traces), noise-free."""
    return SURVEY.format(engine=engine, rendering=rendering, extra=extra)


@pytest.fixture(scope="module")
def kin_strata(tmp_path_factory):
    return generate_tiny(tmp_path_factory.mktemp("ks"), survey("kinematic", "strata"), "ks")


@pytest.fixture(scope="module")
def dem_strata(tmp_path_factory):
    return generate_tiny(tmp_path_factory.mktemp("ds"), survey("dem", "strata"), "ds")


def test_survey_sampling_sets_the_shape_and_the_grid(kin_strata, tmp_path):
    root = zarr.open_group(str(kin_strata), mode="r")
    grid = root.attrs["grid"]
    # tiny: 900 m wide -> 36 traces 25 m apart; a two-way-time axis of 4 ms
    assert grid["dx_m"] == 25.0 and grid["nx"] == 36 and grid["dt_s"] == 0.004
    assert root["seismic"].shape[1:] == (grid["nt"], 36)
    np.testing.assert_allclose(root["x"][:2], [12.5, 37.5])
    assert main(["validate", str(kin_strata)]) == 0
    assert main(["export-segy", str(kin_strata), "--sample", "2",
                 "--out", str(tmp_path / "s.sgy")]) == 0


def test_kinematic_offsets_equal_the_labelled_throw(tmp_path):
    """Where the label says a fault of at least one sample of throw, the reflectors 3 traces
    either side are offset by the lag that throw makes (within one sample) at >= 90 % of the
    pixels: steep faults of a few samples' throw, as a survey shows them."""
    store = generate_tiny(tmp_path, survey("kinematic", "strata",
                                            "throw_m = 25\ndip_deg = [70, 80]"), "k")
    root = zarr.open_group(str(store), mode="r")
    hits = tested = 0
    for i in np.flatnonzero(params_of(root)["snapshot"] > 0):
        z = root["impedance"][i].astype(np.float64)
        vp = (np.maximum(z, 1.0) / 310.0) ** (1.0 / 1.25)        # Gardner, the default rock
        throw = root["slip_m"][i] * np.sin(np.radians(root["dip_deg"][i]))
        lags = expected_lags(root["fault"][i], throw, root["sense"][i], vp, 0.004)
        frac, n = offset_agreement(root["seismic"][i], root["fault"][i], lags)
        hits += frac * n
        tested += n
    assert tested > 50
    assert hits / tested >= 0.9


def test_strata_sections_are_laterally_continuous_but_not_flat(kin_strata, dem_strata):
    for store in (kin_strata, dem_strata):
        root = zarr.open_group(str(store), mode="r")
        i = int(np.flatnonzero(params_of(root)["snapshot"] == 0)[0])     # undeformed, 30 Hz
        sec = root["seismic"][i]
        r = adjacent_trace_correlation(sec, intact_mask(root["fault"][i]) & (sec != 0))
        assert 0.85 < r < 0.995, (store.name, r)


def test_elements_and_strata_share_labels(tmp_path):
    """The rendering changes the seismic, not the labels (in depth, where no velocity maps
    them to time)."""
    stores = [generate_tiny(tmp_path, survey("dem", r).replace('domain = "time"',
                                                               'domain = "depth"'), r)
              for r in ("elements", "strata")]
    a, b = (zarr.open_group(str(p), mode="r") for p in stores)
    assert a["seismic"].shape == b["seismic"].shape == (3, 40, 36)
    assert not np.array_equal(a["seismic"][:], b["seismic"][:])
    for name in ("fault", "damage", "fault_id", "slip_m"):
        np.testing.assert_array_equal(a[name][:], b[name][:])


@pytest.mark.slow
def test_strata_same_bytes_with_two_workers(dem_strata, tmp_path):
    cfg = tmp_path / "c.toml"
    cfg.write_text(survey("dem", "strata"))
    out = tmp_path / "two.zarr"
    assert main(["generate", str(cfg), "--preset", "tiny", "--out", str(out), "--workers", "2",
                 "--quiet"]) == 0
    assert_same_bytes(dem_strata, out)


@pytest.mark.parametrize("domain", ["depth", "time"])
def test_psf_images_the_strata_at_the_traces(tmp_path, domain):
    """The 2-D PSF on strata columns: the same shape as the 1-D section, flat reflectors
    unchanged by the dip filter (undeformed snapshot), dipping ones filtered."""
    toml = survey("kinematic", "strata", 'imaging = ["1d", "psf"]\npsf_max_angle_deg = 20')
    store = generate_tiny(tmp_path, toml.replace('domain = "time"', f'domain = "{domain}"'),
                          "p")
    root = zarr.open_group(str(store), mode="r")
    imaging = params_of(root)["imaging"]
    snap = params_of(root)["snapshot"]
    one, psf = (np.flatnonzero((imaging == k) & (snap == 0))[0] for k in (0, 1))
    a, b = root["seismic"][one], root["seismic"][psf]
    assert a.shape == b.shape and np.isfinite(b).all()
    # undeformed: reflectors are flat but for the small lateral variation of the beds, which
    # the dip filter smooths: the two images stay alike
    assert np.corrcoef(a.ravel(), b.ravel())[0, 1] > 0.9
    last = np.flatnonzero(snap == snap.max())
    c, d = (root["seismic"][i] for i in last[:2])
    assert not np.allclose(c, d)


def test_dem_block_rendering_changes_the_seismic_not_the_labels(tmp_path):
    """`block_smoothing_m`, `surface_median_m` and `velocity_median_m` change how the DEM's
    rock is drawn, not where its faults are: in depth (no velocity maps them to time) the
    label arrays keep their bytes and the impedance its values where the surface is not
    levelled."""
    base = survey("dem", "strata").replace('domain = "time"', 'domain = "depth"')
    keys = "block_smoothing_m = 100.0\nsurface_median_m = 100.0\nvelocity_median_m = 100.0\n"
    stores = [generate_tiny(tmp_path, base, "plain"),
              generate_tiny(tmp_path, base.replace("impedance = true\n",
                                                   "impedance = true\n" + keys), "blocks")]
    a, b = (zarr.open_group(str(p), mode="r") for p in stores)
    assert a["seismic"].shape == b["seismic"].shape
    assert not np.array_equal(a["seismic"][:], b["seismic"][:])
    for name in ("fault", "damage", "fault_id", "slip_m"):
        np.testing.assert_array_equal(a[name][:], b[name][:])
    i = int(np.flatnonzero(params_of(a)["snapshot"] == 0)[0])
    # the undeformed pack has moved nowhere: its smoothed displacement is zero as well, so
    # below the (levelled) surface the impedance is the same
    za, zb = a["impedance"][i], b["impedance"][i]
    np.testing.assert_allclose(zb[10:], za[10:], rtol=1e-9)
