"""Generator subcommands: ``generate``, ``info``, ``preview``, ``render``."""

from __future__ import annotations

import argparse
import math
from pathlib import Path

from demseis.errors import InputError


def register(sub: argparse._SubParsersAction, bench: argparse._SubParsersAction) -> None:
    """Add the generator's commands."""
    p = sub.add_parser(
        "generate",
        help="run a sweep and write a labelled dataset (resumes an interrupted one)",
        description="Run every DEM run of a config and write its samples to a sharded Zarr store. "
        "Rerunning the same command on an existing store completes only the missing shards.",
    )
    p.add_argument("config", nargs="?", help="TOML config file (default: the quick preset)")
    p.add_argument("--preset", help="built-in preset: tiny, quick or seed (a CONFIG file overrides its keys)")
    p.add_argument("--out", required=True, help="output store path (a directory, e.g. data.zarr)")
    p.add_argument("--workers", type=_nonneg_int, default=None,
                   help="worker processes (default: all cores; 0 = run in this process, no dask)")
    p.add_argument("--scheduler", help="address of an existing dask scheduler (e.g. tcp://host:8786)")
    p.add_argument("--overwrite", action="store_true",
                   help="replace an existing store written with a different config")
    p.add_argument("--dry-run", action="store_true", help="print the plan and exit without computing")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.set_defaults(func=cmd_generate)

    p = sub.add_parser("info", help="summarise a store: samples, shapes, parameter ranges, config")
    p.add_argument("path", help="store path")
    p.set_defaults(func=cmd_info)

    p = sub.add_parser("preview", help="PNG figures of one run (like the paper's Figures 2-6)")
    p.add_argument("source", help="a TOML config, a preset name, or a store")
    p.add_argument("--out", required=True, help="output directory for the PNG files")
    p.add_argument("--run", type=_nonneg_int, default=0, help="run index (default 0)")
    p.set_defaults(func=cmd_preview)

    p = sub.add_parser("plot", help="PNG of one stored sample: section, fault label, damage zone")
    p.add_argument("store", help="store path")
    p.add_argument("--sample", type=_nonneg_int, default=0, help="sample index (default 0)")
    p.add_argument("--out", required=True, help="output PNG path")
    p.set_defaults(func=cmd_plot)

    p = sub.add_parser("render", help="re-render a store's particle snapshots at new frequencies / SNRs")
    p.add_argument("store", help="source store (its DEM snapshots are reused)")
    p.add_argument("--freq", required=True, help="comma-separated Ricker frequencies in Hz, e.g. 20,40,60")
    p.add_argument("--snr", default="inf", help="comma-separated SNRs in dB (inf = no noise), default inf")
    p.add_argument("--noise", default="white", choices=("white", "band"), help="noise kind")
    p.add_argument("--out", required=True, help="new store path")
    p.add_argument("--overwrite", action="store_true", help="replace --out if it is a demseis store")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.set_defaults(func=cmd_render)


def _nonneg_int(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not an integer") from None
    if value < 0:
        raise argparse.ArgumentTypeError(f"{text!r} must be >= 0")
    return value


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


def cmd_info(args: argparse.Namespace) -> int:
    print("\n".join(store_info_lines(args.path)))
    return 0


def store_info_lines(path: str | Path) -> list[str]:
    """The lines ``demseis info`` prints."""
    import numpy as np

    from demseis.datasets import open_store, shard_status

    root = open_store(path)
    attrs = dict(root.attrs)
    cfg = attrs.get("config", {})
    status = shard_status(path)
    codes = attrs.get("param_codes", {})
    lines = [f"store: {path}", f"demseis schema: {attrs.get('demseis', {})}"]
    seis = root["seismic"]
    n, h, w = seis.shape
    S = n // max(len(status), 1)
    lines.append(f"samples: {n} in {len(status)} shards of {S}; done shards: {int((status == 1).sum())}")
    grid = attrs.get("grid", {})
    lines.append(f"grid: {h} x {w} cells of {grid.get('cell_m')} m")
    for name in ("seismic", "fault", "damage", "strain", "layer", "impedance"):
        if name in root:
            a = root[name]
            lines.append(f"  {name:10s} {str(a.dtype):8s} shape {tuple(a.shape)} chunks {tuple(a.chunks)}")
    done = np.repeat(status == 1, S)
    lines.append("parameters (over done samples):")
    params = root["params"]
    for name in sorted(params.array_keys()):
        vals = params[name][:][done]
        if vals.size == 0:
            continue
        if name in codes:
            uniq = sorted({codes[name][int(v)] for v in vals})
            lines.append(f"  {name:22s} {', '.join(uniq)}")
            continue
        uniq = np.unique(vals)
        if uniq.size <= 6:
            shown = ", ".join(_fmt(v) for v in uniq)
        else:
            shown = f"{_fmt(vals.min())} .. {_fmt(vals.max())} ({uniq.size} distinct)"
        lines.append(f"  {name:22s} {shown}")
    if cfg:
        sw = cfg.get("sweep", {})
        lines.append(f"config: name={cfg.get('name')} seed={sw.get('seed')} n_runs={sw.get('n_runs')} "
                     f"model={cfg.get('model', {}).get('width_m')}x{cfg.get('model', {}).get('height_m')} m "
                     f"snapshots={cfg.get('model', {}).get('n_snapshots')}")
    failed = attrs.get("failures") or {}
    if failed:
        lines.append(f"failed runs: {len(failed)}")
        for k, v in sorted(failed.items(), key=lambda kv: int(kv[0])):
            lines.append(f"  run {k}: {v}")
    return lines


def _fmt(v: object) -> str:
    f = float(v)  # type: ignore[arg-type]
    if math.isinf(f):
        return "inf"
    return f"{f:g}"


def cmd_preview(args: argparse.Namespace) -> int:
    from demseis.generator.preview import preview

    written = preview(args.source, args.out, run=args.run)
    for p in written:
        print(p)
    return 0


def cmd_plot(args: argparse.Namespace) -> int:
    from demseis.generator.preview import plot_sample

    print(plot_sample(args.store, args.sample, args.out))
    return 0


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
