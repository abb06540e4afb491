"""docs/figures/dem_rendering.png and dem_fault_zone.png: DEM sections drawn with and without
keys of the strata rendering, from one store's particle snapshots.

For each run given, one sample is rendered again with each variant of the set chosen and drawn
with its fault label (red; ``fault_zone``: on the first row only, so that the fault zones show):

- ``statics`` (the default): the store's config, then ``[output] velocity_median_m`` and then
  ``surface_median_m`` and ``block_smoothing_m`` set;
- ``fault_zone``: the store's config, then ``[sweep] fault_zone_impedance`` -0.1 and -0.3.

    PYTHONPATH=$PWD python scripts/dem_rendering_figure.py D.zarr --runs 5 7 --sample 6 \\
        [--set fault_zone] [--out docs/figures/dem_rendering.png]

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

#: each set's rows: (title, look of rendering keys, whether the fault label is drawn)
VARIANTS = {
    "statics": (
        ("element maps (the preset)", {}, True),
        ("+ velocity_median_m = 200", {"output": {"velocity_median_m": 200.0}}, True),
        ("+ surface_median_m = 200, block_smoothing_m = 150",
         {"output": {"velocity_median_m": 200.0, "surface_median_m": 200.0,
                     "block_smoothing_m": 150.0}}, True),
    ),
    "fault_zone": (
        ("the preset, with its fault label", {}, True),
        ("fault_zone_impedance = -0.1", {"sweep": {"fault_zone_impedance": -0.1}}, False),
        ("fault_zone_impedance = -0.3", {"sweep": {"fault_zone_impedance": -0.3}}, False),
    ),
}
OUT = {"statics": Path("docs/figures/dem_rendering.png"),
       "fault_zone": Path("docs/figures/dem_fault_zone.png")}


def render(store: Path, run: int, look: dict) -> dict:
    """The samples of ``run`` rendered again with the rendering keys of ``look``."""
    cfg = look_config(dict(open_store(store).attrs)["config"], look)
    res = stored_run(store, run, cfg, dem_attempts(store))
    return render_run(cfg, res, get_engine(cfg.model.engine)).arrays


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("store", type=Path)
    ap.add_argument("--runs", type=int, nargs="+", default=[5, 7])
    ap.add_argument("--sample", type=int, default=6, help="sample within the run")
    ap.add_argument("--set", choices=sorted(VARIANTS), default="statics", dest="variants",
                    help="the rows: the statics keys or the fault-zone impedance")
    ap.add_argument("--out", type=Path, help="default docs/figures/dem_rendering.png "
                                             "(statics) or dem_fault_zone.png")
    a = ap.parse_args(argv)
    rows, out = VARIANTS[a.variants], a.out or OUT[a.variants]
    fig, axes = plt.subplots(len(rows), len(a.runs), squeeze=False,
                             figsize=(6.0 * len(a.runs), 2.4 * len(rows)))
    for c, run in enumerate(a.runs):
        for r, (title, look, labelled) in enumerate(rows):
            arrays = render(a.store, run, look)
            sec = arrays["seismic"][a.sample]
            fault = arrays["fault"][a.sample] > 0
            v = float(np.percentile(np.abs(sec), 99)) or 1.0
            ax = axes[r, c]
            ax.imshow(sec, cmap="gray", vmin=-v, vmax=v, aspect="auto", interpolation="nearest")
            if labelled:
                yy, xx = np.nonzero(fault)
                ax.scatter(xx, yy, s=0.6, c="red", linewidths=0)
            ax.set_title(f"run {run}, sample {a.sample}: {title}", fontsize=8)
            ax.tick_params(labelsize=6)
    fig.tight_layout()
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=110)
    print(out)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
