"""Subcommands contributed by this subpackage to the ``demseis`` CLI."""

from __future__ import annotations

import argparse


def register(sub: argparse._SubParsersAction, bench: argparse._SubParsersAction) -> None:
    """Add this subpackage's commands to ``sub`` and its benchmarks to ``bench``."""
    from demseis.labels._scoring_cli import add_scoring_commands

    add_scoring_commands(sub)
    _add_bench_labels(bench)


def _add_bench_labels(bench: argparse._SubParsersAction) -> None:
    p = bench.add_parser("labels", help="strain history and label maps on ~11k elements")
    p.add_argument("--snapshots", type=int, default=6, help="number of snapshots (>= 2)")
    p.add_argument("--repeats", type=int, default=5, help="timed repeats (median reported)")
    p.set_defaults(func=_bench_labels)


def _bench_labels(args: argparse.Namespace) -> int:
    import json

    from demseis.errors import InputError
    from demseis.labels._bench import run_benchmark

    if args.snapshots < 2 or args.repeats < 1:
        raise InputError(f"--snapshots must be >= 2 and --repeats >= 1; got {args.snapshots}, "
                         f"{args.repeats}")
    print(json.dumps(run_benchmark(n_snapshots=args.snapshots, repeats=args.repeats)))
    return 0
