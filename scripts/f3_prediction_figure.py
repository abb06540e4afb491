"""docs/figures/f3_prediction.png: what a model trained on demseis data predicts on F3.

Reads the field section and the fault probability `demseis predict` wrote for it, draws the
section and the probability over it, and prints one JSON line: the share of the section
above 0.5 (a network that paints noisy field data as fault scores high; lines along faults
stay below a few per cent).

    demseis train STORE --out model.pt ...
    demseis predict model.pt ../shared/field/f3_inline.sgy --out f3_faults.npy
    PYTHONPATH=$PWD python scripts/f3_prediction_figure.py f3_faults.npy [more.npy ...]
        [--title "..." ...] [--field ../shared/field/f3_inline.sgy]
        [--out docs/figures/f3_prediction.png]

The figure contains the F3 section: "F3 Netherlands data courtesy of dGB Earth Sciences,
CC BY-SA 3.0"; the figure is itself CC BY-SA 3.0.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from _field import ATTRIBUTION, FIELD, ROOT  # noqa: E402  (scripts/_field.py)

from demseis.evaluation.segyfile import read_segy_section  # noqa: E402




def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("predictions", type=Path, nargs="+", help=".npy or .sgy from demseis predict")
    ap.add_argument("--field", type=Path, default=FIELD)
    ap.add_argument("--title", action="append", default=None,
                    help="one per prediction (default: the file name)")
    ap.add_argument("--out", type=Path, default=ROOT / "docs" / "figures" / "f3_prediction.png")
    args = ap.parse_args()
    titles = args.title or [p.name for p in args.predictions]
    if len(titles) != len(args.predictions):
        raise SystemExit("give one --title per prediction")
    sec = read_segy_section(args.field)
    probs = []
    for path in args.predictions:
        prob = np.squeeze(np.load(path) if path.suffix == ".npy" else read_segy_section(path))
        if prob.shape != sec.shape:
            raise SystemExit(f"{path}: prediction shape {prob.shape} is not the section's "
                             f"{sec.shape}")
        probs.append(prob)
    clip = float(np.percentile(np.abs(sec), 98)) or 1.0
    n = 1 + len(probs)
    fig, axes = plt.subplots(n, 1, figsize=(10, n * (10 * sec.shape[0] / sec.shape[1] + 0.5)),
                             layout="constrained")
    for ax in axes:
        ax.imshow(sec, cmap="gray", vmin=-clip, vmax=clip, aspect=1.0, interpolation="nearest")
        ax.set_ylabel("sample (4 ms)", fontsize=8)
        ax.tick_params(labelsize=7)
    axes[0].set_title("F3 inline, 4 ms, 25 m traces", fontsize=9)
    shares = {}
    im = None
    for ax, prob, title, path in zip(axes[1:], probs, titles, args.predictions):
        above = float((prob > 0.5).mean())
        shares[str(path)] = round(above, 4)
        im = ax.imshow(np.ma.masked_less(prob, 0.2), cmap="autumn_r", vmin=0.2, vmax=1.0,
                       alpha=0.75, aspect=1.0, interpolation="nearest")
        ax.set_title(f"{title}: {100 * above:.1f} % of the section above 0.5", fontsize=9)
    axes[-1].set_xlabel("trace", fontsize=8)
    fig.colorbar(im, ax=list(axes), shrink=0.3, label="fault probability (shown above 0.2)")
    fig.text(0.5, -0.01, ATTRIBUTION, ha="center", fontsize=7)
    args.out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(args.out, dpi=110, bbox_inches="tight")
    print(json.dumps({"figure": str(args.out), "share_above_0.5": shares}))


if __name__ == "__main__":
    main()
