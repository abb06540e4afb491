"""The handlers of ``demseis generate``, ``render``, ``relabel`` and ``params``; their parsers
are in :mod:`demseis.cli.generate`."""

from __future__ import annotations

import argparse
import re
import sys
import tomllib
import warnings

from demseis.api import WorkersWarning, generate, workers_warning
from demseis.errors import ConfigError, InputError
from demseis.generator.config.settings import load_config, parse_config
from demseis.generator.sweep.driver import dry_run_plan, pending_runs
from demseis.generator.sweep.rerender import fitted_look, relabel, rerender
from demseis.parameters import PARAMS, markdown_table, text_table
from demseis.survey_fit import fit


def cmd_generate(args: argparse.Namespace) -> int:
    if args.like:
        if args.config is not None:
            raise InputError("give a CONFIG or --like SECTION, not both (demseis fit writes the "
                             "fitted config to a file you can edit)")

        dt = None if args.dt_ms is None else args.dt_ms / 1000.0
        print(f"fitting the config to {', '.join(args.like)} (demseis fit) ...", file=sys.stderr)
        fitted = fit(args.like, None, dt_s=dt, trace_spacing_m=args.trace_spacing_m,
                     preset=args.preset or "field", spread=args.spread or "fit")
        print(fitted.table())
        cfg = parse_config(fitted.config)
    elif args.dt_ms is not None or args.trace_spacing_m is not None or args.spread is not None:
        raise InputError("--dt-ms, --trace-spacing-m and --spread go with --like SECTION")
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


def _toml_file(path: str, flag: str) -> dict:
    """The TOML file ``path`` given to ``flag``, read; a missing or invalid file is an error
    naming the flag."""
    try:
        with open(path, "rb") as fh:
            return tomllib.load(fh)
    except FileNotFoundError:
        raise InputError(f"{flag} {path!r}: no such file") from None
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(f"{flag} {path!r}: not valid TOML ({exc})") from None


def _render_look(args: argparse.Namespace) -> dict | None:
    """The look of ``demseis render``: the --config TOML, or the look fitted to --like."""
    if args.like and args.config:
        raise InputError("give --config LOOK.toml or --like SECTION, not both")
    if not args.like:
        if args.dt_ms is not None or args.trace_spacing_m is not None or args.spread is not None:
            raise InputError("--dt-ms, --trace-spacing-m and --spread go with --like SECTION")
        return _toml_file(args.config, "--config") if args.config else None
    dt = None if args.dt_ms is None else args.dt_ms / 1000.0
    print(f"fitting a look to {', '.join(args.like)} (demseis fit) ...", file=sys.stderr)
    fitted = fit(args.like, None, dt_s=dt, trace_spacing_m=args.trace_spacing_m,
                 spread=args.spread or "fit")
    print(fitted.table())
    return fitted_look(fitted.config)


def cmd_render(args: argparse.Namespace) -> int:
    look = _render_look(args)
    freqs = None if args.freq is None else _float_list(args.freq, "--freq")
    if freqs is None and (args.snr is not None or args.noise is not None):
        raise InputError("--snr and --noise go with --freq")
    snrs = None if args.snr is None else _float_list(args.snr, "--snr")
    imaging = None
    if args.imaging is not None:
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
    if freqs is None and imaging is None and angles is None and aperture is None and not look:
        raise InputError("give what to render: --freq, --config LOOK.toml, --like SECTION or "
                         "an imaging flag")
    try:
        summary = rerender(args.store, args.out, freqs_hz=freqs, snrs_db=snrs,
                           noise_kind=args.noise, imaging=imaging, psf_max_angles_deg=angles,
                           psf_aperture_m=aperture, look=look, overwrite=args.overwrite,
                           progress=not args.quiet)
    except ConfigError as exc:
        flags = {flag for flag in RENDER_FLAGS.values()
                 if getattr(args, flag[2:].replace("-", "_")) is not None}
        source = f"--config {args.config!r}" if args.config else ("--like" if args.like else "")
        raise ConfigError(_flag_message(str(exc), flags, source)) from None
    print("\n".join(summary.lines()))
    return 1 if summary.failed else 0


RENDER_FLAGS = {"freq_hz": "--freq", "snr_db": "--snr", "noise_kind": "--noise",
                "imaging": "--imaging", "psf_max_angle_deg": "--psf-max-angle",
                "psf_aperture_m": "--psf-aperture"}


def _flag_message(message: str, flags: set[str], source: str = "") -> str:
    """A config error about a key that one of the ``render`` ``flags`` given set, reworded to
    name the flag: ``sweep.freq_hz[0] = 0.0 is not allowed: ...`` -> ``--freq 0.0 is not
    allowed: ...``; any other error is prefixed with ``source`` (the look's file)."""
    m = re.match(r"sweep\.(\w+)(?:\[\d+\])? = ", message)
    if m is None or RENDER_FLAGS.get(m.group(1)) not in flags:
        return f"{source}: {message}" if source else message
    return f"{RENDER_FLAGS[m.group(1)]} {message[m.end():]}"


def cmd_relabel(args: argparse.Namespace) -> int:
    table = _toml_file(args.labels, "--labels")
    unknown = sorted(set(table) - {"labels"})
    if unknown or not isinstance(table.get("labels", {}), dict):
        raise ConfigError(f"--labels {args.labels!r}: expected only a [labels] table, "
                          f"got {', '.join(unknown) or 'labels = a non-table'}")
    summary = relabel(args.store, args.out, labels=table.get("labels", {}),
                      overwrite=args.overwrite, progress=not args.quiet)
    print("\n".join(summary.lines()))
    return 1 if summary.failed else 0


def cmd_params(args: argparse.Namespace) -> int:
    print(markdown_table() if args.markdown else text_table(), end="")
    return 0
