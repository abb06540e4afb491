"""Helpers shared by the generator tests (and by the tests of other directories that generate:
tests/faults, tests/evaluation)."""

from __future__ import annotations

import dataclasses
from pathlib import Path


def generate_tiny(folder: Path, toml: str, name: str) -> Path:
    """Write ``toml`` as ``folder/name.toml`` and run `demseis generate` on it over the `tiny`
    preset in-process (``--workers 0 --quiet``); asserts exit 0 and returns the store path."""
    from demseis.cli import main

    cfg = folder / f"{name}.toml"
    cfg.write_text(toml)
    out = folder / f"{name}.zarr"
    assert main(["generate", str(cfg), "--preset", "tiny", "--out", str(out), "--workers", "0",
                 "--quiet"]) == 0
    return out


def tree_bytes(path: Path) -> dict[str, bytes]:
    """Every file below ``path``, by its relative name, with its bytes."""
    return {str(p.relative_to(path)): p.read_bytes() for p in sorted(path.rglob("*")) if p.is_file()}


def assert_same_bytes(a: Path, b: Path) -> None:
    """The two stores (directory trees) hold the same files with the same bytes."""
    ta, tb = tree_bytes(a), tree_bytes(b)
    assert sorted(ta) == sorted(tb), set(ta) ^ set(tb)
    different = [k for k in ta if ta[k] != tb[k]]
    assert not different, f"files differ: {different[:5]}"


def kinematic_cfg(preset: str = "tiny", **model):
    """The config of ``preset`` with the kinematic engine (and ``model`` fields replaced)."""
    from demseis.generator.config.settings import load_config

    cfg = load_config(preset=preset)
    return dataclasses.replace(cfg, model=dataclasses.replace(cfg.model, engine="kinematic",
                                                              **model))
