"""Helpers shared by the generator tests."""

from __future__ import annotations

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
