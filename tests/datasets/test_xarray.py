"""The store is xarray-native: open_datatree opens every group; to_xarray has coordinates in
metres (or seconds), units, long names and categorical parameters as strings."""

from __future__ import annotations

import sys

import numpy as np
import pytest

xr = pytest.importorskip("xarray")

import zarr  # noqa: E402

from demseis.datasets import ParamSpec, to_xarray  # noqa: E402
from demseis.datasets.create import UNIT_SUFFIXES, units_of  # noqa: E402
from demseis.errors import DemseisError  # noqa: E402
from demseis.parameters import PARAMS as PARAMETERS  # noqa: E402
from demseis.parameters import SCENARIO, STORED  # noqa: E402
from tests.datasets._helpers import PARAMS, make_store, mini_config  # noqa: E402


@pytest.fixture(scope="module", params=["depth", "time"])
def generated(request, tmp_path_factory):
    from demseis.generator.sweep.driver import run_sweep  # the generator loads numba: only here

    cfg = mini_config(request.param)
    out = tmp_path_factory.mktemp(request.param) / "g.zarr"
    summary = run_sweep(cfg, out, workers=0, progress=False)
    assert not summary.failed
    return cfg, out


def _all_groups(path):
    root = zarr.open_group(path, mode="r")
    return {"/"} | {"/" + name for name, _ in root.groups()} | {
        "/" + f"particles/{name}" for name, _ in root["particles"].groups()}


def test_open_datatree_opens_every_group(generated):
    _, out = generated
    for consolidated in (None, False):  # the finalized store's consolidated metadata, the files
        tree = xr.open_datatree(out, engine="zarr", consolidated=consolidated)
        assert {node.path for node in tree.subtree} == _all_groups(out)
    for node in tree.subtree:
        for name, var in node.dataset.variables.items():
            assert "units" in var.attrs and "long_name" in var.attrs, (node.path, name)
    run = tree["particles/run_00000"]
    assert run["x_m"].dims == ("element",) and run["x_m"].attrs["units"] == "m"
    assert run["throw_m"].dims == ("snapshot",)


def test_to_xarray_coordinates_units_and_categories(generated):
    from demseis.generator.config.layout import grid_of, time_axis_of  # loads numba: only here

    cfg, out = generated
    ds = to_xarray(out)
    grid = grid_of(cfg)
    row = "twt" if cfg.output.domain == "time" else "depth"
    assert ds["seismic"].dims == ("sample", row, "x")
    # every stored sample array is a data variable (per-pixel dip_deg as fault_dip_deg, since the
    # per-sample parameter dip_deg is a coordinate)
    stored = {k for k, a in zarr.open_group(str(out), mode="r").arrays() if a.ndim == 3}
    assert {("fault_" + k if k == "dip_deg" else k) for k in stored} <= set(ds.data_vars)
    assert ds["dip_deg"].dims == ("sample",)
    np.testing.assert_allclose(ds["x"].values, grid.x_centres())
    assert ds["x"].attrs["units"] == "m"
    if row == "twt":
        np.testing.assert_allclose(ds["twt"].values, time_axis_of(cfg))
        assert ds["twt"].attrs["units"] == "s"
    else:  # depth below the top of the grid: top_m - y of the row centres
        np.testing.assert_allclose(ds["depth"].values, grid.top_m - grid.y_centres())
        assert ds["depth"].attrs["units"] == "m"
    units = {name: ds[name].attrs["units"] for name in ds.variables}
    assert units["impedance"] == "kg/(m^2 s)" and units["seismic"] == "1"
    assert units["throw_m"] == "m" and units["dip_deg"] == "deg"
    assert units["freq_hz"] == "Hz" and units["snr_db"] == "dB"
    assert units["density_kg_m3"] == "kg/m^3" and units["kn_n_m"] == "N/m"
    assert all(ds[name].attrs["long_name"] for name in ds.variables)
    declared = {k: p.unit or "1" for k, p in SCENARIO.items()}
    declared.update({p.name: p.unit or "1" for p in STORED})
    assert {k: units[k] for k in declared} == declared  # the declarations, one place per fact
    assert set(ds["noise_kind"].values.tolist()) == {"band"}
    assert set(ds["dip_direction"].values.tolist()) <= {"right", "left"}
    assert set(ds["contact_model"].values.tolist()) <= {"frictional", "bonded"}
    assert bool(ds["done"].all())
    # the data are the store's
    root = zarr.open_group(out, mode="r")
    np.testing.assert_array_equal(ds["fault"].values, root["fault"][...])
    assert ds.sel(x=ds["x"][3])["seismic"].shape[0] == root["seismic"].shape[0]


def test_handmade_store_and_pending_samples(tmp_path):
    params = {**PARAMS, "noise_kind": ParamSpec("int8", categories=("white", "band"))}
    path = make_store(tmp_path / "s.zarr", n_shards=2, s=4, shape=(6, 5), write=[1],
                      params=params)
    ds = to_xarray(path)
    assert ds["done"].values.tolist() == [False] * 4 + [True] * 4
    assert ds["noise_kind"].values.tolist()[4:] == ["white", "band", "white", "band"]
    np.testing.assert_allclose(ds["depth"].values, 5.0 + 10.0 * np.arange(6))
    np.testing.assert_allclose(ds["x"].values, 5.0 + 10.0 * np.arange(5))
    assert ds["noise_kind"].attrs["categories"] == ["white", "band"]


def test_missing_xarray_names_the_extra(tmp_path, monkeypatch):
    path = make_store(tmp_path / "s.zarr", n_shards=1, s=1, shape=(2, 2))
    monkeypatch.setitem(sys.modules, "xarray", None)  # import xarray now raises ImportError
    with pytest.raises(DemseisError, match=r"pip install 'demseis\[xarray\]'"):
        to_xarray(path)



def test_units_from_names_agree_with_the_declarations():
    """A parameter given without units gets them from its name: the same as declared."""
    declared = {k: p.unit for k, p in PARAMETERS.items()} | {p.name: p.unit for p in STORED}
    checked = 0
    for name, unit in declared.items():
        if any(name.endswith(suffix) for suffix, _ in UNIT_SUFFIXES):
            assert units_of(name) == unit, name
            checked += 1
    assert checked >= 10
