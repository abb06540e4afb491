"""Extension points, proven from outside the package: a toy engine, a toy imaging mode and a toy
label array, each registered here (no package file names them), go through ``generate`` ->
``validate`` -> the torch Dataset."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest
import zarr
from scipy import ndimage

import demseis
from demseis.datasets import FaultSegDataset, validate_store
from demseis.errors import ConfigError
from demseis.generator.config.settings import load_config, parse_config
from demseis.generator.engines import Engine, State, get_engine
from demseis.generator.sweep.rerender import rerender
from demseis.registry import ENGINES, IMAGING
from demseis.schema import SAMPLE_ARRAYS, SampleArray, register_array, stored_arrays
from demseis.seismic import ImagingMode, synthetic_sections
from tests.generator._flat import FlatEngine


def tiny(**model: Any) -> dict[str, Any]:
    raw = load_config(preset="tiny").to_dict()
    raw["model"].update(model)
    return raw


@pytest.fixture
def flat_engine():
    engine = FlatEngine()
    with ENGINES.registered("flat", engine):
        yield engine
    assert "flat" not in ENGINES


def test_a_registered_engine_goes_from_generate_to_the_dataset(tmp_path, flat_engine):
    assert isinstance(flat_engine, Engine)
    with pytest.raises(ConfigError, match="flat engine"):   # its own check runs at load
        parse_config(tiny(engine="flat", width_m=400.0))
    out = tmp_path / "flat.zarr"
    store = demseis.generate(tiny(engine="flat"), out=out, workers=0, progress=False)
    assert sorted(flat_engine.simulated) == [0, 1, 2]
    assert validate_store(out).ok
    ds = FaultSegDataset(out, targets=("fault", "layer"))
    x, y = ds[3]
    assert x.shape == (1, *store.layout.shape)
    assert int(y["fault"].sum()) == 0                           # no faulting, no fault label
    assert np.array_equal(y["layer"].numpy()[:, 0], np.arange(store.layout.shape[0]) // 5)
    # the beds are imaged: flat reflectors, nearly the same in every column (the strata's
    # beds vary a little along their length)
    sec = np.asarray(store.sample(0)["seismic"])
    assert np.abs(sec).max() > 0
    assert np.corrcoef(sec[:, 0], sec[:, -1])[0, 1] > 0.8
    # an engine without a reference map renders only elements, and says so
    class NoMap(FlatEngine):
        strata = False

        def states(self, cfg, run, snapshots):
            for s in super().states(cfg, run, snapshots):
                yield State(s.snapshot, s.vp_m_s, s.rho_kg_m3, s.labels, s.values)
    with ENGINES.registered("nomap", NoMap()):
        with pytest.raises(ConfigError, match="rendering = 'elements'"):
            parse_config(tiny(engine="nomap"))
        raw = tiny(engine="nomap")
        raw["output"]["rendering"] = "elements"
        flat = demseis.generate(raw, out=tmp_path / "e.zarr", workers=0, progress=False)
        sec = np.asarray(flat.sample(0)["seismic"])
        assert np.abs(sec).max() > 0 and np.allclose(sec, sec[:, :1], atol=1e-6)
    # no particles: commands that need them refuse in one line naming the engine
    with pytest.raises(demseis.DemseisError, match="'flat'"):
        rerender(out, tmp_path / "r.zarr", freqs_hz=[20.0], snrs_db=[np.inf], noise_kind="white",
                 progress=False)


def test_unknown_engine_is_a_config_error_listing_the_engines():
    with pytest.raises(ConfigError, match="kinematic"):
        parse_config(tiny(engine="nonesuch"))
    with pytest.raises(demseis.DemseisError, match="'dem', 'kinematic'"):
        get_engine("nonesuch")


def _negated(vp_g, rho_g, cell_m, freqs_hz, domain="depth", *, t_s=None, **grid):
    # ``grid``: col_step_m and rows_per_cell, which the strata rendering passes
    return -synthetic_sections(vp_g, rho_g, cell_m, freqs_hz, domain, t_s=t_s, **grid)


def test_a_registered_imaging_mode_goes_from_generate_to_the_dataset(tmp_path):
    raw = tiny(engine="kinematic")
    raw["sweep"]["snr_db"] = "inf"
    one_d = demseis.generate(raw, out=tmp_path / "1d.zarr", workers=0, progress=False)
    with IMAGING.registered("negated", ImagingMode(_negated, title=lambda v: "negated")):
        raw["sweep"]["imaging"] = ["1d", "negated"]
        out = tmp_path / "neg.zarr"
        store = demseis.generate(raw, out=out, workers=0, progress=False)
        assert validate_store(out).ok
        names = np.asarray(store.params["imaging"])
        assert set(names.tolist()) == {"1d", "negated"}
        assert store.attrs["param_codes"]["imaging"] == ["1d", "psf", "negated"]
        ds = FaultSegDataset(out)
        neg = np.flatnonzero(names == "negated")
        x, _ = ds[neg[0]]
        # the same snapshot imaged in 1-D by the plain store, negated here
        row = {k: store.params[k][neg[0]] for k in ("run_id", "snapshot")}
        twin = next(i for i in range(len(one_d)) if all(one_d.params[k][i] == v
                                                          for k, v in row.items()))
        np.testing.assert_allclose(x.numpy()[0], -np.asarray(one_d.sample(twin)["seismic"]),
                                   atol=1e-6)
    with pytest.raises(ConfigError, match="imaging"):     # gone with its registration
        parse_config(raw)


def _fault_wide(state: State) -> np.ndarray:
    """The fault label grown by one cell (4-neighbourhood), from the engine's own label."""
    return ndimage.binary_dilation(state.labels["fault"]).astype(np.uint8)


def test_a_registered_label_array_goes_from_generate_to_the_dataset(tmp_path):
    spec = SampleArray("fault_wide", "uint8", "label", "1", "fault label grown by one cell",
                       fill=0, valid_range=(0, 1), producer=_fault_wide)
    with SAMPLE_ARRAYS.registered("fault_wide", spec):
        assert stored_arrays()[-1] == "fault_wide"
        for engine in ("kinematic", "dem"):
            out = tmp_path / f"{engine}.zarr"
            raw = tiny(engine=engine)
            # the producer reads the engine's trace label: store it as it is (not re-picked)
            raw["labels"]["fault_style"] = "traces"
            store = demseis.generate(raw, out=out, workers=0)
            assert validate_store(out).ok
            ds = FaultSegDataset(out, targets=("fault", "fault_wide"))
            faulted = [i for i in range(len(ds)) if store.params["has_fault"][i]]
            assert faulted, engine
            for i in faulted:
                _, y = ds[i]
                fault, wide = y["fault"].numpy(), y["fault_wide"].numpy()
                expect = ndimage.binary_dilation(fault).astype(np.uint8)
                np.testing.assert_array_equal(wide, expect)    # made from the same state
                assert wide.sum() > fault.sum()
            root = zarr.open_group(str(out), mode="r")
            assert root["fault_wide"].attrs["long_name"] == "fault label grown by one cell"
    assert "fault_wide" not in stored_arrays()
    with pytest.raises(demseis.DemseisError, match="producer"):
        register_array(SampleArray("orphan", "uint8", "label", "1", "no producer"))


@pytest.mark.slow
def test_an_engine_declares_its_own_run_parameters(flat_engine):
    """The flat engine's ``bed_cells``: a [sweep] key of its configs only, drawn per run after
    the declared parameters (which keep their values), typed on the run's parameters, a column
    of its store; a declaration that breaks the rules is one error naming it."""
    import dataclasses

    from demseis.generator.config.layout import param_dtypes
    from demseis.generator.config.sampling import run_params
    from demseis.parameters import Param

    with pytest.raises(ConfigError, match="sweep.bed_cells: unknown key"):
        parse_config({**tiny(), "sweep": {"bed_cells": 4}})             # not a DEM key
    raw = tiny(engine="flat")
    raw["sweep"].update(dip_deg={"dist": "uniform", "low": 20, "high": 70})
    plain = parse_config(raw)
    raw["sweep"]["bed_cells"] = {"dist": "uniform", "low": 2, "high": 9}
    cfg = parse_config(raw)
    for run in range(4):
        p, q = run_params(plain, run), run_params(cfg, run)
        assert q.dip_deg == p.dip_deg                           # drawn after the declared ones
        assert (p.bed_cells, p["bed_cells"]) == (5, 5)          # the default
        assert isinstance(q.bed_cells, int) and 2 <= q.bed_cells <= 9
        assert dict(q)["bed_cells"] == q.bed_cells and q.replace(bed_cells=7).bed_cells == 7
    assert len({run_params(cfg, r).bed_cells for r in range(12)}) > 1
    assert list(param_dtypes(cfg))[-1] == "bed_cells" and param_dtypes(cfg)["bed_cells"] == "int32"
    with pytest.raises(ConfigError, match=r"sweep.bed_cells = 30 is not allowed.*\[2, 20\]"):
        parse_config({**raw, "sweep": {"bed_cells": 30}})
    bad = [(dataclasses.replace(flat_engine.parameters[0], name="dip_deg"), "name of another"),
           (dataclasses.replace(flat_engine.parameters[0], level="sample"), "run-level"),
           (Param("flat_kind", str, "run", "a", choices=("a", "b")), "integer code"),
           ("bed_cells", "is not a demseis.parameters.Param")]
    for decl, message in bad:
        class Bad(FlatEngine):
            parameters = (decl,)
        with ENGINES.registered("bad", Bad()):
            with pytest.raises(ConfigError, match=f"engine 'bad' declares parameter .*{message}"):
                parse_config(tiny(engine="bad"))


def test_a_plugin_named_in_the_config_reaches_the_dask_workers(tmp_path):
    """issue 36: a user's module named in the config (``plugins``, and an engine given as
    ``"module:attribute"``) is imported by every dask worker (2 workers, so no run is made in
    the driver): the runs use the toy engine, with the run-level parameter it declares, and
    store the toy label array."""
    import subprocess
    import sys

    from tests._helpers import ROOT

    cfg = tmp_path / "p.toml"
    cfg.write_text('plugins = ["tests.generator._plugin"]\n[sweep]\nn_runs = 4\n'
                   'bed_cells = [3, 6]\n[model]\nengine = "tests.generator._plugin:FLAT"\n')
    out = tmp_path / "p.zarr"
    run = subprocess.run([sys.executable, "-m", "demseis", "generate", str(cfg), "--preset",
                          "tiny", "--out", str(out), "--workers", "2", "--quiet"], cwd=ROOT,
                         capture_output=True, text=True, timeout=600)
    assert run.returncode == 0, run.stderr[-3000:]
    root = zarr.open_group(str(out), mode="r")
    assert root["shard_done"][:].all()
    layer, parity = root["layer"][:], root["layer_parity"][:]
    # the flat engine's beds, as thick as its own parameter says (a list: cycled over the
    # runs), which the store keeps as a column, and the plug-in's label made from them
    from demseis.datasets import read_params

    params = read_params(out)
    assert np.array_equal(params["bed_cells"], np.where(params["run_id"] % 2 == 0, 3, 6))
    cells = params["bed_cells"][:, None]
    assert np.array_equal(layer[:, :, 0], np.arange(layer.shape[1])[None, :] // cells)
    np.testing.assert_array_equal(parity, ((layer >= 0) & (layer % 2 == 1)).astype(np.uint8))
    assert "layer_parity" not in SAMPLE_ARRAYS       # this process never imported the plug-in
    assert root.attrs["config"]["plugins"] == ["tests.generator._plugin"]
    # the store describes the plug-in's array: it reads and validates without the plug-in
    from demseis.datasets import read_layout, validate_store

    spec = read_layout(out).specs["layer_parity"]
    assert (spec.role, spec.valid_range, spec.description) == ("label", (0, 1), "1 on odd layers")
    assert validate_store(out).ok


def test_a_module_attribute_engine_and_bad_plugins_are_config_errors():
    with pytest.raises(ConfigError, match=r"model\.engine.*cannot import 'nonesuch_mod'"):
        parse_config(tiny(engine="nonesuch_mod:ENGINE"))
    with pytest.raises(ConfigError, match=r"model\.engine.*has no 'NOPE'"):
        parse_config(tiny(engine="tests.generator._flat:NOPE"))
    with pytest.raises(ConfigError, match="plugins.*cannot import 'nonesuch_mod'"):
        parse_config({**tiny(), "plugins": ["nonesuch_mod"]})
    with pytest.raises(ConfigError, match="expected a list of module names"):
        parse_config({**tiny(), "plugins": "tests.generator._flat"})


def test_a_registered_rendering_and_fault_style_go_from_generate_to_the_store(tmp_path):
    """issue 36 item 4: a rendering and a fault style are one registration each. The toy
    rendering images the elements rendering's columns with Vp scaled (density kept), and the
    toy style draws no fault."""
    from demseis.generator.render.section import ELEMENTS, FaultStyle, Rendering
    from demseis.registry import FAULT_STYLES, RENDERINGS

    def faster(cfg, state, maps, params):
        img = ELEMENTS.columns(cfg, state, maps, params)
        return type(img)(img.vp * 1.5, img.rho, img.dz_m, img.col_step_m, img.substeps,
                         img.vp_cell * 1.5, img.impedance * 1.5)

    def no_fault(cfg, maps, vp, jump):
        return {**maps, "fault": np.zeros_like(maps["fault"])}

    raw = tiny(engine="kinematic")
    raw["sweep"]["snr_db"] = "inf"
    raw["output"]["rendering"] = "elements"
    raw["output"]["impedance"] = True
    plain = demseis.generate(raw, out=tmp_path / "plain.zarr", workers=0, progress=False)
    with RENDERINGS.registered("faster", Rendering(faster)), \
            FAULT_STYLES.registered("none", FaultStyle(no_fault)):
        raw["output"]["rendering"] = "faster"
        raw["labels"]["fault_style"] = "none"
        store = demseis.generate(raw, out=tmp_path / "fast.zarr", workers=0, progress=False)
        assert validate_store(tmp_path / "fast.zarr").ok
        # a rendering without the reference map cannot feed the offset throws
        raw["labels"].update(fault_style="picks", throw_from="offset")
        with pytest.raises(ConfigError, match="rendering = 'faster' has not"):
            parse_config(raw)
    a, b = np.asarray(plain.sample(0)["impedance"]), np.asarray(store.sample(0)["impedance"])
    np.testing.assert_allclose(b, 1.5 * a, rtol=1e-5)
    faults = [zarr.open_group(str(tmp_path / f"{n}.zarr"), mode="r")["fault"][:]
              for n in ("plain", "fast")]
    assert faults[0].any() and not faults[1].any()
    with pytest.raises(ConfigError, match="rendering"):       # gone with its registration
        parse_config({**raw, "labels": {}})


def test_a_registered_label_method_goes_from_generate_to_the_store(tmp_path):
    """issue 36 item 4: a label method is one registration: the toy method is the strain band
    without its damage zone; the DEM's runs are labelled by it."""
    from demseis.labels.maps import STRAIN_BAND, LabelMethod
    from demseis.registry import LABEL_METHODS

    def no_damage(raster, cfg, displacement):
        targets = STRAIN_BAND.targets(raster, cfg, displacement)
        return {**targets, "damage": (targets["damage"] == 2).astype(np.uint8) * 2}

    raw = tiny(engine="dem")
    raw["sweep"]["n_runs"] = 1
    raw["labels"].update(method="strain_band", fault_style="traces")
    demseis.generate(raw, out=tmp_path / "band.zarr", workers=0, progress=False)
    with LABEL_METHODS.registered("no_damage", LabelMethod(no_damage)):
        raw["labels"]["method"] = "no_damage"
        demseis.generate(raw, out=tmp_path / "toy.zarr", workers=0, progress=False)
    band, toy = (zarr.open_group(str(tmp_path / f"{n}.zarr"), mode="r") for n in ("band", "toy"))
    assert np.isin(band["damage"][:], [1]).any() and not np.isin(toy["damage"][:], [1]).any()
    np.testing.assert_array_equal(toy["fault"][:], band["fault"][:])
    np.testing.assert_array_equal(toy["damage"][:] == 2, band["damage"][:] == 2)
    with pytest.raises(ConfigError, match="labels.method"):      # gone with its registration
        parse_config(raw)
