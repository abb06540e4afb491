"""``demseis score``, ``demseis baseline`` and ``demseis realism``: benchmark predictions
against a store, and a store against a field section."""

from __future__ import annotations

import argparse

from demseis.cli._args import nonneg_int, pos_int

# Each handler is named "evaluate:FUNCTION", a function of demseis.cli.commands.evaluate,
# imported when its command runs (demseis.cli), so that `demseis --help` stays light.


def register(sub: argparse._SubParsersAction) -> None:
    """Add ``score`` and ``baseline``."""
    p = sub.add_parser(
        "score",
        help="precision / recall / F1 / IoU of fault predictions against a store's labels or "
        "a picked mask",
        description="Score fault predictions (a .npy file or Zarr array of shape (N, H, W), or "
        "a SEG-Y section from 'demseis predict', probabilities in [0, 1]) against the 'fault' "
        "labels of a demseis store (a directory), or against a hand-picked fault mask (a "
        ".npy, .png, .sgy or .segy file: nonzero on a fault; in a PNG every pixel that differs "
        "from the most common value, see docs/scoring.md). Prints a table and writes "
        "<prefix>.csv and <prefix>.json (and <prefix>.samples.csv with --per-sample).",
    )
    p.add_argument("predictions", help="predictions: .npy file or Zarr array of shape (N, H, W), "
                   "a .npy (H, W), or a .sgy/.segy section (N = 1)")
    p.add_argument("truth", metavar="STORE|MASK",
                   help="demseis Zarr store with 'fault' labels, or a mask file (.npy, .png, "
                   ".sgy, .segy) of the predictions' shape")
    p.add_argument("--tolerance", type=float, default=0.0, metavar="PX",
                   help="matching distance in pixels (default 0: exact overlap)")
    p.add_argument("--threshold", type=float, default=0.5,
                   help="a pixel is a predicted fault when pred >= threshold (default 0.5)")
    p.add_argument("--by", default="", metavar="NAMES",
                   help="comma-separated per-sample parameters to group by, e.g. "
                   "freq_hz,snr_db,dip_deg")
    p.add_argument("--bins", type=int, default=4,
                   help="bins for parameters with more than 12 distinct values (default 4)")
    p.add_argument("--indices", default=None, metavar="PATH",
                   help=".npy/.txt file with the store sample index of each prediction row, "
                   "or the indices themselves, e.g. 7 or 3,4,5 (default: row i is sample i and predictions cover the whole store)")
    p.add_argument("--thresholds", type=int, default=99,
                   help="number of thresholds of the ODS/OIS/AP sweep (default 99)")
    p.add_argument("--out-prefix", default=None,
                   help="output path prefix (default: the predictions path without its "
                   "extension, plus '.score')")
    p.add_argument("--per-sample", action="store_true",
                   help="also write one row per sample (<prefix>.samples.csv and in the JSON)")
    p.add_argument("--resize", action="store_true",
                   help="mask only: resample the predictions onto the mask's grid (bilinear, "
                   "pixel centres aligned) when their shapes differ; --tolerance is then in "
                   "mask pixels")
    p.set_defaults(func="evaluate:cmd_score")

    b = sub.add_parser(
        "baseline",
        help="reference fault detector with no learning (reflector dip or semblance)",
        description="Run a no-learning fault detector over every completed sample of a store "
        "and write fault probabilities of shape (N, H, W) (samples of incomplete shards are 0). "
        "Methods: 'dip' (default; coherence-weighted reflector dip from the structure tensor: "
        "demseis layers are deposited flat) or 'semblance' (dip-scanned semblance). Call a "
        "fault at probability >= 0.5 (the default threshold of 'demseis score').",
    )
    b.add_argument("store", metavar="STORE", help="demseis Zarr store with a 'seismic' array")
    b.add_argument("--out", required=True, metavar="PRED",
                   help="output: PATH.npy for a NumPy file, anything else for a Zarr array")
    b.add_argument("--input", default="seismic", help="input array of the store (default seismic)")
    b.add_argument("--method", choices=("dip", "semblance"), default="dip",
                   help="detector (default dip)")
    b.add_argument("--sigma-tensor", type=float, default=4.0,
                   help="dip: structure-tensor smoothing in pixels (default 4)")
    b.add_argument("--half-traces", type=int, default=2,
                   help="semblance: window half-width in traces (default 2)")
    b.add_argument("--half-samples", type=int, default=4,
                   help="semblance: window half-height in samples (default 4)")
    b.add_argument("--max-slope", type=float, default=1.0,
                   help="semblance: largest trial slope, samples per trace (default 1.0)")
    b.add_argument("--overwrite", action="store_true", help="replace an existing output")
    b.set_defaults(func="evaluate:cmd_baseline")

    r = sub.add_parser(
        "realism",
        help="measures of a store beside a field section and field targets",
        description="Measure a store's samples as a field section is measured (dominant period, "
        "zero crossings, adjacent-trace correlation away from faults, amplitude kurtosis; "
        "noise-free samples where the store has some) and its fault labels (apparent dip in "
        "pixels, faults per 100 traces, label fraction, throw), beside the same measures of "
        "a SEG-Y field section (--field) and targets from hand-picked field sections. Prints "
        "a table; with --out writes DIR/realism.json, DIR/realism.md and DIR/realism.png.",
    )
    r.add_argument("store", metavar="STORE", help="demseis Zarr store")
    r.add_argument("--field", default=None, metavar="SECTION.sgy",
                   help="a 2D SEG-Y field section to measure beside the store")
    r.add_argument("--out", default=None, metavar="DIR",
                   help="write realism.json, realism.md and realism.png here")
    r.add_argument("--max-samples", type=pos_int, default=256, metavar="N",
                   help="measure at most N samples, drawn with --seed (default 256)")
    r.add_argument("--seed", type=nonneg_int, default=0, help="seed of that draw (default 0)")
    r.add_argument("--credit", default=None, metavar="TEXT",
                   help="a line printed under the figure, e.g. the field data's licence")
    r.set_defaults(func="evaluate:cmd_realism")

    f = sub.add_parser(
        "fit",
        help="a config whose sections look like a survey's (sampling, wavelet, noise)",
        description="Measure one or more sections of a survey (SEG-Y; a .png display image or "
        ".npy with --dt-ms and --trace-spacing-m): sampling from the headers, the band, "
        "dominant frequency and phase of the wavelet, noise level, amplitude distribution and "
        "clipping; write a complete config whose ranges are centred on them, calibrated on "
        "small kinematic stores so that their dominant period, zero crossings, adjacent-trace "
        "correlation and amplitude kurtosis match the sections'. Then: demseis generate OUT.toml "
        "--out STORE; demseis realism STORE --field SECTION.",
    )
    f.add_argument("sections", nargs="+", metavar="SECTION",
                   help="SEG-Y sections of one survey (or .png / .npy with the sampling given)")
    f.add_argument("--out", required=True, metavar="SURVEY.toml", help="the config to write")
    f.add_argument("--dt-ms", type=float, default=None, metavar="MS",
                   help="sample interval (ms) where the headers do not give it (overrides them)")
    f.add_argument("--trace-spacing-m", type=float, default=None, metavar="M",
                   help="trace spacing (m) where the headers do not give it (overrides them)")
    f.add_argument("--preset", default="field",
                   help="the preset whose geology and faults the config keeps (default field)")
    f.add_argument("--rounds", type=nonneg_int, default=3,
                   help="calibration rounds on small kinematic stores (default 3; 0 = none)")
    f.add_argument("--spread", choices=("fit", "preset"), default="fit",
                   help="ranges around the fitted centre: fit = the survey's look only "
                   "(frequency +-10%%, SNR +-3 dB; default), preset = the preset's spread of "
                   "frequency, SNR and noise kind moved onto the survey's centre")
    f.set_defaults(func="evaluate:cmd_fit")
