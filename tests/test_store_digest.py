"""benchmarks/store_digest.py: the same store bytes give the same digest, a changed byte does not."""

from __future__ import annotations

import json
import runpy
import shutil
from pathlib import Path

import pytest

DIGEST = Path(__file__).resolve().parents[1] / "benchmarks" / "store_digest.py"


def test_digest_follows_the_bytes(tiny_store, tmp_path, capsys):
    main = runpy.run_path(str(DIGEST))["main"]
    copy = tmp_path / "copy.zarr"
    shutil.copytree(tiny_store, copy)
    (copy / ".some.lock").write_text("held")  # hidden files are not the store's bytes
    outs = []
    for store in (tiny_store, copy):
        assert main([str(store)]) == 0
        outs.append(json.loads(capsys.readouterr().out))
    assert outs[0]["sha256"] == outs[1]["sha256"] and outs[0]["files"] == outs[1]["files"]
    chunk = next(p for p in sorted((copy / "seismic").rglob("*")) if p.is_file() and p.name != "zarr.json")
    data = bytearray(chunk.read_bytes())
    data[-1] ^= 1
    chunk.write_bytes(bytes(data))
    assert main([str(copy)]) == 0
    changed = json.loads(capsys.readouterr().out)
    assert changed["sha256"] != outs[0]["sha256"]
    assert changed["arrays"]["seismic"] != outs[0]["arrays"]["seismic"]
    assert changed["arrays"]["fault"] == outs[0]["arrays"]["fault"]
    with pytest.raises(SystemExit, match="usage"):
        main([str(tmp_path / "missing.zarr")])
