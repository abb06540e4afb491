"""docs/figures/survey_f3.png: the F3 field section beside demseis sections sampled like it.

The stores are those `benchmarks/survey_realism.py --out DIR` writes (4 ms, 25 m traces,
noise-free); the figure shows F3, then one sample of each engine's `elements` and `strata`
stores, at the same sampling and pixel aspect (one pixel per sample and per trace).

    PYTHONPATH=$PWD python scripts/survey_figure.py DIR [--sample 3] [--freq 40]
        [--field ../shared/field/f3_inline.sgy] [--out docs/figures/survey_f3.png]

The figure contains the F3 section: "F3 Netherlands data courtesy of dGB Earth Sciences,
CC BY-SA 3.0"; the figure is itself CC BY-SA 3.0.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from _field import ATTRIBUTION, FIELD, ROOT  # noqa: E402  (scripts/_field.py)

from demseis.evaluation.segyfile import read_segy_section  # noqa: E402

from demseis.datasets import read_params, read_sample  # noqa: E402




def pick(store: Path, sample: int, freq: float) -> tuple[np.ndarray, np.ndarray, int]:
    """The first sample at or after ``sample`` rendered at ``freq`` Hz, with its fault label."""
    params = read_params(store)
    freqs = np.asarray(params["freq_hz"])
    snaps = np.asarray(params["snapshot"])
    order = [i for i in range(freqs.size) if i >= sample and abs(freqs[i] - freq) < 1e-6
             and snaps[i] == snaps.max()]
    i = order[0] if order else sample
    s = read_sample(store, i, ("seismic", "fault"))
    return s.arrays["seismic"], s.arrays["fault"], i


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("stores", type=Path)
    ap.add_argument("--sample", type=int, default=0)
    ap.add_argument("--freq", type=float, default=40.0)
    ap.add_argument("--field", type=Path, default=FIELD)
    ap.add_argument("--out", type=Path, default=ROOT / "docs" / "figures" / "survey_f3.png")
    args = ap.parse_args()
    panels = [("F3 inline (field, 4 ms, 25 m traces)", read_segy_section(args.field), None)]
    for engine in ("dem", "kinematic"):
        for rendering in ("elements", "strata"):
            store = args.stores / f"{engine}_{rendering}.zarr"
            if store.exists():
                sec, fault, i = pick(store, args.sample, args.freq)
                panels.append((f"{engine}, {rendering}\n(sample {i}, {args.freq:g} Hz)", sec,
                               fault))
    # one pixel per sample and per trace in every panel: F3 across the top, the demseis
    # sections side by side below (rows below the deepest live sample cropped)
    syn = panels[1:]
    rows = max([int(np.flatnonzero(np.any(sec != 0, axis=1))[-1]) + 1 for _, sec, _ in syn]
               or [1])
    widths = [sec.shape[1] for _, sec, _ in syn]
    field_w = panels[0][1].shape[1]
    widths_all = widths + ([field_w - sum(widths)] if field_w > sum(widths) else [])
    fig = plt.figure(figsize=(max(field_w, sum(widths)) / 45, (panels[0][1].shape[0] + rows) / 45
                              + 1.2), layout="constrained")
    gs = fig.add_gridspec(2, len(widths_all), width_ratios=widths_all,
                          height_ratios=[panels[0][1].shape[0], rows])
    axes = [fig.add_subplot(gs[0, :])] + [fig.add_subplot(gs[1, k]) for k in range(len(syn))]
    for ax, (title, sec, fault) in zip(axes, panels):
        sec = sec if fault is None else sec[:rows]
        live = sec[np.any(sec != 0, axis=1)] if np.any(sec) else sec
        clip = float(np.percentile(np.abs(live), 98)) or 1.0
        ax.imshow(sec, cmap="gray", vmin=-clip, vmax=clip, aspect=1.0, interpolation="nearest")
        if fault is not None:
            ax.contour(fault[:rows] > 0, levels=[0.5], colors="red", linewidths=0.4, alpha=0.6)
        ax.set_title(title, fontsize=7)
        ax.tick_params(labelsize=6)
    axes[0].set_ylabel("sample (4 ms)", fontsize=7)
    fig.suptitle("A survey's section and demseis's at the same sampling (1 pixel = 4 ms x 25 m)",
                 fontsize=10)
    fig.text(0.5, -0.01, ATTRIBUTION, ha="center", fontsize=7)
    args.out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(args.out, dpi=110, bbox_inches="tight")
    print(args.out)


if __name__ == "__main__":
    main()
