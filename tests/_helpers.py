"""Helpers shared by tests of several directories."""

from __future__ import annotations

from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
"""The repository root (where ``python -m demseis`` finds this checkout's package)."""


def params_of(store) -> dict:
    """Every per-sample parameter of a store, name -> (N,) array (the fill value where a
    shard is not done), as ``demseis.datasets.read_params`` gives them; ``store`` is a path
    or an open zarr group."""
    from demseis.datasets import read_params

    root = getattr(getattr(store, "store", None), "root", store)
    return read_params(Path(str(root)))
