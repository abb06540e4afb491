"""Fixtures shared by the whole suite."""

from __future__ import annotations

from pathlib import Path

import pytest


@pytest.fixture(autouse=True, scope="session")
def _pack_cache(tmp_path_factory):
    """The pack library of every test run lives in a temporary directory, not the user's cache
    (a preset with ``[model] pack_library`` settles its packs there once per session)."""
    mp = pytest.MonkeyPatch()
    mp.setenv("DEMSEIS_PACK_CACHE", str(tmp_path_factory.mktemp("packs")))
    yield
    mp.undo()


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
