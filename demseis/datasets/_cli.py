"""Subcommands contributed by this subpackage to the ``demseis`` CLI.

- ``demseis validate PATH``: exit 0 and a one-line summary when every done shard is fine;
  exit 1 and one line per problem otherwise; exit 2 for a missing or foreign store.
- ``demseis bench loader``: DataLoader vs NumPy-memmap throughput (one JSON line).
"""

from __future__ import annotations

import argparse
import sys


def register(sub: argparse._SubParsersAction, bench: argparse._SubParsersAction) -> None:
    """Add this subpackage's commands to ``sub`` and its benchmarks to ``bench``."""
    p = sub.add_parser(
        "validate",
        help="check a demseis store (done shards complete, finite, labels in range)",
        description="Check every done shard of a demseis store: complete, no NaN, label values "
        "in range, consistent parameters. Exit 0 when fine, 1 with the list of problems, "
        "2 for a missing or foreign store.",
    )
    p.add_argument("path", metavar="PATH", help="store directory")
    p.add_argument("--no-particles", action="store_true",
                   help="skip reading the stored particle snapshots")
    p.set_defaults(func=_validate)

    b = bench.add_parser("loader", help="DataLoader throughput vs NumPy memmap (256x256 crops)")
    b.add_argument("--shards", type=int, default=48, help="shards in the temporary store")
    b.add_argument("--samples-per-shard", type=int, default=32)
    b.add_argument("--shape", type=int, nargs=2, default=(277, 500), metavar=("H", "W"))
    b.add_argument("--crop", type=int, default=256)
    b.add_argument("--batch-size", type=int, default=32)
    b.add_argument("--repeats", type=int, default=5)
    b.add_argument("--workers", type=int, nargs="+", default=(0, 2))
    b.add_argument("--dir", default=None, help="where to build the temporary store")
    b.set_defaults(func=_bench_loader)


def _validate(args: argparse.Namespace) -> int:
    from demseis.datasets.validate import validate_store

    report = validate_store(args.path, check_particles=not args.no_particles,
                            progress=sys.stderr.isatty())
    for line in report.problems:
        print(line)
    print(report.summary())
    return 0 if report.ok else 1


def _bench_loader(args: argparse.Namespace) -> int:
    import json

    from demseis.datasets._bench import run_loader_benchmark

    result = run_loader_benchmark(
        n_shards=args.shards,
        samples_per_shard=args.samples_per_shard,
        shape=tuple(args.shape),
        crop=args.crop,
        batch_size=args.batch_size,
        repeats=args.repeats,
        workers=tuple(args.workers),
        workdir=args.dir,
        progress=sys.stderr.isatty(),
    )
    print(json.dumps(result))
    return 0
