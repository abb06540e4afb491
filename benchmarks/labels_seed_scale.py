"""Labels on the seed-scale model: figure (slip-trace labels over seismic, like the paper's
Fig. 5b, next to the legacy strain-band labels) and per-snapshot facts (faults, slip, rungs,
loops, damage-zone width) of both methods. Prints one JSON line.

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
    from demseis.generator.config.sampling import plan_run
    from demseis.generator.config.settings import load_config
    from demseis.generator.engines import get_engine

    cfg = load_config(preset="seed")
    snaps = list(get_engine("dem").simulate(cfg, plan_run(cfg, 0)).snapshots)
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

    from demseis.labels import (LabelConfig, displacement_history, label_maps, loop_count,
                                rung_fraction, skeleton_length_cells, strain_history)
    from demseis.seismic import (PropertyModel, draw_layer_properties, element_properties,
                                 property_grids, synthetic_sections)
    from demseis.types import Grid

    snaps = _snapshots(args.snapshots)
    if args.save_snapshots:
        with open(args.save_snapshots, "wb") as fh:
            pickle.dump(snaps, fh)
    cfg = LabelConfig()
    old = LabelConfig(method="strain_band")
    grid = Grid.covering(5000.0, 2770.0, 10.0)
    t0 = time.perf_counter()
    hist = strain_history(snaps, cfg)
    disp = displacement_history(snaps)
    t_hist = time.perf_counter() - t0
    out = {"benchmark": "labels_seed_scale", "n_elements": [int(s.n) for s in snaps],
           "throw_m": [round(float(s.throw_m), 1) for s in snaps],
           "strain_history_s": round(t_hist, 3), "config": cfg.__dict__}
    per_snap = []
    maps_all, old_all = [], []
    t_maps = []
    for s, h, d in zip(snaps, hist, disp):
        t1 = time.perf_counter()
        m = label_maps(s, h, grid, cfg, displacement=d)
        t_maps.append(time.perf_counter() - t1)
        mo = label_maps(s, h, grid, old)
        maps_all.append(m)
        old_all.append(mo)
        f, fo = m["fault"] > 0, mo["fault"] > 0
        rock = int((m["layer"] >= 0).sum())
        dz, core = m["damage"] >= 1, m["damage"] == 2
        length = skeleton_length_cells(f)
        per_snap.append({
            "index": int(s.index), "throw_m": round(float(s.throw_m), 1),
            "fault_cells": int(f.sum()), "n_faults": int(np.unique(m["fault_id"][f]).size),
            "max_slip_m": _r(float(m["slip_m"].max())),
            "median_slip_m": _r(float(np.median(m["slip_m"][f]))) if f.any() else None,
            "rungs": _r(rung_fraction(f)), "loops": loop_count(f),
            "damage_share_of_rock": round(float(dz.sum()) / rock, 4),
            "core_share_of_rock": round(float(core.sum()) / rock, 4),
            # mean fault-core width: core area / trace length
            "core_width_m": _r(float(core.sum()) / length * grid.cell_m) if length else None,
            # mean damage-zone width: damage area / trace length
            "damage_width_m": _r(float(dz.sum()) / length * grid.cell_m) if length else None,
            "old_fault_cells": int(fo.sum()), "old_rungs": _r(rung_fraction(fo)),
            "old_loops": loop_count(fo),
            "old_damage_share_of_rock": round(float((mo["damage"] >= 1).sum()) / rock, 4)})
    out["per_snapshot"] = per_snap
    out["label_maps_s_per_snapshot_median"] = round(float(np.median(t_maps)), 3)
    last = snaps[-1]

    # seismic of the final snapshot
    model = PropertyModel()
    n_layers_total = int(max(s.layer.max() for s in snaps)) + 1
    lp = draw_layer_properties(n_layers_total, model, np.random.default_rng(7))
    vp_e, rho_e = element_properties(last.ids, last.layer, lp, model, 7)
    vp_g, rho_g = property_grids(last.xy, last.radius, vp_e, rho_e, last.layer, grid, model)
    sec = synthetic_sections(vp_g, rho_g, grid.cell_m, [args.freq_hz])[0]
    m, mo = maps_all[-1], old_all[-1]
    ext = [grid.x0_m, grid.x0_m + grid.nx * grid.cell_m, grid.top_m - grid.nz * grid.cell_m,
           grid.top_m]
    clip = np.percentile(np.abs(sec), 99)
    fig, ax = plt.subplots(2, 2, figsize=(16, 9.5), constrained_layout=True)

    def seis(a):
        a.imshow(sec, cmap="gray_r", vmin=-clip, vmax=clip, extent=ext, aspect="equal")

    a = ax[0, 0]
    seis(a)
    a.set_title(f"(a) {args.freq_hz:.0f} Hz seismic, throw {last.throw_m:.0f} m")
    a = ax[0, 1]
    seis(a)
    a.imshow(np.ma.masked_equal((m["damage"] == 1).astype(np.uint8), 0),
             cmap=ListedColormap(["#ffb000"]), alpha=0.35, extent=ext, aspect="equal",
             interpolation="nearest")
    a.imshow(np.ma.masked_equal((m["damage"] == 2).astype(np.uint8), 0),
             cmap=ListedColormap(["#7b2cbf"]), alpha=0.35, extent=ext, aspect="equal",
             interpolation="nearest")
    fid = np.ma.masked_equal(m["fault_id"].astype(float), 0)
    a.imshow(fid, cmap="tab10", vmin=0.5, vmax=10.5, extent=ext, aspect="equal",
             interpolation="nearest")
    a.set_title(f"(b) slip-trace labels: {per_snap[-1]['n_faults']} faults (colour = id), "
                f"fault core (purple), damage zone\n(orange, width = slip, "
                f"<= {cfg.damage_max_width_m:.0f} m, around the core)")
    a = ax[1, 0]
    seis(a)
    a.imshow(np.ma.masked_equal((mo["damage"] == 1).astype(np.uint8), 0),
             cmap=ListedColormap(["#ffb000"]), alpha=0.35, extent=ext, aspect="equal",
             interpolation="nearest")
    a.imshow(np.ma.masked_equal(mo["fault"], 0), cmap=ListedColormap(["#d00000"]),
             extent=ext, aspect="equal", interpolation="nearest")
    a.set_title("(c) legacy strain-band labels (method = \"strain_band\"): fault (red), "
                f"damage (orange, gamma >= {old.damage_threshold})")
    a = ax[1, 1]
    im = a.imshow(np.log10(np.maximum(m["strain"], 1e-3)), cmap="Greys", vmin=-2, vmax=1,
                  extent=ext, aspect="equal")
    sl = np.ma.masked_equal(m["slip_m"], 0)
    im2 = a.imshow(sl, cmap="plasma", extent=ext, aspect="equal", interpolation="nearest")
    fig.colorbar(im2, ax=a, shrink=0.8, label="slip_m on the traces")
    a.set_title(f"(d) slip along the traces over log10 {cfg.strain_measure} gamma_max")
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
