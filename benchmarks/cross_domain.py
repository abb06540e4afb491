"""Cross-domain transfer: train on DEM, kinematic or a 50/50 mix; test on held-out runs of
each, and optionally on field sections (SEG-Y + fault mask).

Every cell uses the same network (:func:`demseis.learning.train.build_unet`), budget,
augmentation (flips, polarity, amplitude scaling) and seeds, on the shared training loop
:func:`demseis.learning.train.train_unet`. Runs are split 75 / 0 / 25 % train / val / test by
run in each store (the same split for every cell); the mix draws each batch half from each
store's train runs on average. Scores: precision / recall / F1 at threshold 0.5 and AP, at
tolerances 2 and 4 px, of whole-section predictions.

Field input: ``--field SECTION:MASK`` (repeatable): a 2-D SEG-Y (one trace per column), .npy
or display PNG and a (samples, traces) 0/1 mask of the same shape (.npy, SEG-Y or PNG; read
by ``benchmarks/_field_common.py``, as in ``benchmarks/field_benchmark.py``, the benchmark that
scores models on labelled field sections). Each field section is scaled to the median
RMS of the synthetic test sections (field amplitudes have arbitrary units).

Results accumulate in ``--results`` (JSON): a cell (train set, seed) already there for the same
configuration is not trained again, so seeds can be spread over several invocations (e.g.
visits to a GPU machine). Prints one JSON line: the matrix, mean / std / n over seeds per
(train, test) pair. ``--figure`` draws example predictions of the models trained this time.
CUDA with mixed precision when present (default 3000 steps, base 32), else a small CPU budget
(default 200 steps, base 16).

    PYTHONPATH=$PWD python benchmarks/cross_domain.py --dem DEM.zarr --kin KIN.zarr \\
        --seeds 0 1 2 --results cross_domain.json --figure cross_domain.png
"""

from __future__ import annotations

import argparse
import hashlib
import json
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

from _field_common import (  # noqa: E402  (benchmarks/ is on sys.path)
    add_training_args, budget, load_results, machine, read_field, save_results, score_stack)

TRAIN_SETS = ("dem", "kinematic", "mix")
METRICS = ("precision", "recall", "f1", "ap")


def test_sets(args: argparse.Namespace, fr: tuple[float, float, float]) -> dict:
    """name -> (sections, truth) of the held-out runs of each store, and the field set."""
    from demseis.datasets import FaultSegDataset

    sets = {}
    rng = np.random.default_rng(12345)
    for name, store in (("dem", args.dem), ("kinematic", args.kin)):
        ds = FaultSegDataset(store, inputs=("seismic",), targets=("fault",), split="test",
                             split_fractions=fr)
        idx = np.arange(len(ds))
        if len(idx) > args.max_eval:
            idx = np.sort(rng.choice(len(idx), args.max_eval, replace=False))
        pairs = [ds[int(i)] for i in idx]
        sets[name] = (np.stack([x[0].numpy() for x, _ in pairs]),
                      np.stack([(y.numpy() > 0) for _, y in pairs]))
    if args.field:
        ref = float(np.median([np.sqrt(np.mean(s.astype(np.float64) ** 2))
                               for v in sets.values() for s in v[0]]))
        field = read_field(args.field)
        secs = [s * (ref / max(float(np.sqrt(np.mean(s.astype(np.float64) ** 2))), 1e-30))
                for s, _ in field]
        sets["field"] = (secs, [m for _, m in field])
    return sets


def score_set(model, sections, truth, device: str) -> dict:
    """P/R/F1/AP at tolerances 2 and 4 of a model on a test set (sections may differ in shape)."""
    from demseis.learning.train import predict_sections

    probs = [predict_sections(model, np.asarray(s)[None], device=device)[0] for s in sections]
    out = {}
    for tol in (2, 4):
        r = score_stack(probs, list(truth), tol)
        for k in METRICS:
            out[f"{k}_tol{tol}"] = round(float(getattr(r, k)), 4)
    return out, probs


def fingerprint(args: argparse.Namespace, device: str, steps: int, base: int) -> str:
    """Identity of a configuration: stores, budget, network, device kind, field inputs."""
    key = {"dem": str(Path(args.dem).resolve()), "kin": str(Path(args.kin).resolve()),
           "field": sorted(args.field or []), "steps": steps, "base": base, "crop": args.crop,
           "batch": args.batch, "lr": args.lr, "device": device.split(":")[0],
           "test_fraction": args.test_fraction, "max_eval": args.max_eval}
    return hashlib.sha1(json.dumps(key, sort_keys=True).encode()).hexdigest()[:12]


def matrix(cells: list[dict], config: str) -> dict:
    """(train, test) -> metric -> {mean, std, n} over the seeds of one configuration."""
    out: dict = {}
    for c in cells:
        if c["config"] != config:
            continue
        out.setdefault(f"{c['train']}->{c['test']}", []).append(c)
    summary = {}
    for key, cs in sorted(out.items()):
        summary[key] = {"seeds": sorted(c["seed"] for c in cs)}
        for m in (f"{k}_tol{t}" for t in (2, 4) for k in METRICS):
            v = np.array([c[m] for c in cs], dtype=float)
            summary[key][m] = {"mean": round(float(v.mean()), 4),
                               "std": round(float(v.std(ddof=1)) if v.size > 1 else 0.0, 4),
                               "n": int(v.size)}
    return summary


def example_index(truth) -> int:
    """The test sample drawn in the figure: the one with the most fault pixels."""
    return int(np.argmax([np.count_nonzero(t) for t in truth]))


def draw(path: Path, examples: dict, sets: dict) -> None:
    """Rows: training sets; columns: test sets; seismic, truth (green) and prediction (red)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    trains = sorted(examples, key=TRAIN_SETS.index)
    tests = list(sets)
    fig, axes = plt.subplots(len(trains), len(tests), figsize=(4 * len(tests), 2.6 * len(trains)),
                             squeeze=False)
    for i, tr in enumerate(trains):
        for j, te in enumerate(tests):
            ax = axes[i, j]
            k = example_index(sets[te][1])
            sec, truth = sets[te][0][k], sets[te][1][k]
            prob = examples[tr][te]
            ax.imshow(sec, cmap="gray", aspect="auto")
            ax.imshow(np.ma.masked_less(prob, 0.5), cmap="autumn", alpha=0.8, aspect="auto",
                      vmin=0, vmax=1)
            ax.contour(truth.astype(float), levels=[0.5], colors="lime", linewidths=0.6)
            ax.set_title(f"train {tr} / test {te}", fontsize=9)
            ax.set_xticks([])
            ax.set_yticks([])
    fig.suptitle("cross-domain predictions (red: p >= 0.5, green: label)", fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    plt.close(fig)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--dem", required=True, help="DEM-engine store")
    ap.add_argument("--kin", required=True, help="kinematic-engine store (same grid)")
    ap.add_argument("--field", action="append", help="SECTION:MASK (repeatable)")
    ap.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2])
    ap.add_argument("--train", nargs="+", choices=TRAIN_SETS, default=list(TRAIN_SETS))
    add_training_args(ap, 200, "test samples scored per store")
    ap.add_argument("--results", default="cross_domain.json", help="accumulated results (JSON)")
    ap.add_argument("--figure", help="PNG of example predictions of the models trained now")
    args = ap.parse_args(argv)

    from demseis.learning.train import train_unet

    cuda, device, steps, base = budget(args, 200)
    fr = (1.0 - args.test_fraction, 0.0, args.test_fraction)
    config = fingerprint(args, device, steps, base)
    path = Path(args.results)
    results = load_results(path, "cross_domain")
    results.setdefault("configs", {})[config] = {
        "dem": args.dem, "kin": args.kin, "field": args.field or [], "steps": steps,
        "base": base, "crop": args.crop, "batch": args.batch, "lr": args.lr, "device": device,
        "amp": cuda, "augment": True, "test_fraction": args.test_fraction,
        "max_eval": args.max_eval,
        "machine": machine(cuda, args.threads)}
    sets = test_sets(args, fr)
    stores = {"dem": args.dem, "kinematic": args.kin, "mix": [args.dem, args.kin]}
    done = {(c["train"], c["seed"]) for c in results["cells"] if c["config"] == config}
    examples: dict = {}
    t0 = time.perf_counter()
    for seed in args.seeds:
        for tr in args.train:
            if (tr, seed) in done:
                continue
            model, info = train_unet(stores[tr], steps=steps, crop=args.crop, batch=args.batch,
                                     base=base, lr=args.lr, seed=seed, threads=args.threads,
                                     device=device, split_fractions=fr, log=None, augment=True,
                                     amp=cuda)
            for te, (secs, truth) in sets.items():
                scores, probs = score_set(model, secs, truth, info["device"])
                results["cells"].append({"config": config, "train": tr, "test": te,
                                         "seed": seed, "train_seconds": info["seconds"],
                                         "steps": info["steps"], **scores})
                examples.setdefault(tr, {})[te] = probs[example_index(truth)]
            save_results(path, results)  # after every cell: an interrupted run loses one cell
    summary = matrix(results["cells"], config)
    results.setdefault("summaries", {})[config] = summary
    save_results(path, results)
    if args.figure and examples:
        draw(Path(args.figure), examples, sets)
    print(json.dumps({"benchmark": "cross_domain", "config": config,
                      **results["configs"][config], "wall_seconds":
                      round(time.perf_counter() - t0, 1), "matrix": summary}))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
