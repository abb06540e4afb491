"""``demseis relabel``: new labels from the stored particle snapshots, same seismic bytes."""

from __future__ import annotations

import numpy as np

from demseis.cli import main
from tests._helpers import params_of


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


def _store_of_a_previous_version(tmp_path, toml: str, section: str, key: str):
    """A ``tiny`` store generated with ``toml`` whose stored config then loses
    ``[section] key``, as a store written before that key existed has it; returns its path and
    that config."""
    import zarr

    cfg = tmp_path / "cfg.toml"
    cfg.write_text(toml)
    src = tmp_path / "t.zarr"
    assert main(["generate", str(cfg), "--preset", "tiny", "--out", str(src), "--workers", "0",
                 "--quiet"]) == 0
    root = zarr.open_group(str(src), mode="r+")
    old = dict(root.attrs["config"])
    old[section] = {k: v for k, v in old[section].items() if k != key}
    root.attrs["config"] = old
    return src, old


def test_relabel_keeps_seismic_bytes_and_changes_labels(tmp_path):
    src, dst = tmp_path / "t.zarr", tmp_path / "l.zarr"
    assert main(["generate", "--preset", "tiny", "--out", str(src), "--workers", "0",
                 "--quiet"]) == 0
    a, b = _relabel_strain_band(src, tmp_path)
    assert params_of(a)["has_fault"].sum() > 0
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
    from demseis.generator.config.settings import load_config, stored_config

    src, old = _store_of_a_previous_version(tmp_path, '[output]\nrendering = "elements"\n',
                                            "output", "rendering")
    assert stored_config(old).output.rendering == "elements"
    assert load_config(preset="tiny").output.rendering == "strata"   # the new default
    _relabel_strain_band(src, tmp_path)


def test_a_store_from_before_the_picks_keeps_its_traces_and_relabel_picks_them(tmp_path):
    """A store whose config has no [labels] fault_style drew its faults as traces: rendering
    it again keeps them; ``relabel`` with an empty [labels] table draws them as picks."""
    import zarr

    from demseis.generator.config.settings import stored_config
    from demseis.generator.sweep.rerender import rerender

    src, old = _store_of_a_previous_version(
        tmp_path, '[labels]\nfault_style = "traces"\nthickness_cells = 3.0\n', "labels",
        "fault_style")
    assert stored_config(old).labels.fault_style == "traces"
    again = tmp_path / "again.zarr"
    rerender(src, again, freqs_hz=[30.0], snrs_db=[float("inf")], progress=False)
    a, b = zarr.open(str(src), mode="r"), zarr.open(str(again), mode="r")
    key = lambda g, i: (int(params_of(g)["run_id"][i]), int(params_of(g)["snapshot"][i]))  # noqa: E731
    first = {}
    for i in range(a["fault"].shape[0]):
        first.setdefault(key(a, i), i)
    for j in range(b["fault"].shape[0]):                          # still traces
        np.testing.assert_array_equal(a["fault"][first[key(b, j)]], b["fault"][j])
    empty = tmp_path / "empty.toml"
    empty.write_text("[labels]\n")
    dst = tmp_path / "p.zarr"
    assert main(["relabel", str(src), "--labels", str(empty), "--out", str(dst),
                 "--quiet"]) == 0
    c = zarr.open(str(dst), mode="r")
    np.testing.assert_array_equal(a["seismic"][:].view(np.uint32),
                                  c["seismic"][:].view(np.uint32))
    thick, thin = a["fault"][:], c["fault"][:]
    assert thin.sum() > 0 and thin.sum() < 0.6 * thick.sum()        # 3-cell bands -> lines
    assert c.attrs["config"]["labels"]["fault_style"] == "picks"
