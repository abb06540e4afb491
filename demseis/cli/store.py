"""``demseis info``, ``validate``, ``export-segy`` and ``migrate``: look at a store, convert one.

- ``demseis validate PATH``: exit 0 and a one-line summary when every done shard is fine;
  exit 1 and one line per problem otherwise; exit 2 for a missing or foreign store.
"""

from __future__ import annotations

import argparse

# Each handler is named "store:FUNCTION", a function of demseis.cli.commands.store,
# imported when its command runs (demseis.cli), so that `demseis --help` stays light.


def register(sub: argparse._SubParsersAction) -> None:
    """Add ``info``, ``validate``, ``export-segy`` and ``migrate``."""
    p = sub.add_parser("info", help="summarise a store: samples, shapes, parameter ranges, config")
    p.add_argument("path", metavar="STORE", help="store path")
    p.set_defaults(func="store:cmd_info")

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
    p.set_defaults(func="store:cmd_validate")

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
    p.set_defaults(func="store:cmd_export_segy")

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
    p.set_defaults(func="store:cmd_migrate")
