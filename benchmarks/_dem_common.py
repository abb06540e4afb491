"""What the DEM benchmark scripts do at the end: keep the snapshots, draw them, print the JSON."""

from __future__ import annotations

import argparse
import json
from typing import Any


def finish(res: dict[str, Any], snaps: list, args: argparse.Namespace, title: str) -> int:
    """Save ``snaps`` to ``args.save`` and draw them to ``args.figure`` when asked, then print
    ``res`` as one JSON line; returns the exit code 0."""
    if args.save:
        from demseis.types import save_snapshots

        save_snapshots(args.save, snaps)
    if args.figure:
        from demseis.plotting import plot_snapshots

        plot_snapshots(snaps, args.figure, title=title)
    print(json.dumps(res))
    return 0
