"""`validate_store` and `demseis validate`: clean stores pass, each kind of damage is reported."""

from __future__ import annotations

import json
import shutil

import numpy as np
import pytest
import zarr

from demseis.cli import main
from demseis.datasets import SCHEMA_VERSION, open_store, record_failures, validate_store
from tests.datasets._helpers import make_store, set_param


@pytest.fixture(scope="module")
def pristine(tmp_path_factory):
    """A complete 4-shard store, copied by the tests that damage it."""
    return make_store(tmp_path_factory.mktemp("pristine") / "s.zarr")


def _copy(src, dst):
    shutil.copytree(src, dst)
    return dst


def _raw_group(path):
    return zarr.open_group(path, mode="r+", use_consolidated=False)


def test_clean_store_passes_and_pending_shards_are_not_problems(tmp_path, capsys):
    path = make_store(tmp_path / "s.zarr", write=[0, 1, 3])
    record_failures(path, {2: "SimulationError: kinetic energy blow-up"})
    report = validate_store(path)
    assert report.ok, report.problems
    assert (report.n_shards, report.n_done, report.n_samples_checked) == (4, 3, 18)
    assert report.failures == {"2": "SimulationError: kinetic energy blow-up"}
    assert main(["validate", str(path)]) == 0
    out = capsys.readouterr().out.strip().splitlines()
    assert len(out) == 1 and "3/4 shards done" in out[0] and "ok" in out[0]


@pytest.mark.parametrize(
    "damage, expected",
    [
        (lambda p: _raw_group(p)["seismic"].__setitem__((7, 3, 4), np.nan), "shard 1: seismic has 1 NaN"),
        (lambda p: _raw_group(p)["strain"].__setitem__((0, 0, 0), np.inf), "shard 0: strain has 1 NaN/inf"),
        (lambda p: _raw_group(p)["fault"].__setitem__((13, 2, 2), 3), "shard 2: fault has values 3 outside"),
        (lambda p: _raw_group(p)["damage"].__setitem__((1, 0, 0), 7), "shard 0: damage has values 7"),
        (lambda p: _raw_group(p)["layer"].__setitem__((19, 0, 0), -5), "shard 3: layer has values -5"),
        (lambda p: set_param(p, "freq_hz", 2, np.nan), "shard 0: parameter freq_hz has NaN"),
        (lambda p: set_param(p, "freq_hz", 2, np.inf), "parameter freq_hz has infinite"),
        (lambda p: set_param(p, "run_id", 5, 1), "shard 0: run_id is not constant \\(0, 1\\)"),
        (lambda p: set_param(p, "run_id", slice(6, 12), 0), "shards 0 and 1 share run_id 0"),
        (lambda p: set_param(p, "snapshot", 6, 9), "snapshot reaches 9 but run 1 stores 3"),
        (lambda p: _raw_group(p)["shard_done"].__setitem__(0, 2), "shard_done holds values other than 0/1"),
    ],
)
def test_damage_is_reported(tmp_path, capsys, pristine, damage, expected):
    path = _copy(pristine, tmp_path / "s.zarr")
    damage(path)
    report = validate_store(path)
    assert not report.ok
    assert any(__import__("re").search(expected, p) for p in report.problems), report.problems
    assert main(["validate", str(path)]) == 1
    out = capsys.readouterr().out
    n = len(report.problems)
    assert out.splitlines()[-1].endswith(f", {n} problem{'' if n == 1 else 's'}")


def test_done_flag_on_never_written_shard(tmp_path):
    path = make_store(tmp_path / "s.zarr", write=[0])
    _raw_group(path)["shard_done"][2] = 1
    problems = validate_store(path).problems
    text = "\n".join(problems)
    assert "shard 2: seismic samples 12..17 were never written" in text
    assert "shard 2: fault samples 12..17 were never written" in text
    assert "shard 2: parameters of samples 12..17 were never written" in text


def test_truncated_shard_file_is_reported(tmp_path, pristine):
    path = _copy(pristine, tmp_path / "s.zarr")
    shard_file = path / "seismic" / "c" / "1" / "0" / "0"
    shard_file.write_bytes(shard_file.read_bytes()[:1000])
    problems = validate_store(path).problems
    assert any(p.startswith("shard 1: seismic") for p in problems), problems


def test_missing_root_attrs_reported(tmp_path):
    path = make_store(tmp_path / "s.zarr", write=[])
    g = _raw_group(path)
    attrs = dict(g.attrs)
    attrs.pop("config")
    attrs["grid"] = {**attrs["grid"], "nz": 99}
    g.attrs.put(attrs)
    text = "\n".join(validate_store(path).problems)
    assert "'config'" in text and "nz, nx = (99, 32)" in text


def test_cli_exit_2_for_missing_foreign_or_other_version(tmp_path, capsys):
    assert main(["validate", str(tmp_path / "nope.zarr")]) == 2
    zarr.create_group(tmp_path / "foreign.zarr")
    assert main(["validate", str(tmp_path / "foreign.zarr")]) == 2
    path = make_store(tmp_path / "s.zarr", n_shards=1, s=1, shape=(2, 2))
    meta = json.loads((path / "zarr.json").read_text())
    meta["attributes"]["demseis"]["schema_version"] = SCHEMA_VERSION + 1
    (path / "zarr.json").write_text(json.dumps(meta))
    assert main(["validate", str(path)]) == 2
    err = capsys.readouterr().err.splitlines()
    assert len(err) == 3 and all(line.startswith("demseis: error: ") for line in err)
    assert "does not exist" in err[0] and "not written by demseis" in err[1]
    assert f"reads schema version {SCHEMA_VERSION}" in err[2]


def test_open_store_after_validate_is_read_only_safe(tmp_path):
    path = make_store(tmp_path / "s.zarr", write=[0])
    before = (path / "zarr.json").read_bytes()
    validate_store(path)
    assert (path / "zarr.json").read_bytes() == before
    assert open_store(path)["shard_done"][0] == 1
