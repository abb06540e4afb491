"""``demseis preview`` and ``demseis plot``: PNG figures (drawing lives in :mod:`demseis.plotting`)."""

from __future__ import annotations

import argparse

from demseis.cli._args import nonneg_int

# The handlers below import demseis.plotting (matplotlib, the whole pipeline) inside themselves,
# so that `demseis --help` imports none of it (see demseis.cli).


def register(sub: argparse._SubParsersAction, bench: argparse._SubParsersAction) -> None:
    """Add ``preview`` and ``plot``."""
    p = sub.add_parser("preview", help="PNG figures of one run (like the paper's Figures 2-6)")
    p.add_argument("source", metavar="SOURCE", help="a TOML config, a preset name, or a store")
    p.add_argument("--out", required=True, help="output directory for the PNG files")
    p.add_argument("--run", type=nonneg_int, default=0, help="run index (default 0)")
    p.set_defaults(func=cmd_preview)

    p = sub.add_parser("plot", help="PNG of one stored sample: section, fault label, damage zone")
    p.add_argument("store", metavar="STORE", help="store path")
    p.add_argument("--sample", type=nonneg_int, default=0, help="sample index (default 0)")
    p.add_argument("--out", required=True, help="output PNG path")
    p.set_defaults(func=cmd_plot)


def cmd_preview(args: argparse.Namespace) -> int:
    from demseis.plotting import preview

    for p in preview(args.source, args.out, run=args.run):
        print(p)
    return 0


def cmd_plot(args: argparse.Namespace) -> int:
    from demseis.plotting import plot_sample

    print(plot_sample(args.store, args.sample, args.out))
    return 0
