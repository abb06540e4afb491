"""Subcommands contributed by this subpackage to the ``demseis`` CLI."""

from __future__ import annotations

import argparse


def register(sub: argparse._SubParsersAction, bench: argparse._SubParsersAction) -> None:
    """Add this subpackage's commands to ``sub`` and its benchmarks to ``bench``."""
    from demseis.labels._scoring_cli import add_scoring_commands

    add_scoring_commands(sub)
