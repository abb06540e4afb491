"""``demseis realism``: a store beside a SEG-Y section, written as JSON, Markdown and PNG;
bad input exits 2 with one line."""

from __future__ import annotations

import json

import numpy as np
import pytest

from demseis.cli import main


@pytest.fixture(scope="module")
def section_sgy(tiny_store, tmp_path_factory):
    """Sample 4 of the tiny store written by the package's SEG-Y writer."""
    from demseis.datasets.read import export_segy

    return export_segy(tiny_store, 4, tmp_path_factory.mktemp("sgy") / "s4.sgy")


def test_realism_writes_table_json_markdown_and_figure(tiny_store, section_sgy, tmp_path, capsys):
    from demseis.datasets import read_sample
    from demseis.evaluation.realism_report import section_measures

    out = tmp_path / "out"
    assert main(["realism", str(tiny_store), "--field", str(section_sgy), "--out", str(out),
                 "--max-samples", "4", "--credit", "data: CC0"]) == 0
    printed = capsys.readouterr().out
    assert "adjacent-trace correlation" in printed and "81-88, median 85" in printed
    report = json.loads((out / "realism.json").read_text())
    # the field column is the written section, measured as a section
    want = section_measures(read_sample(tiny_store, 4, ("seismic",)).arrays["seismic"])
    for key, value in want["measures"].items():
        assert report["field"]["measures"][key] == pytest.approx(value, rel=1e-5), key
    assert report["field"]["shape"] == list(report["store"]["shape"])
    assert len(report["store"]["label_samples"]) == 4
    md = (out / "realism.md").read_text()
    assert "| measure | store | field section | target |" in md
    assert (out / "realism.png").stat().st_size > 20_000


def test_realism_without_field_prints_dashes(tiny_store, capsys):
    assert main(["realism", str(tiny_store), "--max-samples", "2"]) == 0
    lines = capsys.readouterr().out.splitlines()
    row = next(line for line in lines if line.startswith("zero crossings"))
    assert " - " in row and not any(line.startswith("wrote") for line in lines)


@pytest.mark.parametrize("case", ["missing_store", "file_store", "missing_field", "bad_field"])
def test_bad_input_exits_2_with_one_line(case, tiny_store, tmp_path, capsys):
    bad = tmp_path / "bad.sgy"
    bad.write_bytes(np.arange(1000, dtype=np.uint8).tobytes())
    args = {"missing_store": [str(tmp_path / "none.zarr")],
            "file_store": [str(bad)],
            "missing_field": [str(tiny_store), "--field", str(tmp_path / "none.sgy")],
            "bad_field": [str(tiny_store), "--field", str(bad)]}[case]
    assert main(["realism", *args]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and err.startswith("demseis: error:"), err


def test_max_samples_must_be_positive(tiny_store, capsys):
    with pytest.raises(SystemExit) as exc:
        main(["realism", str(tiny_store), "--max-samples", "0"])
    assert exc.value.code == 2 and "'0' must be >= 1" in capsys.readouterr().err
