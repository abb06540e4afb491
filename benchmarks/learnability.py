"""How well a U-Net learns a store's fault labels: train on the train runs, score held-out runs.

Trains the examples' U-Net (:func:`demseis.learning.train.train_unet`) for a fixed number of
steps on random crops of the ``train`` runs of STORE, predicts whole sections of (a sample of)
the train runs and of the held-out runs, and scores both against the store's ``fault`` labels
at tolerances 2 and 4 px (precision / recall / F1 at threshold 0.5, and AP). Prints one JSON
line. CUDA when present (default 3000 steps, base 32), else a CPU budget (default 300 steps,
base 16). Runs are split 75 / 0 / 25 % train / val / test by default (held-out = test).

A fixed threshold of 0.5 favours whichever label set the loss's positive weight happens to
suit (it is capped at 50, and sparse labels hit the cap), so the line also gives, per
tolerance, the threshold that maximises the pooled F1 on the *train* runs
(``train_ods_threshold_tol*``) and the held-out F1 at that threshold
(``test_f1_at_train_threshold_tol*``): a threshold chosen without looking at the held-out runs.
``test_ods_f1_tol*`` (the held-out runs' own best threshold) is an optimistic ceiling, for
reference only.

Which labels the network misses: ``test_recall_by_slip_tol2`` is the held-out recall at 2 px
(at the train-chosen threshold) of the labelled pixels grouped by their ``slip_m`` (m; labels
without a slip value, e.g. the legacy strain band's, are left out), with the pixel counts.

Comparing label sets: make stores that differ only in their labels with ``demseis relabel``
(same seismic bytes), then run this on each with the same ``--seed`` and budget. Each run is
then scored against its own labels. ``--reference REF`` scores against REF's labels instead
(train threshold, held-out figures, recall by slip), training still on STORE's: a fixed truth
for label sets that change what is counted as a fault (another ``min_slip_m``, a thicker
mask). REF must hold the same samples with the same seismic bytes (a relabel of STORE, or
STORE the relabel of REF); every scored sample is checked.

    PYTHONPATH=$PWD python benchmarks/learnability.py STORE [--steps N] [--seed 0]
        [--train-runs N] [--save-pred PRED.npz] [--reference REF] [--ignore ARRAY[=V,V]]
        [--score-without ARRAY[=V,V]]

Pixels where the labels are in doubt: ``--ignore ARRAY[=V,V]`` trains with them left out
of the loss (``train_unet(ignore=)``; ``fault_uncertain`` marks where label and visible
offsets disagree, docs/labels.md), and ``--score-without ARRAY[=V,V]`` adds every score with
them left out (prediction 0 and no label there; a prediction within the tolerance of a
left-out label still counts against the rest), suffixed ``_kept``.

``--save-pred`` writes a few held-out sections (seismic, labels, predicted probabilities, the
train-chosen thresholds) for ``benchmarks/learnability_figure.py``, which draws label sets side
by side.
"""

from __future__ import annotations

import argparse
import json
import platform
import time

import numpy as np


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("store")
    ap.add_argument("--steps", type=int, help="optimiser steps (default 3000 CUDA / 300 CPU)")
    ap.add_argument("--base", type=int, help="U-Net base width (default 32 CUDA / 16 CPU)")
    ap.add_argument("--crop", type=int, default=96)
    ap.add_argument("--batch", type=int, default=8)
    ap.add_argument("--lr", type=float, default=2e-3)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--threads", type=int, default=2, help="torch CPU threads")
    ap.add_argument("--test-fraction", type=float, default=0.25, help="share of runs held out")
    ap.add_argument("--max-train-eval", type=int, default=96,
                    help="train samples scored (a fixed random subset)")
    ap.add_argument("--device", help="cuda / cpu (default: cuda when available)")
    ap.add_argument("--train-runs", type=int,
                    help="train on the first N train runs only, the held-out runs unchanged "
                         "(a learning curve on one store: e.g. 64 against all 96 of 128 runs)")
    ap.add_argument("--save-pred", help="write held-out sections and predictions (.npz)")
    ap.add_argument("--save-n", type=int, default=4, help="held-out sections saved")
    ap.add_argument("--reference", help="score against this relabelled store's labels")
    ap.add_argument("--no-progress", action="store_true", help="no training progress bar on stderr")
    ap.add_argument("--ignore", metavar="ARRAY[=V,V]",
                    help="train with these pixels left out of the loss (train_unet(ignore=))")
    ap.add_argument("--score-without", metavar="ARRAY[=V,V]",
                    help="also score with these pixels left out (prediction 0 and no label "
                         "there): the *_kept figures")
    ap.add_argument("--pos-weight", type=float, metavar="W",
                    help="the fault pixels' weight in the cross-entropy (train_unet(pos_weight=)"
                         "; default: the background / fault ratio, at most 50)")
    args = ap.parse_args(argv)

    import torch

    from demseis.datasets import FaultSegDataset
    from demseis.evaluation import score
    from demseis.learning.train import ignored_pixels, parse_ignore, predict_sections, train_unet

    cuda = torch.cuda.is_available() if args.device is None else args.device.startswith("cuda")
    steps = args.steps or (3000 if cuda else 300)
    base = args.base or (32 if cuda else 16)
    fr = (1.0 - args.test_fraction, 0.0, args.test_fraction)
    where = None
    if args.train_runs is not None:
        train_runs = np.unique(FaultSegDataset(args.store, inputs=("seismic",), targets=("fault",),
                                               split="train", split_fractions=fr).run_ids)
        if not 0 < args.train_runs <= train_runs.size:
            raise SystemExit(f"--train-runs {args.train_runs}: the store has {train_runs.size} "
                             "train runs")
        where = {"run_id": [int(r) for r in train_runs[:args.train_runs]]}
    ignore, ignore_values = parse_ignore(args.ignore)
    without, without_values = parse_ignore(args.score_without)
    t0 = time.perf_counter()
    model, info = train_unet(args.store, steps=steps, crop=args.crop, batch=args.batch,
                             base=base, lr=args.lr, seed=args.seed, threads=args.threads,
                             device=args.device, split_fractions=fr, log=None, where=where,
                             progress=not args.no_progress, ignore=ignore,
                             ignore_values=ignore_values, pos_weight=args.pos_weight)
    out: dict = {"benchmark": "learnability", "store": args.store, "steps": info["steps"],
                 "base": base, "crop": args.crop, "batch": args.batch, "seed": args.seed,
                 "device": info["device"], "train_seconds": info["seconds"],
                 "final_loss": round(info["final_loss"], 4), "pos_weight": info["pos_weight"]}
    if info["device"] == "cpu":
        out["cpu"] = platform.processor() or platform.machine()
        out["threads"] = args.threads
    rng = np.random.default_rng(args.seed)
    out["train_runs_used"] = None if where is None else len(where["run_id"])
    truth_store = args.reference or args.store
    if args.reference:
        out["reference"] = args.reference
    if ignore:
        out["ignore"] = [ignore, ignore_values]
        out["ignored_fraction"] = info["ignored_fraction"]
    if without:
        out["score_without"] = [without, without_values]
    for split in ("train", "test"):
        kw = dict(inputs=("seismic",), split=split, split_fractions=fr,
                  where=where if split == "train" else None)
        ds = FaultSegDataset(truth_store, targets=("fault",), **kw)
        with_slip = split == "test" and "slip_m" in ds.layout.arrays
        extra = (("slip_m",) if with_slip else ()) + ((without,) if without else ())
        if extra:  # the held-out slip, the pixels left out of a score, with the same samples
            ds = FaultSegDataset(truth_store, targets=("fault", *extra), **kw)
        idx = np.arange(len(ds))
        if split == "train" and len(ds) > args.max_train_eval:
            idx = np.sort(rng.choice(len(ds), args.max_train_eval, replace=False))
        pairs = [ds[int(i)] for i in idx]
        seis = np.stack([x[0].numpy() for x, _ in pairs])
        if args.reference:
            same_seismic(FaultSegDataset(args.store, targets=("fault",), **kw), ds, idx, seis,
                         args.store, args.reference)
        fault = [y["fault"] if extra else y for _, y in pairs]
        truth = np.stack([(y.numpy() > 0) for y in fault])
        prob = predict_sections(model, seis, device=info["device"])
        out[f"{split}_samples"] = len(idx)
        out[f"{split}_runs"] = int(len(np.unique(ds.run_ids[idx])))
        scored = [("", prob, truth)]
        if without:
            u = np.stack([y[without].numpy() for _, y in pairs])
            left_out = ignored_pixels(u, without_values)
            scored.append(("_kept", np.where(left_out, 0.0, prob), truth & ~left_out))
            out[f"{split}_left_out_fraction"] = round(float(left_out.mean()), 4)
        for suffix, p_, t_ in scored:
            for tol in (2, 4):
                r = score(p_, t_, threshold=0.5, tolerance_px=tol)
                for k in ("precision", "recall", "f1", "ap", "ods_f1"):
                    out[f"{split}_{k}_tol{tol}{suffix}"] = round(float(getattr(r, k)), 4)
                if split == "train":
                    out[f"train_ods_threshold_tol{tol}{suffix}"] = round(float(r.ods_threshold),
                                                                         4)
                else:  # the held-out F1 at the threshold chosen on the train runs (same sweep)
                    k = int(np.argmin(np.abs(r.thresholds
                                             - out[f"train_ods_threshold_tol{tol}{suffix}"])))
                    out[f"test_f1_at_train_threshold_tol{tol}{suffix}"] = round(
                        float(r.f1_curve[k]), 4)
        if with_slip:
            slip = np.stack([y["slip_m"].numpy() for _, y in pairs])
            out["test_recall_by_slip_tol2"] = recall_by_slip(
                prob >= out["train_ods_threshold_tol2"], truth, slip, 2)
        if split == "test" and args.save_pred:
            save_predictions(args.save_pred, seis, truth, prob, idx, out, args.save_n)
    out["f1_gap_tol2"] = round(out["train_f1_tol2"] - out["test_f1_tol2"], 4)
    out["ods_f1_gap_tol2"] = round(out["train_ods_f1_tol2"]
                                   - out["test_f1_at_train_threshold_tol2"], 4)
    out["seconds"] = round(time.perf_counter() - t0, 1)
    print(json.dumps(out))
    return 0


def same_seismic(ds, ref_ds, idx: np.ndarray, ref_seis: np.ndarray, store: str, ref: str) -> None:
    """Exit with a message unless ``ds`` (STORE) holds the samples ``idx`` of ``ref_ds`` (REF)
    with the same run ids and seismic bytes (REF must be a relabel of STORE or the reverse)."""
    if len(ds) != len(ref_ds) or not np.array_equal(ds.run_ids, ref_ds.run_ids):
        raise SystemExit(f"--reference {ref}: its runs or samples differ from {store}'s; the "
                         "reference must be the same store relabelled (demseis relabel)")
    for j, i in enumerate(idx):
        if not np.array_equal(ds[int(i)][0][0].numpy(), ref_seis[j]):
            raise SystemExit(f"--reference {ref}: the seismic of sample {int(i)} differs from "
                             f"{store}'s; the reference must be the same store relabelled "
                             "(demseis relabel)")


SLIP_BANDS_M = (10.0, 20.0, 40.0, 80.0, 160.0, np.inf)


def recall_by_slip(pred: np.ndarray, truth: np.ndarray, slip: np.ndarray,
                   tol: float) -> dict[str, list]:
    """Recall (share of labelled pixels with a predicted pixel within ``tol`` px) per slip band.

    Returns ``{"lo-hi": [recall, pixels]}`` over the bands of :data:`SLIP_BANDS_M`, plus
    ``"below"`` for labelled pixels with 0 < slip < the first band edge.
    """
    from demseis.evaluation.scoring import within_tolerance  # the scorer's matching rule

    hit = np.stack([within_tolerance(p, tol) for p in pred])
    lab = truth & (slip > 0)
    edges = (0.0,) + SLIP_BANDS_M
    res = {}
    for lo, hi in zip(edges[:-1], edges[1:]):
        m = lab & (slip >= lo) & (slip < hi)
        n = int(m.sum())
        key = "below" if lo == 0.0 else f"{lo:g}-{hi:g}"
        res[key] = [round(float(hit[m].mean()), 4) if n else None, n]
    return res


def save_predictions(path: str, seis: np.ndarray, truth: np.ndarray, prob: np.ndarray,
                     idx: np.ndarray, out: dict, n: int) -> None:
    """Write ``n`` held-out sections with faults, evenly spaced over the held-out samples."""
    faulted = np.flatnonzero(truth.reshape(len(truth), -1).any(axis=1))
    pick = faulted[np.linspace(0, faulted.size - 1, min(n, faulted.size)).round().astype(int)] \
        if faulted.size else np.zeros(0, int)
    np.savez_compressed(path, seismic=seis[pick], truth=truth[pick], prob=prob[pick],
                        sample=idx[pick], threshold_tol2=out["train_ods_threshold_tol2"],
                        store=out["store"], result=json.dumps(out))


if __name__ == "__main__":
    raise SystemExit(main())
