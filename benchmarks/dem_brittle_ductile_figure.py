"""Brittle vs ductile cover side by side: particles and 40 Hz seismic of the final snapshots.

Usage::

    NUMBA_NUM_THREADS=1 python benchmarks/dem_localisation.py --scale seed --save ductile.npz
    NUMBA_NUM_THREADS=1 python benchmarks/dem_localisation.py --scale seed --model brittle \\
        --cohesion 1.4e9 --bond-strain 0.005 --save brittle.npz
    python benchmarks/dem_brittle_ductile_figure.py ductile.npz brittle.npz --out FIG.png

Each .npz is a run saved by ``dem_localisation.py --save`` (5 km x 2.77 km seed model). The
seismic uses the default PropertyModel with the same layer-property draw (seed 0) for both
runs, a 10 m grid and a 40 Hz Ricker wavelet, no noise. Prints ONE JSON line with the
mid-depth horizon step of each run (:func:`demseis_dev.measure.horizon_step`).
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from demseis.types import Grid, Snapshot  # noqa: E402

W, H, N_LAYERS, THROW = 5000.0, 2770.0, 48, 450.0


def load_last(path: str) -> Snapshot:
    z = np.load(path)
    k = max(int(key.split("_")[1]) for key in z.files if key.startswith("xy_"))
    return Snapshot(index=k, step=0, throw_m=THROW, ids=z[f"ids_{k}"], xy=z[f"xy_{k}"],
                    radius=z[f"radius_{k}"], layer=z[f"layer_{k}"],
                    deposited=z[f"deposited_{k}"])


def seismic(snap: Snapshot, grid: Grid) -> np.ndarray:
    from demseis.seismic import (PropertyModel, draw_layer_properties, element_properties,
                                 property_grids, synthetic_sections)

    model = PropertyModel()
    props = draw_layer_properties(int(snap.layer.max()) + 1, model, np.random.default_rng(0))
    vp, rho = element_properties(snap.ids, snap.layer, props, model, 0)
    vp_g, rho_g = property_grids(snap.xy, snap.radius, vp, rho, snap.layer, grid, model)
    return synthetic_sections(vp_g, rho_g, grid.cell_m, [40.0])[0]


def main(argv=None) -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("ductile")
    ap.add_argument("brittle")
    ap.add_argument("--out", default="docs/figures/dem_brittle_ductile.png")
    args = ap.parse_args(argv)
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from benchmarks.dem_localisation import mid_horizon_step
    from demseis.plotting import _draw_particles, layer_colors

    grid = Grid.covering(W, H, 10.0)
    fig, axes = plt.subplots(2, 2, figsize=(14, 7.5), constrained_layout=True)
    res = {"benchmark": "dem_brittle_ductile_figure"}
    for col, (name, path) in enumerate((("ductile", args.ductile), ("brittle", args.brittle))):
        snap = load_last(path)
        step = mid_horizon_step(snap, N_LAYERS, H, 0.5 * W, 45.0, THROW)
        res[f"{name}_step_100m_m"] = round(step, 1)
        ax = axes[0, col]
        _draw_particles(ax, snap, layer_colors(snap.layer, N_LAYERS))
        ax.set_xlim(0, W)
        ax.set_ylim(-THROW - 50, H + 50)
        ax.set_aspect("equal")
        ax.set_title(f"{name}: particles, mid-depth horizon steps {step:.0f} m of {THROW:.0f} m "
                     "within 100 m")
        sec = seismic(snap, grid)
        v = np.percentile(np.abs(sec), 99)
        ax = axes[1, col]
        ax.imshow(sec, cmap="gray_r", vmin=-v, vmax=v, aspect="equal",
                  extent=(0, grid.nx * grid.cell_m, grid.top_m - grid.nz * grid.cell_m,
                          grid.top_m))
        ax.set_title(f"{name}: 40 Hz Ricker, no noise")
    fig.savefig(args.out, dpi=80)
    res["figure"] = args.out
    print(json.dumps(res))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
