"""The ``demseis`` command line.

Each subpackage contributes its subcommands through ``demseis.<pkg>._cli.register(sub, bench)``,
where ``sub`` is the top-level subparsers object and ``bench`` the subparsers of
``demseis bench``. A handler is ``func(args) -> int`` set with ``parser.set_defaults(func=...)``.
Handlers import heavy modules (dask, torch, matplotlib) inside themselves, so ``--help`` is fast.

Any :class:`demseis.errors.DemseisError` becomes one line on stderr and its exit code (2 for
usage and input errors); argparse's own usage errors also exit 2.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence

from demseis import __version__
from demseis.errors import DemseisError


def build_parser() -> argparse.ArgumentParser:
    """The full argument parser with every subpackage's subcommands registered."""
    from demseis.datasets import _cli as datasets_cli
    from demseis.dem import _cli as dem_cli
    from demseis.generator import _commands as generator_cli
    from demseis.labels import _cli as labels_cli
    from demseis.seismic import _cli as seismic_cli

    parser = argparse.ArgumentParser(
        prog="demseis",
        description="Labelled synthetic seismic from discrete-element fault models.",
    )
    parser.add_argument("--version", action="version", version=f"demseis {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    bench_parser = sub.add_parser("bench", help="speed benchmarks printing one JSON line")
    bench = bench_parser.add_subparsers(dest="bench_target", metavar="TARGET")
    bench_parser.set_defaults(func=lambda args: _missing_sub(bench_parser))
    for module in (generator_cli, dem_cli, seismic_cli, labels_cli, datasets_cli):
        module.register(sub, bench)
    return parser


def _missing_sub(parser: argparse.ArgumentParser) -> int:
    parser.print_usage(sys.stderr)
    print(f"{parser.prog}: error: choose a target", file=sys.stderr)
    return 2


def main(argv: Sequence[str] | None = None) -> int:
    """Run the CLI; returns the process exit code."""
    parser = build_parser()
    args = parser.parse_args(argv)
    if not getattr(args, "func", None):
        parser.print_help()
        return 2
    try:
        return int(args.func(args) or 0)
    except DemseisError as exc:
        print(f"demseis: error: {exc}", file=sys.stderr)
        return exc.exit_code
    except KeyboardInterrupt:
        print("demseis: interrupted; rerun the same command to resume", file=sys.stderr)
        return 130


if __name__ == "__main__":  # pragma: no cover
    raise SystemExit(main())
