"""export-segy: segyio reads back the stored section, sample interval and coordinates."""

import numpy as np
import pytest
import segyio

from demseis.errors import InputError, StoreError
from demseis.cli import main
from demseis.datasets.read import export_segy
from demseis.seismic.segy import write_segy

from .conftest import make_store


def test_export_roundtrip(tiny_store, tmp_path):
    path, data, grid = tiny_store
    out = tmp_path / "s1.sgy"
    assert main([ "export-segy", str(path), "--sample", "1", "--out", str(out)]) == 0
    with segyio.open(str(out), ignore_geometry=True) as f:
        traces = segyio.tools.collect(f.trace[:])
        assert traces.dtype == np.float32
        np.testing.assert_array_equal(traces, data[1].T)  # identical bytes
        assert segyio.tools.dt(f) == 10000.0  # depth step 10 m stored in mm
        np.testing.assert_allclose(f.samples, 5.0 + 10.0 * np.arange(grid["nz"]))
        xs = np.array([h[segyio.TraceField.CDP_X] for h in f.header]) / 100.0
        np.testing.assert_allclose(xs, 100.0 + 10.0 * (np.arange(grid["nx"]) + 0.5))
        assert all(h[segyio.TraceField.SourceGroupScalar] == -100 for h in f.header)
        assert [h[segyio.TraceField.CDP] for h in f.header] == list(range(1, grid["nx"] + 1))
        assert f.bin[segyio.BinField.Format] == 5
        assert b"DEPTH DOMAIN" in f.text[0]


def test_time_domain_interval(tmp_path):
    sec = np.random.default_rng(0).standard_normal((50, 4)).astype(np.float32)
    out = write_segy(sec, tmp_path / "t.sgy", x0_m=0.0, cell_m=10.0, top_m=0.0, domain="time",
                     dt_s=0.002)
    with segyio.open(str(out), ignore_geometry=True) as f:
        assert segyio.tools.dt(f) == 2000.0
        np.testing.assert_array_equal(segyio.tools.collect(f.trace[:]), sec.T)


def test_export_errors(tiny_store, tmp_path, capsys):
    path, data, grid = tiny_store
    out = tmp_path / "x.sgy"
    with pytest.raises(InputError, match="out of range"):
        export_segy(path, 3, out)
    with pytest.raises(StoreError, match="never written"):
        export_segy(path, 2, out)
    with pytest.raises(StoreError, match="does not exist"):
        export_segy(tmp_path / "nope.zarr", 0, out)
    assert not out.exists()
    export_segy(path, 0, out)
    before = out.read_bytes()
    assert main(["export-segy", str(path), "--sample", "1", "--out", str(out)]) == 2
    assert "exists" in capsys.readouterr().err
    assert out.read_bytes() == before  # nothing written is lost
    assert main(["export-segy", str(path), "--sample", "1", "--out", str(out),
                 "--overwrite"]) == 0
    foreign = make_store(tmp_path / "foreign.zarr", data, grid, schema_version=99)
    with pytest.raises(StoreError, match="schema version"):
        export_segy(foreign, 0, tmp_path / "y.sgy")


def test_text_header_cards_do_not_overflow(tmp_path):
    """40 cards of 80 characters, each starting "C<nn> "; no line runs into the next card."""
    sec = np.zeros((20, 3), np.float32)
    out = write_segy(sec, tmp_path / "c.sgy", x0_m=0.0, cell_m=10.0, top_m=0.0,
                     note="a note " * 20)
    with segyio.open(str(out), ignore_geometry=True) as f:
        text = bytes(f.text[0]).decode("ascii", "replace")
    assert len(text) == 3200
    cards = [text[i:i + 80] for i in range(0, 3200, 80)]
    for k, card in enumerate(cards, start=1):
        assert card.startswith(f"C{k:2d} "), (k, card)
    assert any("CDP = CROSSLINE = COLUMN + 1" in c for c in cards)
    assert any("SCALAR -100" in c for c in cards)
