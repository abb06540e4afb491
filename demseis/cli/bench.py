"""``demseis bench dem|seismic|labels|loader``: speed benchmarks printing one JSON line each.

The code that is timed lives in :mod:`demseis.diagnostics.bench`. Each handler imports it inside
itself: the diagnostics load the DEM, seismic and label stages (and the loader torch), which
neither ``demseis --help`` nor the product commands need, and no product module may import
:mod:`demseis.diagnostics` (``tests/test_layout.py``).
"""

from __future__ import annotations

import argparse
import json
import os
import sys

from demseis.errors import InputError


def register(sub: argparse._SubParsersAction, bench: argparse._SubParsersAction) -> None:
    """Add the benchmark targets to ``bench``."""
    p = bench.add_parser("dem", help="DEM kernel throughput (element-steps per second)")
    p.add_argument("--pack", default=None,
                   help=".npz with arrays x, y, radius (m); default: the seed-scale pack "
                        "(5 km x 2.77 km), settled once and cached")
    p.add_argument("--steps", type=int, default=2000, help="timed steps (default 2000)")
    p.set_defaults(func=cmd_dem)

    p = bench.add_parser(
        "seismic",
        help="ms per rendered snapshot/section at 512x288 (1 and 3 frequencies)",
        description="Time the whole per-snapshot seismic render (element properties, "
                    "rasterisation, background, smoothing, time-domain Ricker convolution back "
                    "to depth) of a faulted toy disk pack; prints one JSON line.",
    )
    p.add_argument("--nx", type=int, default=512, help="grid columns (default 512)")
    p.add_argument("--nz", type=int, default=288, help="grid rows (default 288)")
    p.add_argument("--repeats", type=int, default=7, help="timed repeats, median (default 7)")
    p.add_argument("--npz", help="render the last snapshot of this .npz (demseis.types."
                                 "save_snapshots, e.g. saved from a DEM run) instead of the "
                                 "kinematic toy pack")
    p.set_defaults(func=cmd_seismic)

    p = bench.add_parser("labels", help="strain history and label maps on ~11k elements")
    p.add_argument("--snapshots", type=int, default=6, help="number of snapshots (>= 2)")
    p.add_argument("--repeats", type=int, default=5, help="timed repeats (median reported)")
    p.set_defaults(func=cmd_labels)

    p = bench.add_parser("loader", help="DataLoader throughput vs NumPy memmap (256x256 crops)")
    p.add_argument("--shards", type=int, default=48, help="shards in the temporary store")
    p.add_argument("--samples-per-shard", type=int, default=32)
    p.add_argument("--shape", type=int, nargs=2, default=(277, 500), metavar=("H", "W"))
    p.add_argument("--crop", type=int, default=256)
    p.add_argument("--batch-size", type=int, default=32)
    p.add_argument("--repeats", type=int, default=5)
    p.add_argument("--workers", type=int, nargs="+", default=(0, 2))
    p.add_argument("--dir", default=None, help="where to build the temporary store")
    p.set_defaults(func=cmd_loader)


def cmd_dem(args: argparse.Namespace) -> int:
    from demseis.diagnostics import bench

    if args.steps < 1:
        raise InputError(f"--steps {args.steps}: must be >= 1")
    if args.pack:
        xy, r = bench.load_pack(args.pack)
    else:
        print("demseis: settling the seed-scale pack (cached after the first time)...",
              file=sys.stderr)
        pack = bench.seed_pack()
        xy, r = pack.xy, pack.radius
    print(json.dumps(bench.dem_benchmark(xy, r, n_steps=args.steps)))
    return 0


def cmd_seismic(args: argparse.Namespace) -> int:
    from demseis.diagnostics.bench import seismic_benchmark

    for name in ("nx", "nz", "repeats"):
        if getattr(args, name) < 1:
            raise InputError(f"--{name} must be >= 1, got {getattr(args, name)}")
    if args.npz is not None and not os.path.isfile(args.npz):
        raise InputError(f"--npz {args.npz!r} is not a file")
    print(json.dumps(seismic_benchmark(nx=args.nx, nz=args.nz, repeats=args.repeats,
                                       npz=args.npz)))
    return 0


def cmd_labels(args: argparse.Namespace) -> int:
    from demseis.diagnostics.bench import labels_benchmark

    if args.snapshots < 2 or args.repeats < 1:
        raise InputError(f"--snapshots must be >= 2 and --repeats >= 1; got {args.snapshots}, "
                         f"{args.repeats}")
    print(json.dumps(labels_benchmark(n_snapshots=args.snapshots, repeats=args.repeats)))
    return 0


def cmd_loader(args: argparse.Namespace) -> int:
    from demseis.diagnostics.bench import loader_benchmark

    result = loader_benchmark(
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
