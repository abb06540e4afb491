"""The handlers of ``demseis score``, ``baseline``, ``fit`` and ``realism``; their parsers are in
:mod:`demseis.cli.evaluate`."""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

import numpy as np

from demseis.api import score
from demseis.errors import InputError
from demseis.evaluation.baseline import SemblanceBaseline, baseline_store
from demseis.evaluation.fieldio import is_mask_file
from demseis.evaluation.realism_report import (format_report, realism_report, report_json,
                                               report_markdown)
from demseis.plotting import plot_realism
from demseis.survey_fit import fit


def _default_prefix(pred_path: str) -> str:
    base = pred_path.rstrip("/\\")
    for ext in (".npy", ".zarr", ".sgy", ".segy"):
        if base.endswith(ext):
            base = base[: -len(ext)]
    return base + ".score"


def _load_indices(path: str) -> np.ndarray:
    if all(part.strip().isdigit() for part in path.split(",")) and not os.path.exists(path):
        return np.asarray([int(part) for part in path.split(",")], dtype=np.int64)
    if not os.path.exists(path):
        raise InputError(f"--indices: file {path!r} does not exist")
    try:
        idx = np.load(path) if path.endswith(".npy") else np.loadtxt(path, dtype=np.int64, ndmin=1)
    except Exception as exc:
        raise InputError(f"--indices: cannot read {path!r} ({exc})") from exc
    return np.asarray(idx)


def cmd_score(args: argparse.Namespace) -> int:
    by = tuple(s.strip() for s in args.by.split(",") if s.strip())
    mask = is_mask_file(args.truth)
    if mask and (by or args.indices):
        raise InputError(f"{'--by' if by else '--indices'} goes with a store; a mask has no "
                         "store samples or parameters")
    if args.resize and not mask:
        raise InputError("--resize goes with a mask file; predictions scored against a store "
                         "must have its sections' shape")
    indices = _load_indices(args.indices) if args.indices else None
    kw = {"resize": args.resize} if mask else {"indices": indices, "by": by}
    result = score(args.predictions, args.truth, threshold=args.threshold,
                   tolerance_px=args.tolerance, bins=args.bins, thresholds=args.thresholds,
                   progress=sys.stderr.isatty(), **kw)
    what = "mask" if mask else "store"
    print(f"predictions {args.predictions}  {what} {args.truth}  samples "
          f"{result.counts.n_samples}  threshold {args.threshold:g}  tolerance "
          f"{args.tolerance:g} px")
    print(result.table())
    print(result.summary_line())
    prefix = args.out_prefix or _default_prefix(args.predictions)
    written = result.write(prefix, per_sample=args.per_sample,
                           meta={"predictions": args.predictions,
                                 "store": None if mask else args.truth,
                                 **({"mask": args.truth} if mask else {}),
                                 "by": list(by), "bins": args.bins})
    print("wrote " + ", ".join(written))
    return 0


def cmd_baseline(args: argparse.Namespace) -> int:
    done, n = baseline_store(
        args.store, args.out, method=args.method, array=args.input,
        sigma_tensor_px=args.sigma_tensor,
        semblance=SemblanceBaseline(half_traces=args.half_traces, half_samples=args.half_samples,
                                    max_slope=args.max_slope),
        overwrite=args.overwrite, progress=sys.stderr.isatty())
    print(f"wrote {args.out}: {done} of {n} samples (others are incomplete shards); "
          "call a fault at probability >= 0.5")
    return 0


def cmd_fit(args: argparse.Namespace) -> int:
    dt = None if args.dt_ms is None else args.dt_ms / 1000.0
    result = fit(args.sections, args.out, dt_s=dt, trace_spacing_m=args.trace_spacing_m,
                 preset=args.preset, rounds=args.rounds, spread=args.spread,
                 progress=False)
    print(result.table())
    print(f"wrote {args.out}: demseis generate {args.out} --out STORE.zarr")
    return 0


def cmd_realism(args: argparse.Namespace) -> int:
    if args.field is not None and not Path(args.field).is_file():
        raise InputError(f"--field {args.field!r} does not exist")
    report = realism_report(args.store, args.field, max_samples=args.max_samples, seed=args.seed)
    print(format_report(report))
    if args.out:
        out = Path(args.out)
        out.mkdir(parents=True, exist_ok=True)
        (out / "realism.json").write_text(report_json(report))
        (out / "realism.md").write_text(report_markdown(report))
        plot_realism(report, out / "realism.png", credit=args.credit)
        print(f"wrote {out / 'realism.json'}, {out / 'realism.md'}, {out / 'realism.png'}")
    return 0
