"""``demseis generate``, ``render``, ``relabel`` and ``params``: write a dataset, re-render or
relabel a store's snapshots, list the parameters a config may set."""

from __future__ import annotations

import argparse
import re
import sys
import tomllib
import warnings

from demseis.cli._args import nonneg_int
from demseis.errors import ConfigError, InputError

# The handlers below import the modules they run inside themselves, so that `demseis --help`
# imports none of them (see demseis.cli).


def register(sub: argparse._SubParsersAction) -> None:
    """Add ``generate``, ``render``, ``relabel`` and ``params``."""
    p = sub.add_parser(
        "generate",
        help="run a sweep and write a labelled dataset (resumes an interrupted one)",
        description="Simulate and render every run of a config and write its samples to a sharded Zarr store. "
        "Rerunning the same command on an existing store completes only the missing shards.",
    )
    p.add_argument("config", nargs="?", help="TOML config file (default: the quick preset)")
    p.add_argument("--preset", help="built-in preset: tiny, quick, seed, variety, field or planar "
                   "(a CONFIG file overrides its keys)")
    p.add_argument("--out", required=True, help="output store path (a directory, e.g. data.zarr)")
    p.add_argument("--workers", type=nonneg_int, default=None,
                   help="worker processes (default: all cores; 0 = run in this process, no dask)")
    p.add_argument("--scheduler", help="address of an existing dask scheduler (e.g. tcp://host:8786)")
    p.add_argument("--overwrite", action="store_true",
                   help="replace an existing store written with a different config")
    p.add_argument("--dry-run", action="store_true", help="print the plan and exit without computing")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.add_argument("--like", action="append", metavar="SECTION",
                   help="fit the config to this survey section first (demseis fit; repeatable; "
                        "on --preset, default field) instead of reading a CONFIG")
    p.add_argument("--dt-ms", type=float, default=None, metavar="MS",
                   help="with --like: the sample interval where the headers do not give it")
    p.add_argument("--trace-spacing-m", type=float, default=None, metavar="M",
                   help="with --like: the trace spacing where the headers do not give it")
    p.set_defaults(func=cmd_generate)

    p = sub.add_parser("render", help="re-render a store's particle snapshots at new frequencies / SNRs")
    p.add_argument("store", metavar="STORE", help="source store (its DEM snapshots are reused)")
    p.add_argument("--freq", required=True, help="comma-separated Ricker frequencies in Hz, e.g. 20,40,60")
    p.add_argument("--snr", default="inf", help="comma-separated SNRs in dB (inf = no noise), default inf")
    p.add_argument("--noise", default="white", choices=("white", "band", "coloured"),
                   help="noise kind (coloured: power spectrum f^-1)")
    p.add_argument("--imaging", help="comma-separated imaging: 1d, psf (2-D dip-limited PSF), or "
                                     "both; default: the source store's")
    p.add_argument("--psf-max-angle", help="comma-separated maximum illumination angles of the PSF "
                                           "in degrees, e.g. 20,45; default: the source store's")
    p.add_argument("--psf-aperture", help="survey half-aperture of the PSF in m (0 = no limit: "
                                          "constant angle); default: the source store's")
    p.add_argument("--out", required=True, help="new store path")
    p.add_argument("--overwrite", action="store_true", help="replace --out if it is a demseis store")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.set_defaults(func=cmd_render)

    p = sub.add_parser("relabel", help="new labels for a store's particle snapshots (same seismic)")
    p.add_argument("store", metavar="STORE", help="source store (its DEM snapshots are reused)")
    p.add_argument("--labels", required=True,
                   help="TOML file with a [labels] table (keys not given take their defaults)")
    p.add_argument("--out", required=True, help="new store path")
    p.add_argument("--overwrite", action="store_true", help="replace --out if it is a demseis store")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.set_defaults(func=cmd_relabel)

    p = sub.add_parser("params", help="list every parameter: section, level, unit, range, default",
                       description="Print the declared parameters (demseis.parameters): the "
                       "config section, where each is drawn (sweep, run or sample), its unit, "
                       "allowed range and default. docs/parameters.md holds the same table.")
    p.add_argument("--markdown", action="store_true", help="print the Markdown table of the docs")
    p.set_defaults(func=cmd_params)


def cmd_generate(args: argparse.Namespace) -> int:
    from demseis.api import WorkersWarning, generate, workers_warning
    from demseis.generator.config.settings import load_config
    from demseis.generator.sweep.driver import dry_run_plan, pending_runs

    if args.like:
        if args.config is not None:
            raise InputError("give a CONFIG or --like SECTION, not both (demseis fit writes the "
                             "fitted config to a file you can edit)")
        from demseis.generator.config.settings import parse_config
        from demseis.survey_fit import fit

        dt = None if args.dt_ms is None else args.dt_ms / 1000.0
        print(f"fitting the config to {', '.join(args.like)} (demseis fit) ...", file=sys.stderr)
        fitted = fit(args.like, None, dt_s=dt, trace_spacing_m=args.trace_spacing_m,
                     preset=args.preset or "field")
        print(fitted.table())
        cfg = parse_config(fitted.config)
    elif args.dt_ms is not None or args.trace_spacing_m is not None:
        raise InputError("--dt-ms and --trace-spacing-m go with --like SECTION")
    else:
        cfg = load_config(args.config, preset=args.preset)
    if args.dry_run:  # what this command would compute into --out now (nothing is written)
        pending, why = pending_runs(cfg, args.out, overwrite=args.overwrite)
        print("\n".join(dry_run_plan(cfg, pending, why)))
        return 0
    if args.workers is not None and args.scheduler is not None:
        raise InputError("give either --workers or --scheduler, not both")
    warning = workers_warning(args.workers)
    if warning:
        print(f"demseis: warning: --{warning}", file=sys.stderr)
    with warnings.catch_warnings():  # printed above, once
        warnings.simplefilter("ignore", WorkersWarning)
        store = generate(cfg, out=args.out, workers=args.workers, scheduler=args.scheduler,
                         overwrite=args.overwrite, progress=not args.quiet)
    print("\n".join(store.run_summary.lines()))
    return 1 if store.run_summary.failed else 0


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
    from demseis.generator.sweep.rerender import rerender

    freqs = _float_list(args.freq, "--freq")
    snrs = _float_list(args.snr, "--snr")
    imaging = None
    if args.imaging is not None:
        from demseis.parameters import PARAMS

        allowed = PARAMS["imaging"].choices
        imaging = [part.strip() for part in args.imaging.split(",")]
        bad = [m for m in imaging if m not in allowed]
        if bad:
            raise InputError(f"--imaging {args.imaging!r}: {bad[0]!r} is not one of "
                             + ", ".join(repr(c) for c in allowed))
    angles = None if args.psf_max_angle is None else _float_list(args.psf_max_angle,
                                                                  "--psf-max-angle")
    aperture = None
    if args.psf_aperture is not None:
        vals = _float_list(args.psf_aperture, "--psf-aperture")
        if len(vals) != 1:
            raise InputError(f"--psf-aperture {args.psf_aperture!r}: give one value in m")
        aperture = vals[0]
    try:
        summary = rerender(args.store, args.out, freqs_hz=freqs, snrs_db=snrs,
                           noise_kind=args.noise, imaging=imaging, psf_max_angles_deg=angles,
                           psf_aperture_m=aperture, overwrite=args.overwrite,
                           progress=not args.quiet)
    except ConfigError as exc:
        raise ConfigError(_flag_message(str(exc))) from None
    print("\n".join(summary.lines()))
    return 1 if summary.failed else 0


#: the config key each ``demseis render`` flag sets, so that an error names the flag typed
RENDER_FLAGS = {"freq_hz": "--freq", "snr_db": "--snr", "noise_kind": "--noise",
                "imaging": "--imaging", "psf_max_angle_deg": "--psf-max-angle",
                "psf_aperture_m": "--psf-aperture"}


def _flag_message(message: str) -> str:
    """A config error about a key that a ``render`` flag set, reworded to name the flag:
    ``sweep.freq_hz[0] = 0.0 is not allowed: ...`` -> ``--freq 0.0 is not allowed: ...``."""
    m = re.match(r"sweep\.(\w+)(?:\[\d+\])? = ", message)
    if m is None or m.group(1) not in RENDER_FLAGS:
        return message
    return f"{RENDER_FLAGS[m.group(1)]} {message[m.end():]}"


def cmd_relabel(args: argparse.Namespace) -> int:
    from demseis.generator.sweep.rerender import relabel

    try:
        with open(args.labels, "rb") as fh:
            table = tomllib.load(fh)
    except FileNotFoundError:
        raise InputError(f"--labels {args.labels!r}: no such file") from None
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(f"--labels {args.labels!r}: not valid TOML ({exc})") from None
    unknown = sorted(set(table) - {"labels"})
    if unknown or not isinstance(table.get("labels", {}), dict):
        raise ConfigError(f"--labels {args.labels!r}: expected only a [labels] table, "
                          f"got {', '.join(unknown) or 'labels = a non-table'}")
    summary = relabel(args.store, args.out, labels=table.get("labels", {}),
                      overwrite=args.overwrite, progress=not args.quiet)
    print("\n".join(summary.lines()))
    return 1 if summary.failed else 0


def cmd_params(args: argparse.Namespace) -> int:
    from demseis.parameters import markdown_table, text_table

    print(markdown_table() if args.markdown else text_table(), end="")
    return 0
