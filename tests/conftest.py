"""Fixtures shared by the whole suite."""

from __future__ import annotations

from pathlib import Path

import pytest


@pytest.fixture(scope="session")
def tiny_store(tmp_path_factory) -> Path:
    """The ``tiny`` preset generated once (in-process, no dask) through ``demseis.generate``.

    Read-only: tests that change a store make their own.
    """
    import demseis

    out = tmp_path_factory.mktemp("tiny") / "t.zarr"
    store = demseis.generate("tiny", out=out, workers=0)
    assert not store.run_summary.failed
    return out
