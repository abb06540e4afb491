"""The handlers of ``demseis info``, ``validate``, ``export-segy`` and ``migrate``; their
parsers are in :mod:`demseis.cli.store`."""

from __future__ import annotations

import argparse
import sys

from demseis.datasets.migrate import migrate_store
from demseis.datasets.read import export_segy, store_summary
from demseis.datasets.table import read_done_params
from demseis.datasets.validate import validate_store
from demseis.generator.sweep.faultinfo import fault_distribution


def cmd_info(args: argparse.Namespace) -> int:
    table = read_done_params(args.path)  # once: the summary and the fault counts share it
    print("\n".join([*store_summary(args.path, table), *fault_distribution(args.path, table)]))
    return 0


def cmd_validate(args: argparse.Namespace) -> int:
    report = validate_store(args.path, check_particles=not args.no_particles,
                            progress=sys.stderr.isatty())
    for line in report.problems:
        print(line)
    print(report.summary())
    return 0 if report.ok else 1


def cmd_export_segy(args: argparse.Namespace) -> int:
    out = export_segy(args.store, args.sample, args.out, overwrite=args.overwrite)
    print(f"wrote {out}", file=sys.stderr)
    return 0


def cmd_migrate(args: argparse.Namespace) -> int:
    print(migrate_store(args.path, progress=sys.stderr.isatty()).summary())
    return 0
