"""``demseis train``, ``predict`` and ``threshold``: a fault-segmentation U-Net from a store,
the fault probability of any section (SEG-Y or .npy) with it, and the threshold its faults are
drawn from. They need torch (the ``[torch]`` extra); see :mod:`demseis.learning.model`."""

from __future__ import annotations

import argparse

from demseis.cli._args import nonneg_int, pos_int

# Each handler is named "model:FUNCTION", a function of demseis.cli.commands.model,
# imported when its command runs (demseis.cli), so that `demseis --help` stays light.


def register(sub: argparse._SubParsersAction) -> None:
    """Add ``train``, ``predict`` and ``threshold``."""
    t = sub.add_parser(
        "train", help="train a fault-segmentation U-Net on one or more stores (needs "
        "demseis[torch])",
        description="Train the project's U-Net on a store's training runs (CPU or CUDA), keep "
        "the best model on its validation runs, and print and save precision, recall, F1 and "
        "AP on its test runs (whole runs are held out, so the store needs at least 3). With "
        "several stores each is split by its own runs, the batches draw from their training "
        "runs in proportion to --weights, and validation and the test metrics cover every "
        "store (per store and overall). Writes OUT, OUT with suffix .json (metrics and "
        "settings) and OUT.ckpt (training state for --resume).")
    t.add_argument("store", metavar="STORE", nargs="+",
                   help="demseis store(s) with seismic and fault arrays")
    t.add_argument("--weights", default=None, metavar="W1,W2,...",
                   help="one positive weight per store, comma-separated: the share of the "
                   "training samples drawn from each (default: equal)")
    t.add_argument("--ignore", default=None, metavar="ARRAY[=V,V]",
                   help="leave the pixels of this label array out of the training loss (with "
                   "these values; default any non-zero), in the stores that hold it; e.g. "
                   "fault_uncertain, stored with [labels] fault_uncertain = true (docs/labels.md)")
    t.add_argument("--select", choices=("ods_f1", "f1"), default="ods_f1",
                   help="the validation score that picks the model kept: F1 at the model's best "
                   "threshold, which is saved with it (ods_f1, the default), or F1 at 0.5 (f1)")
    t.add_argument("--pos-weight", default=None, metavar="W[,W...]",
                   help="the weight of fault pixels in the cross-entropy (default: the "
                   "background / fault pixel ratio of the first batches, at most 50; 1: "
                   "unweighted, lower probabilities; docs/model.md); or one per store, "
                   "comma-separated")
    t.add_argument("--out", default="model.pt", help="model file (default model.pt)")
    t.add_argument("--steps", type=pos_int, default=300,
                   help="optimiser steps in all, counting those before a --resume (default 300)")
    t.add_argument("--crop", type=pos_int, default=None,
                   help="square training crop, a multiple of 4 (default 96, or the sections' "
                   "smaller side)")
    t.add_argument("--batch", type=pos_int, default=8, help="batch size (default 8)")
    t.add_argument("--base", type=pos_int, default=16, help="U-Net base width (default 16)")
    t.add_argument("--lr", type=float, default=2e-3, help="Adam learning rate (default 0.002)")
    t.add_argument("--seed", type=nonneg_int, default=0, help="seed (default 0)")
    t.add_argument("--device", default=None,
                   help="cpu, cuda, cuda:1 ... (default: CUDA when available)")
    t.add_argument("--val-every", type=pos_int, default=None,
                   help="validate every this many steps (default: 5 times per training)")
    t.add_argument("--save-every", type=pos_int, default=50,
                   help="write OUT.ckpt every this many steps (default 50)")
    t.add_argument("--resume", action="store_true", help="continue from OUT.ckpt")
    t.add_argument("--threads", type=pos_int, default=None, help="torch CPU threads")
    t.add_argument("--quiet", action="store_true", help="no progress bar or log lines")
    t.set_defaults(func="model:cmd_train")

    p = sub.add_parser(
        "predict", help="fault probability of a SEG-Y or .npy section with a trained model",
        description="Apply a model (the one shipped with demseis, docs/model.md, or --model "
        "from 'demseis train') to a SEG-Y section (one trace per "
        "column), a 3-D SEG-Y cube (inline and crossline numbers in the trace headers: every "
        "inline and crossline is predicted and the two averaged, one line in memory at a "
        "time) or a .npy array (H, W) or (N, H, W) of any size. Writes the fault probability "
        "as SEG-Y with the input's headers (float32 samples) or as .npy; 'demseis score' "
        "reads either.")
    p.add_argument("paths", nargs="+", metavar="[MODEL] IN",
                   help="input section or cube: .sgy, .segy or .npy (MODEL IN: a model file "
                   "from demseis train first, as --model)")
    p.add_argument("--model", default=None,
                   help="model file from demseis train (default: the model shipped with "
                   "demseis, docs/model.md)")
    p.add_argument("--out", required=True, help="output: .sgy/.segy (SEG-Y input) or .npy")
    p.add_argument("--device", default=None,
                   help="cpu, cuda, cuda:1 ... (default: CUDA when available)")
    p.add_argument("--overwrite", action="store_true", help="replace an existing --out")
    p.add_argument("--mask", default=None,
                   help="also write the faults: 1 where the probability reaches the threshold, "
                   "0 elsewhere (.sgy/.segy or .npy)")
    p.add_argument("--threshold", type=float, default=None,
                   help="the threshold of --mask and --png (default: the model's, chosen on its "
                   "validation runs by demseis train; 0.5 for a model without one)")
    p.add_argument("--png", default=None,
                   help="also draw the section with the prediction over it, from the threshold, "
                   "into this PNG")
    p.set_defaults(func="model:cmd_predict")

    c = sub.add_parser(
        "threshold", help="choose a model's threshold on the validation runs of its stores "
        "and save it in the model (needs demseis[torch])",
        description="Choose the probability threshold at which a model finds the faults of "
        "the given stores best (F1 at 2 px on their validation runs, pooled) and save it in "
        "the model file and its JSON, with the test runs scored at it. demseis train does "
        "this itself; this command is for models made without it. Give the stores the model "
        "was trained on.")
    c.add_argument("model", metavar="MODEL", help="model file from demseis train")
    c.add_argument("store", metavar="STORE", nargs="+",
                   help="the store(s) the model was trained on")
    c.add_argument("--device", default=None,
                   help="cpu, cuda, cuda:1 ... (default: CUDA when available)")
    c.set_defaults(func="model:cmd_threshold")
