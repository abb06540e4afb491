"""Subcommands contributed by this subpackage to the ``demseis`` CLI."""

from __future__ import annotations

import argparse
import json
import os
import sys


def register(sub: argparse._SubParsersAction, bench: argparse._SubParsersAction) -> None:
    """Add this subpackage's commands to ``sub`` and its benchmarks to ``bench``."""
    p = sub.add_parser(
        "export-segy",
        help="write one stored seismic section as SEG-Y",
        description="Write seismic sample I of a demseis store as a SEG-Y file (one trace per "
                    "grid column, IEEE float32, sample interval and trace x set).",
    )
    p.add_argument("store", help="path of the demseis Zarr store")
    p.add_argument("--sample", type=int, required=True, metavar="I", help="sample index")
    p.add_argument("--out", required=True, metavar="FILE.sgy", help="SEG-Y file to write")
    p.add_argument("--overwrite", action="store_true", help="replace FILE.sgy if it exists")
    p.set_defaults(func=_export_segy)

    b = bench.add_parser(
        "seismic",
        help="ms per rendered snapshot/section at 512x288 (1 and 3 frequencies)",
        description="Time the whole per-snapshot seismic render (element properties, "
                    "rasterisation, background, smoothing, time-domain Ricker convolution back "
                    "to depth) of a faulted toy disk pack; prints one JSON line.",
    )
    b.add_argument("--nx", type=int, default=512, help="grid columns (default 512)")
    b.add_argument("--nz", type=int, default=288, help="grid rows (default 288)")
    b.add_argument("--repeats", type=int, default=7, help="timed repeats, median (default 7)")
    b.add_argument("--npz", help="render the last snapshot of this .npz (e.g. saved from a DEM "
                                 "run) instead of the kinematic toy pack")
    b.set_defaults(func=_bench_seismic)


def _export_segy(args: argparse.Namespace) -> int:
    from demseis.seismic.segy import export_segy

    out = export_segy(args.store, args.sample, args.out, overwrite=args.overwrite)
    print(f"wrote {out}", file=sys.stderr)
    return 0


def _bench_seismic(args: argparse.Namespace) -> int:
    from demseis.errors import InputError
    from demseis.seismic.bench import run_benchmark

    for name in ("nx", "nz", "repeats"):
        if getattr(args, name) < 1:
            raise InputError(f"--{name} must be >= 1, got {getattr(args, name)}")
    if args.npz is not None and not os.path.isfile(args.npz):
        raise InputError(f"--npz {args.npz!r} is not a file")
    print(json.dumps(run_benchmark(nx=args.nx, nz=args.nz, repeats=args.repeats, npz=args.npz)))
    return 0
