"""Subcommands contributed by this subpackage to the ``demseis`` CLI."""

from __future__ import annotations

import argparse


def register(sub: argparse._SubParsersAction, bench: argparse._SubParsersAction) -> None:
    """Add this subpackage's commands to ``sub`` and its benchmarks to ``bench``."""
    p = bench.add_parser("dem", help="DEM kernel throughput (element-steps per second)")
    p.add_argument("--pack", default=None,
                   help=".npz with arrays x, y, radius (m); default: the seed-scale pack "
                        "(5 km x 2.77 km), settled once and cached")
    p.add_argument("--steps", type=int, default=2000, help="timed steps (default 2000)")
    p.set_defaults(func=_bench_dem)


def _bench_dem(args: argparse.Namespace) -> int:
    import json
    import sys

    from demseis.dem import bench

    if args.steps < 1:
        from demseis.errors import InputError
        raise InputError(f"--steps {args.steps}: must be >= 1")
    if args.pack:
        xy, r = bench.load_pack(args.pack)
    else:
        print("demseis: settling the seed-scale pack (cached after the first time)...",
              file=sys.stderr)
        pack = bench.seed_pack()
        xy, r = pack.xy, pack.radius
    print(json.dumps(bench.run_bench(xy, r, n_steps=args.steps)))
    return 0
