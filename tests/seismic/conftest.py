"""Shared fixtures of the seismic tests.

bruges 0.5.4 imports ``pkg_resources`` at import time, which setuptools >= 81 no longer ships;
when it is missing a minimal stand-in (``get_distribution`` raising ``DistributionNotFound``,
after which bruges reads its ``_version.py``) is installed before bruges is imported.
"""

from __future__ import annotations

import sys
import types

import numpy as np
import pytest


def _import_bruges():
    try:
        import pkg_resources  # noqa: F401
    except ImportError:
        shim = types.ModuleType("pkg_resources")

        class DistributionNotFound(Exception):
            pass

        def get_distribution(name):
            raise DistributionNotFound(name)

        shim.DistributionNotFound = DistributionNotFound
        shim.get_distribution = get_distribution
        sys.modules["pkg_resources"] = shim
    import bruges

    return bruges


@pytest.fixture(scope="session")
def bruges():
    """The bruges package (a test dependency)."""
    return _import_bruges()


def make_store(path, seismic: np.ndarray, grid: dict, schema_version: int | None = None):
    """A minimal demseis-like Zarr v3 store: root array ``seismic`` and attrs grid/demseis."""
    import zarr

    g = zarr.open_group(str(path), mode="w", zarr_format=3)
    a = g.create_array("seismic", shape=seismic.shape, dtype="float32",
                       chunks=(1,) + seismic.shape[1:], fill_value=np.nan)
    a[...] = seismic
    g.attrs["grid"] = grid
    from demseis.datasets import SCHEMA_VERSION

    version = SCHEMA_VERSION if schema_version is None else schema_version
    g.attrs["demseis"] = {"schema_version": version, "package_version": "0.1.0"}
    return path


@pytest.fixture
def tiny_store(tmp_path):
    """A 3-sample store of 12 x 7 sections (sample 2 never written: NaN)."""
    rng = np.random.default_rng(5)
    nz, nx = 12, 7
    data = rng.standard_normal((3, nz, nx)).astype(np.float32)
    data[2] = np.nan
    grid = {"x0_m": 100.0, "top_m": 2770.0, "cell_m": 10.0, "nz": nz, "nx": nx}
    return make_store(tmp_path / "store.zarr", data, grid), data, grid
