"""Gallery of a ``variety`` store: 12 runs, final snapshot at 40 Hz, seismic beside its labels.

Usage::

    demseis generate --preset variety --out variety.zarr
    python benchmarks/variety_gallery.py variety.zarr --out docs/figures/variety_gallery.png

For each of the first 12 runs the sample of its last snapshot at 40 Hz (first such render) is
drawn: seismic (grey) and its labels (damage zone grey levels, fault mask black), titled with
the run's structure and fault kinds. Prints ONE JSON line with the samples drawn.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))


def main(argv=None) -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("store")
    ap.add_argument("--out", default="docs/figures/variety_gallery.png")
    ap.add_argument("--n", type=int, default=12)
    args = ap.parse_args(argv)
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import zarr

    from demseis.datasets import read_params
    from demseis.generator.config.layout import param_codes
    from demseis.parameters import MAX_BASEMENT_FAULTS

    codes = param_codes()

    root = zarr.open_group(args.store, mode="r")
    params = read_params(args.store)
    p = {k: params[k] for k in ("run_id", "snapshot", "freq_hz", "structure",
                                "n_basement_faults")}
    kinds = [params[f"fault{k}_kind"] for k in range(MAX_BASEMENT_FAULTS)]
    picked = []
    for run in range(args.n):
        sel = np.flatnonzero((p["run_id"] == run) & (p["freq_hz"] == 40.0))
        if sel.size:
            picked.append(int(sel[np.argmax(p["snapshot"][sel])]))
    rows = (len(picked) + 1) // 2
    fig, axes = plt.subplots(rows, 4, figsize=(16, 1.9 * rows), constrained_layout=True)
    for q, i in enumerate(picked):
        seis = root["seismic"][i]
        lab = root["damage"][i].astype(float)
        lab[root["fault"][i] > 0] = 3.0
        names = [codes["fault_kind"][int(k[i])] for k in kinds if k[i] >= 0]
        title = (f"run {int(p['run_id'][i])}: {codes['structure'][int(p['structure'][i])]}"
                 f", {', '.join(names)}")
        v = np.percentile(np.abs(seis), 99) or 1.0
        a, b = axes[q // 2, 2 * (q % 2)], axes[q // 2, 2 * (q % 2) + 1]
        a.imshow(seis, cmap="gray_r", vmin=-v, vmax=v, aspect="equal")
        b.imshow(lab, cmap="Greys", vmin=0, vmax=3, aspect="equal")
        a.set_title(title, fontsize=8)
        b.set_title("labels: damage (grey), fault (black)", fontsize=8)
        for ax in (a, b):
            ax.set_xticks([])
            ax.set_yticks([])
    fig.savefig(args.out, dpi=72)
    print(json.dumps({"benchmark": "variety_gallery", "samples": picked, "figure": args.out}))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
