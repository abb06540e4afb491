"""``demseis info``, ``validate``, ``export-segy`` and ``migrate``: look at a store, convert one.

- ``demseis validate PATH``: exit 0 and a one-line summary when every done shard is fine;
  exit 1 and one line per problem otherwise; exit 2 for a missing or foreign store.
"""

from __future__ import annotations

import argparse
import sys

# The handlers below import the modules they run inside themselves, so that `demseis --help`
# imports none of them (see demseis.cli).


def register(sub: argparse._SubParsersAction) -> None:
    """Add ``info``, ``validate``, ``export-segy`` and ``migrate``."""
    p = sub.add_parser("info", help="summarise a store: samples, shapes, parameter ranges, config")
    p.add_argument("path", metavar="STORE", help="store path")
    p.set_defaults(func=cmd_info)

    p = sub.add_parser(
        "validate",
        help="check a demseis store (checksums, done shards complete, labels in range)",
        description="Check every done shard of a demseis store: every chunk checksum (naming "
        "each damaged sample and array), complete, no NaN, label values in range, consistent "
        "parameters. Read only: it takes no lock. Exit 0 when fine, 1 with the list of "
        "problems, 2 for a missing or foreign store.",
    )
    p.add_argument("path", metavar="STORE", help="store directory")
    p.add_argument("--no-particles", action="store_true",
                   help="skip reading the stored particle snapshots")
    p.set_defaults(func=cmd_validate)

    p = sub.add_parser(
        "export-segy",
        help="write one stored seismic section as SEG-Y",
        description="Write seismic sample I of a demseis store as a SEG-Y file (one trace per "
                    "grid column, IEEE float32, sample interval and trace x set).",
    )
    p.add_argument("store", metavar="STORE", help="path of the demseis Zarr store")
    p.add_argument("--sample", type=int, required=True, metavar="I", help="sample index")
    p.add_argument("--out", required=True, metavar="FILE.sgy", help="SEG-Y file to write")
    p.add_argument("--overwrite", action="store_true", help="replace FILE.sgy if it exists")
    p.set_defaults(func=cmd_export_segy)

    p = sub.add_parser(
        "migrate",
        help="convert a store written by an older demseis to this one's layout (in place)",
        description="Convert a store of schema version 2 to this demseis's version in place: "
        "its per-sample parameters move into one table (one file per run instead of one per "
        "parameter and run) with an index; the samples, done flags and particles keep their "
        "bytes and nothing is recomputed. Interrupted, run it again. On a current store it "
        "rebuilds the parameter index.",
    )
    p.add_argument("path", metavar="STORE", help="store directory")
    p.set_defaults(func=cmd_migrate)


def cmd_info(args: argparse.Namespace) -> int:
    from demseis.api import open as open_store
    from demseis.generator.sweep.faultinfo import fault_distribution

    print("\n".join([open_store(args.path).summary(), *fault_distribution(args.path)]))
    return 0


def cmd_validate(args: argparse.Namespace) -> int:
    from demseis.datasets.validate import validate_store

    report = validate_store(args.path, check_particles=not args.no_particles,
                            progress=sys.stderr.isatty())
    for line in report.problems:
        print(line)
    print(report.summary())
    return 0 if report.ok else 1


def cmd_export_segy(args: argparse.Namespace) -> int:
    from demseis.datasets.read import export_segy

    out = export_segy(args.store, args.sample, args.out, overwrite=args.overwrite)
    print(f"wrote {out}", file=sys.stderr)
    return 0


def cmd_migrate(args: argparse.Namespace) -> int:
    from demseis.datasets.migrate import migrate_store

    print(migrate_store(args.path, progress=sys.stderr.isatty()).summary())
    return 0
