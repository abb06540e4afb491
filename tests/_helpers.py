"""Helpers shared by tests of several directories."""

from __future__ import annotations

from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
"""The repository root (where ``python -m demseis`` finds this checkout's package)."""
