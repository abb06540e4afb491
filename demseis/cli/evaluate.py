"""``demseis score`` and ``demseis baseline``: benchmark predictions against a store."""

from __future__ import annotations

import argparse
import csv
import json
import os
import sys
from typing import Any

import numpy as np

from demseis.errors import InputError


def register(sub: argparse._SubParsersAction, bench: argparse._SubParsersAction) -> None:
    """Add ``score`` and ``baseline``."""
    p = sub.add_parser(
        "score",
        help="precision / recall / F1 / IoU of fault predictions against a store's labels",
        description="Score fault predictions (a .npy file or Zarr array of shape (N, H, W), "
        "probabilities in [0, 1]) against the 'fault' labels of a demseis store. Prints a "
        "table and writes <prefix>.csv and <prefix>.json (and <prefix>.samples.csv with "
        "--per-sample).",
    )
    p.add_argument("predictions", help="predictions: .npy file or Zarr array, shape (N, H, W)")
    p.add_argument("truth_store", help="demseis Zarr store with 'fault' labels")
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
                   help=".npy/.txt file with the store sample index of each prediction row "
                   "(default: row i is sample i and predictions cover the whole store)")
    p.add_argument("--thresholds", type=int, default=99,
                   help="number of thresholds of the ODS/OIS/AP sweep (default 99)")
    p.add_argument("--out-prefix", default=None,
                   help="output path prefix (default: the predictions path without its "
                   "extension, plus '.score')")
    p.add_argument("--per-sample", action="store_true",
                   help="also write one row per sample (<prefix>.samples.csv and in the JSON)")
    p.set_defaults(func=_score_command)

    b = sub.add_parser(
        "baseline",
        help="reference fault detector with no learning (reflector dip or semblance)",
        description="Run a no-learning fault detector over every completed sample of a store "
        "and write fault probabilities of shape (N, H, W) (samples of incomplete shards are 0). "
        "Methods: 'dip' (default; coherence-weighted reflector dip from the structure tensor: "
        "demseis layers are deposited flat) or 'semblance' (dip-scanned semblance). Call a "
        "fault at probability >= 0.5 (the default threshold of 'demseis score').",
    )
    b.add_argument("store", help="demseis Zarr store with a 'seismic' array")
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
    b.set_defaults(func=_baseline_command)


def _default_prefix(pred_path: str) -> str:
    base = pred_path.rstrip("/\\")
    for ext in (".npy", ".zarr"):
        if base.endswith(ext):
            base = base[: -len(ext)]
    return base + ".score"


def _load_indices(path: str) -> np.ndarray:
    if not os.path.exists(path):
        raise InputError(f"--indices: file {path!r} does not exist")
    try:
        idx = np.load(path) if path.endswith(".npy") else np.loadtxt(path, dtype=np.int64, ndmin=1)
    except Exception as exc:
        raise InputError(f"--indices: cannot read {path!r} ({exc})") from exc
    return np.asarray(idx)


def _json_safe(v: Any) -> Any:
    if isinstance(v, dict):
        return {k: _json_safe(x) for k, x in v.items()}
    if isinstance(v, (list, tuple)):
        return [_json_safe(x) for x in v]
    if isinstance(v, np.generic):
        v = v.item()
    if isinstance(v, float) and not np.isfinite(v):
        return None if np.isnan(v) else ("inf" if v > 0 else "-inf")
    return v


def _score_command(args: argparse.Namespace) -> int:
    from demseis.datasets.read import open_truth
    from demseis.evaluation.scoring import (
        format_table,
        group_rows,
        load_predictions,
        score_store_counts,
        summarise,
    )

    by = [s.strip() for s in args.by.split(",") if s.strip()]
    store = open_truth(args.truth_store)
    for name in by:
        if name not in store.params:
            raise InputError(f"--by {name!r}: the store has per-sample parameters "
                             f"{sorted(store.params)}")
    pred = load_predictions(args.predictions)
    indices = _load_indices(args.indices) if args.indices else None
    counts, sample = score_store_counts(
        pred, store, indices=indices, threshold=args.threshold, tolerance_px=args.tolerance,
        thresholds=args.thresholds, progress=sys.stderr.isatty())
    params = {k: v[sample] for k, v in store.params.items()}
    rows = group_rows(counts, params, by, bins=args.bins)
    overall = summarise(counts)

    print(f"predictions {args.predictions}  store {args.truth_store}  samples {counts.n_samples}"
          f"  threshold {args.threshold:g}  tolerance {args.tolerance:g} px")
    print(format_table(rows))
    print(f"ODS F1 {overall.ods_f1:.3f} at threshold {overall.ods_threshold:.2f}   "
          f"OIS F1 {overall.ois_f1:.3f}   AP {overall.ap:.3f}   "
          f"chance AP (random scores) {overall.chance_ap:.4f}")

    prefix = args.out_prefix or _default_prefix(args.predictions)
    os.makedirs(os.path.dirname(os.path.abspath(prefix)), exist_ok=True)
    cols = ["by", "group", "lo", "hi", "n_samples", "precision", "recall", "f1", "iou", "ap",
            "ods_f1", "chance_ap", "tp", "fp", "fn", "tp_truth"]
    with open(prefix + ".csv", "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=cols)
        w.writeheader()
        for r in rows:
            w.writerow({k: ("" if r[k] is None else r[k]) for k in cols})
    report: dict[str, Any] = {
        "predictions": args.predictions, "store": args.truth_store, "by": by,
        "bins": args.bins, "overall": overall.summary(), "groups": rows,
    }
    if args.per_sample:
        ps = overall.per_sample
        names = sorted(params)
        sample_rows = []
        for j in range(counts.n_samples):
            row: dict[str, Any] = {"sample": int(sample[j])}
            row.update({k: params[k][j] for k in names})
            row.update({k: ps[k][j] for k in ("precision", "recall", "f1", "iou", "tp", "fp",
                                              "fn", "tp_truth", "n_pred", "n_truth")})
            sample_rows.append(_json_safe(row))
        with open(prefix + ".samples.csv", "w", newline="") as fh:
            w = csv.DictWriter(fh, fieldnames=list(sample_rows[0]))
            w.writeheader()
            w.writerows(sample_rows)
        report["per_sample"] = sample_rows
    with open(prefix + ".json", "w") as fh:
        json.dump(_json_safe(report), fh, indent=1)
    written = [prefix + ".csv", prefix + ".json"] + \
        ([prefix + ".samples.csv"] if args.per_sample else [])
    print("wrote " + ", ".join(written))
    return 0


def _baseline_command(args: argparse.Namespace) -> int:
    import zarr
    from tqdm import tqdm

    from demseis.datasets.read import open_sections
    from demseis.evaluation.baseline import (
        SemblanceBaseline,
        dip_fault_probability,
        semblance_fault_probability,
    )

    cfg = SemblanceBaseline(half_traces=args.half_traces, half_samples=args.half_samples,
                            max_slope=args.max_slope)
    if args.method == "dip":
        settings = {"method": "dip", "sigma_tensor_px": args.sigma_tensor}

        def detect(sec: np.ndarray) -> np.ndarray:
            return dip_fault_probability(sec, sigma_tensor_px=args.sigma_tensor)
    else:
        settings = {"method": "semblance", **cfg.__dict__}

        def detect(sec: np.ndarray) -> np.ndarray:
            return semblance_fault_probability(sec, cfg)
    seis, valid = open_sections(args.store, args.input)
    if os.path.exists(args.out) and not args.overwrite:
        raise InputError(f"--out {args.out!r} exists; pass --overwrite to replace it")
    n, h, w = (int(v) for v in seis.shape)
    if args.out.endswith(".npy"):
        out = np.lib.format.open_memmap(args.out + ".part.npy", mode="w+", dtype=np.float32,
                                        shape=(n, h, w))
    else:
        out = zarr.create_array(args.out + ".part", shape=(n, h, w), chunks=(1, h, w),
                                dtype="float32", fill_value=0.0, overwrite=True)
        out.attrs["demseis_baseline"] = {"threshold": 0.5, **settings}
    done = np.flatnonzero(valid)
    for i in tqdm(done, desc="baseline", unit="sample", disable=not sys.stderr.isatty()):
        out[int(i)] = detect(np.asarray(seis[int(i)]))
    if isinstance(out, np.memmap):  # a new memmap is zero-filled: skipped samples stay 0
        out.flush()
        del out
        os.replace(args.out + ".part.npy", args.out)
    else:
        import shutil

        if os.path.exists(args.out):
            shutil.rmtree(args.out)
        os.replace(args.out + ".part", args.out)
    print(f"wrote {args.out}: {done.size} of {n} samples (others are incomplete shards); "
          "call a fault at probability >= 0.5")
    return 0
