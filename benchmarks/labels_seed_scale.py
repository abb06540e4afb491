"""Labels on the seed-scale model: figure (labels over seismic, like the paper's Fig. 5b) and
label thickness at the defaults and under the thickness control. Prints one JSON line.

Needs demseis.dem (simulate) and demseis.seismic (synthetic_sections) importable. Either pass
pickled snapshots (a list of Snapshot) with --snapshots, or let it run the DEM:

    PYTHONPATH=<tree with dem+seismic+labels> python benchmarks/labels_seed_scale.py \
        [--snapshots snaps.pkl] [--figure docs/figures/labels_seed_scale.png]
"""

from __future__ import annotations

import argparse
import json
import pickle
import time

import numpy as np


def _snapshots(path: str | None):
    """Pickled snapshots, or run 0 of the ``seed`` preset through the generator's DEM step
    (the current DEM defaults: 5 km x 2.77 km, 48 layers, 45 deg fault, 450 m throw)."""
    if path:
        with open(path, "rb") as fh:
            return pickle.load(fh)
    from demseis.generator.config import load_config
    from demseis.generator.pipeline import simulate_run
    from demseis.generator.sampling import plan_run

    cfg = load_config(preset="seed")
    snaps, _ = simulate_run(cfg, plan_run(cfg, 0))
    return snaps


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--snapshots", default=None, help="pickled list of Snapshot (else run the DEM)")
    ap.add_argument("--save-snapshots", default=None, help="pickle the DEM snapshots here")
    ap.add_argument("--figure", default="docs/figures/labels_seed_scale.png")
    ap.add_argument("--freq-hz", type=float, default=40.0)
    args = ap.parse_args()

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.colors import ListedColormap

    from demseis.labels import (
        LabelConfig,
        label_maps,
        mask_thickness_cells,
        strain_history,
    )
    from demseis.types import Grid
    from demseis.seismic import (
        PropertyModel,
        draw_layer_properties,
        element_properties,
        property_grids,
        synthetic_sections,
    )

    snaps = _snapshots(args.snapshots)
    if args.save_snapshots:
        with open(args.save_snapshots, "wb") as fh:
            pickle.dump(snaps, fh)
    cfg = LabelConfig()
    grid = Grid.covering(5000.0, 2770.0, 10.0)
    t0 = time.perf_counter()
    hist = strain_history(snaps, cfg)
    t_hist = time.perf_counter() - t0
    out = {"benchmark": "labels_seed_scale", "n_elements": [int(s.n) for s in snaps],
           "throw_m": [round(float(s.throw_m), 1) for s in snaps],
           "strain_history_s": round(t_hist, 3), "config": cfg.__dict__}
    per_snap = []
    maps_all = []
    for s, h in zip(snaps, hist):
        m = label_maps(s, h, grid, cfg)
        raw = label_maps(s, h, grid, LabelConfig(thickness_cells=0.0))["fault"]
        maps_all.append(m)
        per_snap.append({"index": int(s.index), "fault_cells": int(m["fault"].sum()),
                         "damage_cells": int((m["damage"] == 1).sum()),
                         "thickness_default_cells": _r(mask_thickness_cells(m["fault"])),
                         "thickness_thresholded_cells": _r(mask_thickness_cells(raw))})
    out["per_snapshot"] = per_snap
    last, hl = snaps[-1], hist[-1]
    control = {}
    for t in (0.0, 1.0, 3.0, 5.0, 7.0):
        f = label_maps(last, hl, grid, LabelConfig(thickness_cells=t))["fault"]
        control[str(t)] = {"measured_cells": _r(mask_thickness_cells(f)), "cells": int(f.sum())}
    out["thickness_control_final"] = control
    # threshold check: fault cells / 8-connected components per snapshot, damage share of rock
    from scipy import ndimage

    sweep = {}
    for ft, dt in ((0.5, 0.3), (0.75, 0.3), (1.0, 0.3), (0.5, 0.15), (0.5, 0.5)):
        c = LabelConfig(fault_threshold=ft, damage_threshold=dt)
        rows = []
        for s, h in zip(snaps[1:], hist[1:]):
            mm = label_maps(s, h, grid, c)
            rock = int((mm["layer"] >= 0).sum())
            rows.append([int(mm["fault"].sum()),
                         int(ndimage.label(mm["fault"], structure=np.ones((3, 3)))[1]),
                         round(float((mm["damage"] >= 1).sum()) / rock, 3)])
        sweep[f"fault>={ft},damage>={dt}"] = rows
    out["threshold_sweep_[fault_cells,components,damage_share]_snapshots_1_on"] = sweep

    # seismic of the final snapshot
    model = PropertyModel()
    n_layers_total = int(max(s.layer.max() for s in snaps)) + 1
    lp = draw_layer_properties(n_layers_total, model, np.random.default_rng(7))
    vp_e, rho_e = element_properties(last.ids, last.layer, lp, model, 7)
    vp_g, rho_g = property_grids(last.xy, last.radius, vp_e, rho_e, last.layer, grid, model)
    sec = synthetic_sections(vp_g, rho_g, grid.cell_m, [args.freq_hz])[0]
    m = maps_all[-1]
    m3 = label_maps(last, hl, grid, LabelConfig(thickness_cells=3.0))
    ext = [grid.x0_m, grid.x0_m + grid.nx * grid.cell_m, grid.top_m - grid.nz * grid.cell_m,
           grid.top_m]
    clip = np.percentile(np.abs(sec), 99)
    fig, ax = plt.subplots(2, 2, figsize=(16, 9.5), constrained_layout=True)
    a = ax[0, 0]
    a.imshow(sec, cmap="gray_r", vmin=-clip, vmax=clip, extent=ext, aspect="equal")
    a.set_title(f"(a) {args.freq_hz:.0f} Hz seismic, throw {last.throw_m:.0f} m")
    a = ax[0, 1]
    a.imshow(sec, cmap="gray_r", vmin=-clip, vmax=clip, extent=ext, aspect="equal")
    dmg = np.ma.masked_equal(np.where(m3["fault"] > 0, 2, m["damage"]), 0)
    a.imshow(dmg, cmap=ListedColormap(["#ffb000", "#d00000"]), vmin=1, vmax=2, alpha=0.55,
             extent=ext, aspect="equal", interpolation="nearest")
    a.set_title(f"(b) labels: damage zone (orange, >= {cfg.damage_threshold}), "
                f"fault (red, >= {cfg.fault_threshold}, 3 cells)")
    a = ax[1, 0]
    im = a.imshow(np.log10(np.maximum(m["strain"], 1e-3)), cmap="magma", vmin=-2, vmax=1,
                  extent=ext, aspect="equal")
    fig.colorbar(im, ax=a, shrink=0.8, label=f"log10 {cfg.strain_measure} gamma_max")
    a.set_title("(c) strain regression target")
    a = ax[1, 1]
    lay = np.ma.masked_less(m["layer"], 0)
    a.imshow(lay % 2, cmap="Greys", vmin=-1, vmax=2, extent=ext, aspect="equal",
             interpolation="nearest")
    a.imshow(np.ma.masked_equal(m3["fault"], 0), cmap=ListedColormap(["#0050ff"]), alpha=0.9,
             extent=ext, aspect="equal", interpolation="nearest")
    a.imshow(np.ma.masked_equal(m["fault"], 0), cmap=ListedColormap(["#d00000"]),
             extent=ext, aspect="equal", interpolation="nearest")
    a.set_title("(d) layer-id map (alternate layers) with fault mask: 1-cell (red) on "
                "3-cell (blue)")
    for a in ax.ravel():
        a.set_xlabel("x (m)")
        a.set_ylabel("elevation (m)")
    fig.savefig(args.figure, dpi=90)
    out["figure"] = args.figure
    print(json.dumps(out))


def _r(v: float) -> float | None:
    return None if not np.isfinite(v) else round(float(v), 2)


if __name__ == "__main__":
    main()
