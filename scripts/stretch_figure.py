"""Figure: a fault population grown over a stretching base (``base_stretch``) in the DEM.

Usage::

    PYTHONPATH=. python scripts/stretch_figure.py --stretch 0.1 --out docs/figures/dem_stretch.png
    (about 10 s on one core)

One quick-sized run (the config of ``benchmarks/dem_stretch.py``: 2500 x 1100 m, brittle,
cohesion_n 6e8 N, friction 0.8, ``structure = "none"``; ``--set key=value`` overrides a sweep
key). Top: the elements of the
last snapshot coloured by layer (growth layers grey), the labelled faults (``fault_id`` of the
engine's states) drawn over them; bottom: the 30 Hz section of the same snapshot with the
fault labels.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--stretch", type=float, default=0.1)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--set", action="append", default=[], help="sweep key=value (JSON value)")
    ap.add_argument("--out", default="docs/figures/dem_stretch.png")
    args = ap.parse_args()

    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from dem_stretch import _value, config

    from demseis.generator.config.layout import grid_of
    from demseis.generator.config.sampling import plan_run
    from demseis.generator.config.settings import parse_config
    from demseis.generator.engines import get_engine
    from demseis.plotting import _draw_particles, layer_colors
    from demseis.seismic import synthetic_sections

    extra = {k: _value(v) for k, v in (s.split("=", 1) for s in args.set)}
    cfg = parse_config(config(args.stretch, args.seed, extra))
    engine = get_engine("dem")
    run = engine.simulate(cfg, plan_run(cfg, 0))
    last = run.snapshots[-1]
    state = next(iter(engine.states(cfg, run, [len(run.snapshots) - 1])))
    grid = grid_of(cfg)
    extent = (grid.x0_m, grid.x0_m + grid.nx * grid.cell_m, grid.top_m - grid.nz * grid.cell_m,
              grid.top_m)
    fid = np.asarray(state.labels["fault_id"])
    n_faults = int(np.unique(fid[fid > 0]).size)
    sec = synthetic_sections(state.vp_m_s, state.rho_kg_m3, grid.cell_m, [30.0])[0]
    clip = float(np.percentile(np.abs(sec), 99)) or 1.0
    faults = np.ma.masked_equal(fid, 0)

    W = float(last.xy[:, 0].max() + last.radius.max())
    fig, axes = plt.subplots(2, 1, figsize=(12, 7.6))
    _draw_particles(axes[0], last, layer_colors(last.layer, int(run.spec.params["n_layers"])))
    axes[0].imshow(faults % 10, extent=extent, cmap="tab10", vmin=0, vmax=10, alpha=1.0,
                   interpolation="nearest", aspect="equal", zorder=3)
    axes[0].set_xlim(0, max(W, extent[1]))
    axes[0].set_ylim(min(0.0, float((last.xy[:, 1] - last.radius).min())), extent[3] * 1.02)
    axes[0].set_title(f"elements by layer (grey: growth layers) and the {n_faults} labelled "
                      f"faults, base_stretch = {args.stretch:g}", fontsize=10)
    axes[1].imshow(sec, extent=extent, cmap="gray", vmin=-clip, vmax=clip, aspect="equal")
    axes[1].imshow(faults % 10, extent=extent, cmap="tab10", vmin=0, vmax=10, alpha=0.6,
                   interpolation="nearest", aspect="equal")
    axes[1].set_xlim(axes[0].get_xlim())
    axes[1].set_title("30 Hz section with the fault labels", fontsize=10)
    for ax in axes:
        ax.set_ylabel("y (m)")
    axes[1].set_xlabel("x (m)")
    fig.tight_layout()
    Path(args.out).parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(args.out, dpi=100)
    print(f"{args.out}: {n_faults} faults")


if __name__ == "__main__":
    main()
