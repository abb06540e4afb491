"""``demseis generate``, ``render``, ``relabel`` and ``params``: write a dataset, re-render or
relabel a store's snapshots, list the parameters a config may set."""

from __future__ import annotations

import argparse

from demseis.cli._args import nonneg_int

# Each handler is named "generate:FUNCTION", a function of demseis.cli.commands.generate,
# imported when its command runs (demseis.cli), so that `demseis --help` stays light.


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
    _add_like_options(p)
    p.set_defaults(func="generate:cmd_generate")

    p = sub.add_parser(
        "render", help="re-render a store's particle snapshots: new frequencies / SNRs, or "
        "another survey's look",
        description="Write a new store with every run of STORE drawn again from its particle "
        "snapshots, without the DEM: at a grid of frequencies and SNRs (--freq, --snr), with "
        "the rendering keys of a config (--config: [output], [labels], the sample-level "
        "[sweep] keys and [sweep] fault_zone_impedance), or with the look of a survey's "
        "sections (--like: demseis fit's sampling, wavelet, noise and processing). A run's "
        "samples equal those demseis generate writes with the same config.")
    p.add_argument("store", metavar="STORE", help="source store (its DEM snapshots are reused)")
    p.add_argument("--freq", help="comma-separated Ricker frequencies in Hz, e.g. 20,40,60 "
                                  "(one render per snapshot and frequency and SNR)")
    p.add_argument("--snr", help="with --freq: comma-separated SNRs in dB (inf = no noise), "
                                 "default inf")
    p.add_argument("--noise", choices=("white", "band", "coloured"),
                   help="with --freq: noise kind (coloured: power spectrum f^-1), default white")
    p.add_argument("--config", metavar="LOOK.toml",
                   help="TOML whose [output], [labels] and sample-level [sweep] keys replace the "
                        "store's (any other key must equal the store's)")
    p.add_argument("--like", action="append", metavar="SECTION",
                   help="fit a look to this survey section (demseis fit on the field preset; "
                        "repeatable) and render with its sampling, wavelet, noise and processing")
    _add_like_options(p)
    p.add_argument("--imaging", help="comma-separated imaging: 1d, psf (2-D dip-limited PSF), or "
                                     "both; default: the source store's")
    p.add_argument("--psf-max-angle", help="comma-separated maximum illumination angles of the PSF "
                                           "in degrees, e.g. 20,45; default: the source store's")
    p.add_argument("--psf-aperture", help="survey half-aperture of the PSF in m (0 = no limit: "
                                          "constant angle); default: the source store's")
    p.add_argument("--out", required=True, help="new store path")
    p.add_argument("--overwrite", action="store_true", help="replace --out if it is a demseis store")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.set_defaults(func="generate:cmd_render")

    p = sub.add_parser("relabel", help="new labels for a store's particle snapshots (same seismic)")
    p.add_argument("store", metavar="STORE", help="source store (its DEM snapshots are reused)")
    p.add_argument("--labels", required=True,
                   help="TOML file with a [labels] table (keys not given take their defaults)")
    p.add_argument("--out", required=True, help="new store path")
    p.add_argument("--overwrite", action="store_true", help="replace --out if it is a demseis store")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.set_defaults(func="generate:cmd_relabel")

    p = sub.add_parser("params", help="list every parameter: section, level, unit, range, default",
                       description="Print the declared parameters (demseis.parameters): the "
                       "config section, where each is drawn (sweep, run or sample), its unit, "
                       "allowed range and default. docs/parameters.md holds the same table.")
    p.add_argument("--markdown", action="store_true", help="print the Markdown table of the docs")
    p.set_defaults(func="generate:cmd_params")


def _add_like_options(p: argparse.ArgumentParser) -> None:
    """The options that go with ``--like SECTION`` (those of ``demseis fit``)."""
    p.add_argument("--dt-ms", type=float, default=None, metavar="MS",
                   help="with --like: the sample interval where the headers do not give it")
    p.add_argument("--trace-spacing-m", type=float, default=None, metavar="M",
                   help="with --like: the trace spacing where the headers do not give it")
    p.add_argument("--spread", choices=("fit", "preset"), default=None,
                   help="with --like: ranges around the fitted centre (as demseis fit --spread; "
                        "default fit)")
