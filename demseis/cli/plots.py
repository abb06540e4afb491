"""``demseis preview`` and ``demseis plot``: PNG figures (drawing lives in :mod:`demseis.plotting`)."""

from __future__ import annotations

import argparse

from demseis.cli._args import nonneg_int

# Each handler is named "plots:FUNCTION", a function of demseis.cli.commands.plots,
# imported when its command runs (demseis.cli), so that `demseis --help` stays light.


def register(sub: argparse._SubParsersAction) -> None:
    """Add ``preview`` and ``plot``."""
    p = sub.add_parser("preview", help="PNG figures of one run (like the paper's Figures 2-6)")
    p.add_argument("source", metavar="SOURCE", help="a TOML config, a preset name, or a store")
    p.add_argument("--out", required=True, help="output directory for the PNG files")
    p.add_argument("--run", type=nonneg_int, default=0, help="run index (default 0)")
    p.set_defaults(func="plots:cmd_preview")

    p = sub.add_parser("plot", help="PNG of a stored sample, or of a section with its prediction",
                       description="STORE: one stored sample (section, fault label, damage "
                       "zone). SECTION (.sgy, .segy, .npy or .png): the section, with --pred "
                       "(fault probabilities of the same shape, e.g. from demseis predict) "
                       "drawn where they reach Otsu's threshold of their own values (or "
                       "--threshold), and --labels (a picked mask: .npy, .png or SEG-Y).")
    p.add_argument("source", metavar="STORE|SECTION", help="store path, or a section file")
    p.add_argument("--sample", type=nonneg_int, default=None,
                   help="sample index of a store (default 0)")
    p.add_argument("--pred", default=None, help="a section's fault probabilities (.sgy, .npy)")
    p.add_argument("--labels", default=None, help="a section's picked mask (.npy, .png, .sgy)")
    p.add_argument("--threshold", type=float, default=None,
                   help="draw the prediction from this probability (default: Otsu's threshold "
                   "of the prediction)")
    line = p.add_mutually_exclusive_group()
    line.add_argument("--inline", type=int, default=None,
                      help="of a 3-D SEG-Y cube (and its --pred cube): the inline number")
    line.add_argument("--crossline", type=int, default=None,
                      help="of a 3-D SEG-Y cube: the crossline number")
    p.add_argument("--out", required=True, help="output PNG path")
    p.set_defaults(func="plots:cmd_plot")
