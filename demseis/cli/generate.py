"""``demseis generate`` and ``demseis render``: write a dataset, re-render a store's snapshots."""

from __future__ import annotations

import argparse

from demseis.cli import nonneg_int
from demseis.errors import InputError


def register(sub: argparse._SubParsersAction, bench: argparse._SubParsersAction) -> None:
    """Add ``generate`` and ``render``."""
    p = sub.add_parser(
        "generate",
        help="run a sweep and write a labelled dataset (resumes an interrupted one)",
        description="Run every DEM run of a config and write its samples to a sharded Zarr store. "
        "Rerunning the same command on an existing store completes only the missing shards.",
    )
    p.add_argument("config", nargs="?", help="TOML config file (default: the quick preset)")
    p.add_argument("--preset", help="built-in preset: tiny, quick or seed (a CONFIG file overrides its keys)")
    p.add_argument("--out", required=True, help="output store path (a directory, e.g. data.zarr)")
    p.add_argument("--workers", type=nonneg_int, default=None,
                   help="worker processes (default: all cores; 0 = run in this process, no dask)")
    p.add_argument("--scheduler", help="address of an existing dask scheduler (e.g. tcp://host:8786)")
    p.add_argument("--overwrite", action="store_true",
                   help="replace an existing store written with a different config")
    p.add_argument("--dry-run", action="store_true", help="print the plan and exit without computing")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.set_defaults(func=cmd_generate)

    p = sub.add_parser("render", help="re-render a store's particle snapshots at new frequencies / SNRs")
    p.add_argument("store", help="source store (its DEM snapshots are reused)")
    p.add_argument("--freq", required=True, help="comma-separated Ricker frequencies in Hz, e.g. 20,40,60")
    p.add_argument("--snr", default="inf", help="comma-separated SNRs in dB (inf = no noise), default inf")
    p.add_argument("--noise", default="white", choices=("white", "band"), help="noise kind")
    p.add_argument("--out", required=True, help="new store path")
    p.add_argument("--overwrite", action="store_true", help="replace --out if it is a demseis store")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.set_defaults(func=cmd_render)


def cmd_generate(args: argparse.Namespace) -> int:
    from demseis.generator.config import load_config
    from demseis.generator.sweep import dry_run_plan, run_sweep

    cfg = load_config(args.config, preset=args.preset)
    if args.dry_run:
        print("\n".join(dry_run_plan(cfg)))
        return 0
    if args.workers is not None and args.scheduler is not None:
        raise InputError("give either --workers or --scheduler, not both")
    summary = run_sweep(cfg, args.out, workers=args.workers, scheduler=args.scheduler,
                        overwrite=args.overwrite, progress=not args.quiet)
    print("\n".join(summary.lines()))
    return 1 if summary.failed else 0


def _float_list(text: str, name: str) -> list[float]:
    vals = []
    for part in text.split(","):
        part = part.strip()
        try:
            vals.append(float(part))
        except ValueError:
            raise InputError(f"{name} {text!r}: {part!r} is not a number") from None
    if not vals:
        raise InputError(f"{name} {text!r}: give at least one value")
    return vals


def cmd_render(args: argparse.Namespace) -> int:
    from demseis.generator.rerender import rerender

    freqs = _float_list(args.freq, "--freq")
    snrs = _float_list(args.snr, "--snr")
    summary = rerender(args.store, args.out, freqs_hz=freqs, snrs_db=snrs, noise_kind=args.noise,
                       overwrite=args.overwrite, progress=not args.quiet)
    print("\n".join(summary.lines()))
    return 1 if summary.failed else 0
