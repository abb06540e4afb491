"""Train a small 2D U-Net on a demseis store for a few minutes on CPU, then score it.

Usage::

    python examples/train_unet.py STORE [--minutes 5] [--out-dir runs/unet] [--tolerance 2]

What it does:

1. trains a 3-level U-Net (16-32-64 channels, ~120k parameters; the training loop is
   :func:`demseis.learning.train.train_unet`, shared with ``benchmarks/learnability.py``) on
   random crops of the ``train`` split of the store (seismic in, fault mask out) with
   binary cross-entropy (positive weight = background/fault pixel ratio, capped at 50) plus soft
   Dice, Adam, for a wall-clock budget, with augmentation (left-right and polarity flips,
   amplitude scaling, random crops) and a progress bar; every ``--val-every`` steps it scores
   the ``val`` split (runs never trained on) and keeps the best model by validation F1
   (checkpointed to ``unet.pt``), stopping after ``--patience`` evaluations without gain;
2. predicts fault probabilities on the whole sections of the ``test`` split (DEM runs never seen
   in training) and writes ``unet_test.npy`` with ``test_indices.npy`` (store index of each row);
3. runs the no-learning baseline (``--baseline-method``, default ``dip``: coherence-weighted
   reflector dip; or ``semblance``) on the same test sections (``baseline_test.npy``);
4. scores both with ``demseis.score(pred, store, indices=..., by=("freq_hz", "snr_db",
   "dip_deg"))`` (what ``demseis score`` does) and prints the tables (CSV and JSON land next to
   the predictions).

It uses only the public API: ``demseis.open``, ``Store.torch_dataset``, ``demseis.score`` and
the baseline of :mod:`demseis.evaluation`.

Everything is seeded (``--seed``); on CPU, PyTorch's results are repeatable for a fixed thread
count. The time budget makes the number of steps depend on the machine, so the script prints it.
"""

from __future__ import annotations

import argparse
import os
import sys

import numpy as np


def train(args: argparse.Namespace) -> tuple[object, dict]:
    """Train for ``args.minutes`` of wall clock; returns the model and a log dict."""
    from demseis.learning.train import train_unet

    return train_unet(args.store, minutes=args.minutes, crop=args.crop, batch=args.batch,
                      base=args.base, lr=args.lr, seed=args.seed, threads=args.threads,
                      augment=not args.no_augment, val_every=args.val_every or None,
                      patience=args.patience, checkpoint=os.path.join(args.out_dir, "unet.pt"),
                      progress=True, log=None)


def run_score(pred: str, store, indices: np.ndarray, tolerance: float, by: str,
              bins: int) -> int:
    """Score predictions of the test samples; print the table, write CSV and JSON beside them."""
    import demseis

    groups = tuple(s.strip() for s in by.split(",") if s.strip())
    result = demseis.score(np.load(pred, mmap_mode="r"), store, indices=indices,
                           tolerance_px=tolerance, by=groups, bins=bins)
    print(f"\nscores of {pred} (tolerance {tolerance:g} px, {result.counts.n_samples} samples)")
    print(result.table())
    print(result.summary_line())
    prefix = pred.removesuffix(".npy") + ".score"
    print("wrote " + ", ".join(result.write(prefix, meta={"predictions": pred, "by": list(groups)})),
          flush=True)
    return 0


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("store", help="demseis store (from `demseis generate`)")
    ap.add_argument("--out-dir", default="runs/unet", help="where predictions and scores go")
    ap.add_argument("--minutes", type=float, default=5.0, help="training wall-clock budget")
    ap.add_argument("--crop", type=int, default=96, help="training crop size (multiple of 4)")
    ap.add_argument("--batch", type=int, default=8)
    ap.add_argument("--base", type=int, default=16, help="channels of the first U-Net level")
    ap.add_argument("--lr", type=float, default=2e-3)
    ap.add_argument("--threads", type=int, default=2, help="torch CPU threads")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--tolerance", type=float, default=2.0, help="scoring tolerance in pixels")
    ap.add_argument("--by", default="freq_hz,snr_db,dip_deg", help="scoring breakdown")
    ap.add_argument("--bins", type=int, default=3, help="bins of drawn parameters (dip)")
    ap.add_argument("--val-every", type=int, default=50,
                    help="steps between validation scores (0 = no validation)")
    ap.add_argument("--patience", type=int, default=5, help="validations without gain to stop")
    ap.add_argument("--no-augment", action="store_true", help="no flips / amplitude scaling")
    ap.add_argument("--baseline-method", choices=("dip", "semblance"), default="dip")
    args = ap.parse_args(argv)

    import torch

    import demseis
    from demseis.evaluation import baseline_fault_probability
    from demseis.learning.train import predict_sections

    os.makedirs(args.out_dir, exist_ok=True)
    model, info = train(args)
    torch.save(model.state_dict(), os.path.join(args.out_dir, "unet.pt"))  # the best model
    if "best_val_f1" in info:
        print(f"best val F1@2 {info['best_val_f1']:.4f} at step {info['best_step']} of "
              f"{info['steps']}" + (" (stopped early)" if info["stopped_early"] else ""))

    store = demseis.open(args.store)
    test = store.torch_dataset(inputs=("seismic",), targets=("fault",), split="test")
    if len(test) == 0:
        raise SystemExit("the test split of the store is empty")
    seis = np.stack([test[i][0][0].numpy() for i in range(len(test))])
    idx_path = os.path.join(args.out_dir, "test_indices.npy")
    np.save(idx_path, test.indices)
    unet_path = os.path.join(args.out_dir, "unet_test.npy")
    np.save(unet_path, predict_sections(model, seis))
    base_path = os.path.join(args.out_dir, "baseline_test.npy")
    np.save(base_path, baseline_fault_probability(seis, args.baseline_method))
    print(f"\npredicted {len(test)} test sections ({len(np.unique(test.run_ids))} runs)")
    rc = run_score(base_path, store, test.indices, args.tolerance, args.by, args.bins)
    rc = rc or run_score(unet_path, store, test.indices, args.tolerance, args.by, args.bins)
    return rc


if __name__ == "__main__":
    sys.exit(main())
