"""Held-out predictions of U-Nets trained on different label sets of the same seismic, side by side.

Reads the ``--save-pred`` files of ``benchmarks/learnability.py`` (runs on stores that differ
only in their labels, e.g. made with ``demseis relabel``), checks that they hold the same
held-out sections, and draws one row per section: the seismic, then for each label set its
labels and the network's probabilities (threshold: the one chosen on the train runs).

    python benchmarks/learnability_figure.py "legacy=old.npz" "slip traces=new.npz" \\
        --out docs/figures/learnability.png
"""

from __future__ import annotations

import argparse
import json
import sys

import numpy as np


def load(specs: list[str]) -> list[tuple[str, dict]]:
    """``NAME=PATH`` pairs -> (name, arrays); all must hold the same held-out sections."""
    sets = []
    for spec in specs:
        name, sep, path = spec.partition("=")
        if not sep:
            raise SystemExit(f"{spec!r}: give NAME=PRED.npz")
        with np.load(path) as z:
            sets.append((name, {k: z[k] for k in z.files}))
    ref = sets[0][1]
    for name, d in sets[1:]:
        if not (np.array_equal(d["sample"], ref["sample"])
                and np.array_equal(d["seismic"], ref["seismic"])):
            raise SystemExit(f"{name}: not the same held-out sections as {sets[0][0]} "
                             "(compare stores with the same seismic, same split)")
    return sets


def draw(sets: list[tuple[str, dict]], path: str) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    seis = sets[0][1]["seismic"]
    n, ncol = len(seis), 1 + 2 * len(sets)
    h, w = seis.shape[1:]
    fig, axes = plt.subplots(n, ncol, figsize=(2.3 * ncol, 2.3 * n * h / w + 0.6), squeeze=False)
    for i in range(n):
        clip = np.percentile(np.abs(seis[i]), 99)
        axes[i, 0].imshow(seis[i], cmap="gray", vmin=-clip, vmax=clip, aspect="auto")
        for j, (name, d) in enumerate(sets):
            t = float(d["threshold_tol2"])
            a, b = axes[i, 1 + 2 * j], axes[i, 2 + 2 * j]
            a.imshow(d["truth"][i], cmap="gray_r", vmin=0, vmax=1, aspect="auto")
            b.imshow(d["prob"][i], cmap="magma", vmin=0, vmax=1, aspect="auto")
            b.contour(d["prob"][i] >= t, levels=[0.5], colors="cyan", linewidths=0.5)
            if i == 0:
                r = json.loads(str(d["result"]))
                a.set_title(f"{name}: labels", fontsize=8)
                b.set_title(f"{name}: prediction\nheld-out F1@2 {r['test_f1_at_train_threshold_tol2']:.2f}"
                            f", AP@2 {r['test_ap_tol2']:.2f}", fontsize=8)
        if i == 0:
            axes[i, 0].set_title("held-out seismic", fontsize=8)
    for ax in axes.ravel():
        ax.set_xticks([])
        ax.set_yticks([])
    fig.suptitle("same seismic, same network and budget; cyan: p >= train-chosen threshold",
                 fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("pred", nargs="+", help="NAME=PRED.npz from learnability.py --save-pred")
    ap.add_argument("--out", required=True, help="PNG path")
    args = ap.parse_args(argv)
    sets = load(args.pred)
    draw(sets, args.out)
    print(json.dumps({"figure": args.out, "sets": [n for n, _ in sets],
                      "sections": int(len(sets[0][1]["seismic"]))}))
    return 0


if __name__ == "__main__":
    sys.exit(main())
