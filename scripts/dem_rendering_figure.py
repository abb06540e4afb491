"""docs/figures/dem_rendering.png: DEM sections drawn with and without the statics and block
keys of the strata rendering, from one store's particle snapshots.

For each run given, one sample is rendered again (the store's config, then
``[output] velocity_median_m`` and then ``surface_median_m`` and ``block_smoothing_m`` set)
and drawn with its fault label:

    PYTHONPATH=$PWD python scripts/dem_rendering_figure.py D.zarr --runs 5 7 --sample 6 \\
        [--out docs/figures/dem_rendering.png]

``D.zarr``: a DEM store with particle snapshots (``demseis generate --preset field``).
"""

from __future__ import annotations

import argparse
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from demseis.datasets import open_store  # noqa: E402
from demseis.generator.engines import get_engine  # noqa: E402
from demseis.generator.render.section import render_run  # noqa: E402
from demseis.generator.sweep.rerender import dem_attempts, look_config, stored_run  # noqa: E402

#: (title, [output] keys) of each column
VARIANTS = (
    ("element maps (the preset)", {}),
    ("+ velocity_median_m = 200", {"velocity_median_m": 200.0}),
    ("+ surface_median_m = 200, block_smoothing_m = 150",
     {"velocity_median_m": 200.0, "surface_median_m": 200.0, "block_smoothing_m": 150.0}),
)


def render(store: Path, run: int, keys: dict) -> dict:
    """The samples of ``run`` rendered again with ``keys`` in ``[output]``."""
    cfg = look_config(dict(open_store(store).attrs)["config"], {"output": keys})
    res = stored_run(store, run, cfg, dem_attempts(store))
    return render_run(cfg, res, get_engine(cfg.model.engine)).arrays


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("store", type=Path)
    ap.add_argument("--runs", type=int, nargs="+", default=[5, 7])
    ap.add_argument("--sample", type=int, default=6, help="sample within the run")
    ap.add_argument("--out", type=Path, default=Path("docs/figures/dem_rendering.png"))
    a = ap.parse_args(argv)
    fig, axes = plt.subplots(len(VARIANTS), len(a.runs), squeeze=False,
                             figsize=(6.0 * len(a.runs), 2.4 * len(VARIANTS)))
    for c, run in enumerate(a.runs):
        for r, (title, keys) in enumerate(VARIANTS):
            arrays = render(a.store, run, keys)
            sec = arrays["seismic"][a.sample]
            fault = arrays["fault"][a.sample] > 0
            v = float(np.percentile(np.abs(sec), 99)) or 1.0
            ax = axes[r, c]
            ax.imshow(sec, cmap="gray", vmin=-v, vmax=v, aspect="auto", interpolation="nearest")
            yy, xx = np.nonzero(fault)
            ax.scatter(xx, yy, s=0.6, c="red", linewidths=0)
            ax.set_title(f"run {run}, sample {a.sample}: {title}", fontsize=8)
            ax.tick_params(labelsize=6)
    fig.tight_layout()
    a.out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(a.out, dpi=110)
    print(a.out)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
