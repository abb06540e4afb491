"""The handlers of ``demseis preview`` and ``plot``; their parsers are in
:mod:`demseis.cli.plots`."""

from __future__ import annotations

import argparse
import os

from demseis.errors import InputError
from demseis.evaluation.fieldio import MASK_SUFFIXES
from demseis.plotting import plot_sample, plot_section, preview


def cmd_preview(args: argparse.Namespace) -> int:
    for p in preview(args.source, args.out, run=args.run):
        print(p)
    return 0


def cmd_plot(args: argparse.Namespace) -> int:
    section_file = not os.path.isdir(args.source) and args.source.lower().endswith(MASK_SUFFIXES)
    if section_file:
        if args.sample is not None:
            raise InputError(f"--sample is for a store; {args.source!r} is a section file")
        line = (("inline", args.inline) if args.inline is not None else
                ("crossline", args.crossline) if args.crossline is not None else None)
        print(plot_section(args.source, args.out, pred=args.pred, labels=args.labels,
                           threshold=args.threshold, line=line))
        return 0
    given = [f for f, v in (("--pred", args.pred), ("--labels", args.labels),
                            ("--threshold", args.threshold), ("--inline", args.inline),
                            ("--crossline", args.crossline)) if v is not None]
    if given:
        raise InputError(f"{given[0]} is for a section file (.sgy, .segy, .npy, .png); "
                         f"{args.source!r} is read as a store")
    print(plot_sample(args.source, args.sample or 0, args.out))
    return 0
