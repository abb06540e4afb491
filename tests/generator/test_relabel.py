"""``demseis relabel``: new labels from the stored particle snapshots, same seismic bytes."""

from __future__ import annotations

import numpy as np

from demseis.cli import main


def _relabel_strain_band(src, tmp_path):
    """``demseis relabel SRC`` with the strain-band labels into ``tmp_path/l.zarr``; asserts the
    seismic bytes are SRC's and returns the two stores, opened."""
    import zarr

    dst = tmp_path / "l.zarr"
    labels = tmp_path / "old.toml"
    labels.write_text('[labels]\nmethod = "strain_band"\n')
    assert main(["relabel", str(src), "--labels", str(labels), "--out", str(dst),
                 "--quiet"]) == 0
    a, b = zarr.open(str(src), mode="r"), zarr.open(str(dst), mode="r")
    np.testing.assert_array_equal(a["seismic"][:].view(np.uint32),
                                  b["seismic"][:].view(np.uint32))
    return a, b


def test_relabel_keeps_seismic_bytes_and_changes_labels(tmp_path):
    src, dst = tmp_path / "t.zarr", tmp_path / "l.zarr"
    assert main(["generate", "--preset", "tiny", "--out", str(src), "--workers", "0",
                 "--quiet"]) == 0
    a, b = _relabel_strain_band(src, tmp_path)
    assert a["params/has_fault"][:].sum() > 0
    assert (a["slip_m"][:] > 0).any() and not (b["slip_m"][:] > 0).any()  # strain_band: no slip
    assert main(["validate", str(dst)]) == 0


def test_relabel_rejects_a_bad_labels_file(tmp_path, capsys):
    bad = tmp_path / "bad.toml"
    bad.write_text("[sweep]\nn_runs = 3\n")
    assert main(["relabel", str(tmp_path / "none.zarr"), "--labels", str(bad), "--out",
                 str(tmp_path / "o.zarr")]) == 2
    assert "only a [labels] table" in capsys.readouterr().err


def test_relabel_of_a_store_from_before_the_strata_rendering_keeps_its_seismic(tmp_path):
    """A store whose config has no [output] rendering was rendered from elements; relabelling
    it must not switch to the strata default."""
    import zarr

    from demseis.generator.config import load_config, stored_config

    cfg = tmp_path / "e.toml"
    cfg.write_text('[output]\nrendering = "elements"\n')
    src = tmp_path / "t.zarr"
    assert main(["generate", str(cfg), "--preset", "tiny", "--out", str(src), "--workers", "0",
                 "--quiet"]) == 0
    root = zarr.open_group(str(src), mode="r+")
    old = dict(root.attrs["config"])
    old["output"] = {k: v for k, v in old["output"].items() if k != "rendering"}
    root.attrs["config"] = old                     # as a store of the previous version has it
    assert stored_config(old).output.rendering == "elements"
    assert load_config(preset="tiny").output.rendering == "strata"   # the new default
    _relabel_strain_band(src, tmp_path)
