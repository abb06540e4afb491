"""docs/figures/f3_prediction.png: what a model trained on demseis data predicts on F3.

Reads the field section and the fault probability `demseis predict` wrote for it, draws the
section and the probability over it, and prints one JSON line: the share of the section
above 0.5 (a network that paints noisy field data as fault scores high; lines along faults
stay below a few per cent).

    demseis train STORE --out model.pt ...
    demseis predict model.pt ../shared/field/f3_inline.sgy --out f3_faults.npy
    PYTHONPATH=$PWD python scripts/f3_prediction_figure.py f3_faults.npy --title "..."
        [--field ../shared/field/f3_inline.sgy] [--out docs/figures/f3_prediction.png]

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

ROOT = Path(__file__).resolve().parents[1]
FIELD = ROOT.parent / "shared" / "field" / "f3_inline.sgy"
ATTRIBUTION = ("F3 Netherlands data courtesy of dGB Earth Sciences, CC BY-SA 3.0; "
               "this figure is CC BY-SA 3.0")


def read_sgy(path: Path) -> np.ndarray:
    import segyio  # lazy: only this figure reads SEG-Y

    with segyio.open(str(path), ignore_geometry=True) as f:
        return np.stack([np.asarray(t, dtype=np.float64) for t in f.trace]).T


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("prediction", type=Path, help=".npy or .sgy from demseis predict")
    ap.add_argument("--field", type=Path, default=FIELD)
    ap.add_argument("--title", default="fault probability of a U-Net trained on demseis data")
    ap.add_argument("--out", type=Path, default=ROOT / "docs" / "figures" / "f3_prediction.png")
    args = ap.parse_args()
    sec = read_sgy(args.field)
    prob = (np.load(args.prediction) if args.prediction.suffix == ".npy"
            else read_sgy(args.prediction))
    prob = np.squeeze(prob)
    if prob.shape != sec.shape:
        raise SystemExit(f"prediction shape {prob.shape} is not the section's {sec.shape}")
    above = float((prob > 0.5).mean())
    clip = float(np.percentile(np.abs(sec), 98)) or 1.0
    fig, axes = plt.subplots(2, 1, figsize=(10, 10.5 * sec.shape[0] / sec.shape[1] + 1.5),
                             layout="constrained")
    for ax in axes:
        ax.imshow(sec, cmap="gray", vmin=-clip, vmax=clip, aspect=1.0, interpolation="nearest")
        ax.set_ylabel("sample (4 ms)", fontsize=8)
        ax.tick_params(labelsize=7)
    shown = np.ma.masked_less(prob, 0.2)
    im = axes[1].imshow(shown, cmap="autumn_r", vmin=0.2, vmax=1.0, alpha=0.75, aspect=1.0,
                        interpolation="nearest")
    fig.colorbar(im, ax=axes[1], shrink=0.6, label="fault probability (shown above 0.2)")
    axes[0].set_title("F3 inline, 4 ms, 25 m traces", fontsize=9)
    axes[1].set_title(f"{args.title}: {100 * above:.1f} % of the section above 0.5", fontsize=9)
    axes[1].set_xlabel("trace", fontsize=8)
    fig.text(0.5, -0.01, ATTRIBUTION, ha="center", fontsize=7)
    args.out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(args.out, dpi=110, bbox_inches="tight")
    print(json.dumps({"figure": str(args.out), "share_above_0.5": round(above, 4)}))


if __name__ == "__main__":
    main()
