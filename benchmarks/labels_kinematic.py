"""Kinematic planar fault check: how well the default fault mask lies on the known fault line.

A dense polydisperse disk pack (radii 12.5-25 m, 2000 m x 1000 m) is cut by a planar normal
fault through (1200 m, 0); the hanging wall moves rigidly down-dip by the slip. Scored where both
walls are present (below the lowered hanging-wall top and right of its trailing left edge): ``on_line`` = fraction of mask cells
within 2 cells of the line, ``covered`` = fraction of the line with a mask cell within 2 cells.
Prints one JSON line; --figure writes a picture of one case.

    PYTHONPATH=$PWD python benchmarks/labels_kinematic.py \
        [--figure docs/figures/labels_kinematic.png]
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # demseis_dev: the checkout's

import numpy as np
from scipy.spatial import cKDTree

from demseis.labels import LabelConfig, element_strain, label_maps, mask_thickness_cells
from demseis.types import Grid, Snapshot
from demseis_dev.toys import disk_pack, fault_signed_distance, kinematic_fault

W, H, XF = 2000.0, 1000.0, 1200.0


def score(fault, grid, dip, slip, tol=2.0, trailing_edge=True):
    """(fraction of mask cells within tol cells of the line, fraction of the line covered).

    Scored where both walls are present. The hanging wall slides down-dip: its top drops by
    slip sin(dip) (above, the footwall's free scarp faces air) and its left edge moves right by
    slip cos(dip) (left of it, the footwall's side of the fault faces the void the hanging wall
    left). At 30 deg the fault leaves the section through the left side (y = 693 m), so the
    trailing edge exposes 0.87 slip of the line; at >= 45 deg the line leaves through the top
    and only the scarp is exposed. ``trailing_edge=False`` gives the old region (top only).
    """
    th = np.radians(dip)
    top = H - slip * np.sin(th) - 2 * grid.cell_m
    left = slip * np.cos(th) + 2 * grid.cell_m if trailing_edge else 0.0
    zz, xx = np.meshgrid(grid.y_centres(), grid.x_centres(), indexing="ij")
    f = fault.astype(bool) & (zz < top) & (xx > left)
    pts = np.column_stack([xx[f], zz[f]])
    if pts.shape[0] == 0:
        return 0.0, 0.0
    d = np.abs(fault_signed_distance(pts, XF, dip)) / grid.cell_m
    s = np.linspace(0.0, H / np.sin(th), 4000)
    lp = np.column_stack([XF - s * np.cos(th), s * np.sin(th)])
    lp = lp[(lp[:, 0] > left) & (lp[:, 1] < top)]
    dd, _ = cKDTree(pts).query(lp)
    return float((d <= tol).mean()), float((dd <= tol * grid.cell_m).mean())


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--figure", default=None)
    args = ap.parse_args()
    grid = Grid.covering(W, H, 10.0)
    packs = [disk_pack(W, H, np.random.default_rng(s)) for s in (1, 2, 3)]
    rows = []
    for t in (1.0, 3.0):
        cfg = LabelConfig(thickness_cells=t)
        for dip in (30.0, 45.0, 60.0, 70.0):
            for slip in (100.0, 150.0, 300.0):
                for p, (xy, r) in enumerate(packs):
                    cur = kinematic_fault(xy, x_m=XF, dip_deg=dip, slip_m=slip)
                    g = element_strain(xy, cur, r).gamma_max
                    n = xy.shape[0]
                    snap = Snapshot(1, 1, slip, np.arange(n), cur, r, np.zeros(n, np.int16),
                                    np.zeros(n, bool))
                    f = label_maps(snap, g, grid, cfg)["fault"]
                    on, cov = score(f, grid, dip, slip)
                    on0, cov0 = score(f, grid, dip, slip, trailing_edge=False)
                    rows.append({"thickness_cells": t, "dip_deg": dip, "slip_m": slip, "pack": p,
                                 "on_line": round(on, 3), "covered": round(cov, 3),
                                 "on_line_top_only": round(on0, 3),
                                 "covered_top_only": round(cov0, 3),
                                 "measured_thickness": round(mask_thickness_cells(f), 2)})
    summary = {}
    for t in (1.0, 3.0):
        sel = [r for r in rows if r["thickness_cells"] == t]
        summary[str(t)] = {
            "on_line_median": float(np.median([r["on_line"] for r in sel])),
            "on_line_min": float(np.min([r["on_line"] for r in sel])),
            "covered_median": float(np.median([r["covered"] for r in sel])),
            "covered_min": float(np.min([r["covered"] for r in sel])),
            "cases_passing_both_0.9": sum(r["on_line"] >= 0.9 and r["covered"] >= 0.9 for r in sel),
            "cases_passing_both_0.9_top_only_region": sum(
                r["on_line_top_only"] >= 0.9 and r["covered_top_only"] >= 0.9 for r in sel),
            "failing": [(r["dip_deg"], r["slip_m"], r["pack"]) for r in sel
                        if not (r["on_line"] >= 0.9 and r["covered"] >= 0.9)],
            "cases": len(sel),
        }
    print(json.dumps({"benchmark": "labels_kinematic", "summary": summary, "rows": rows}))
    if args.figure:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        from matplotlib.colors import ListedColormap

        xy, r = packs[0]
        dip, slip = 60.0, 150.0
        cur = kinematic_fault(xy, x_m=XF, dip_deg=dip, slip_m=slip)
        g = element_strain(xy, cur, r).gamma_max
        n = xy.shape[0]
        snap = Snapshot(1, 1, slip, np.arange(n), cur, r, np.zeros(n, np.int16), np.zeros(n, bool))
        ext = [0, W, 0, H]
        fig, ax = plt.subplots(1, 3, figsize=(18, 4.6), constrained_layout=True)
        m0 = label_maps(snap, g, grid, LabelConfig(thickness_cells=0.0))
        im = ax[0].imshow(np.log10(np.maximum(m0["strain"], 1e-3)), cmap="magma", vmin=-2,
                          vmax=1, extent=ext)
        fig.colorbar(im, ax=ax[0], shrink=0.8, label="log10 gamma_max")
        ax[0].set_title("rasterised gamma_max, rigid offset 150 m on a 60 deg fault")
        for a, t in zip(ax[1:], (1.0, 3.0)):
            m = label_maps(snap, g, grid, LabelConfig(thickness_cells=t))
            cmap = ListedColormap(["#ffb000", "#d00000"])
            a.imshow(np.ma.masked_equal(m["damage"], 0), cmap=cmap, vmin=1, vmax=2, extent=ext, interpolation="nearest")
            a.set_title(f"damage (orange) / fault (red), thickness_cells={t:.0f}")
        for a in ax:
            a.plot([XF, XF - H / np.tan(np.radians(dip))], [0, H], "c-", lw=0.8)
            a.set_xlim(500, 1500)
            a.set_xlabel("x (m)")
            a.set_ylabel("elevation (m)")
        fig.savefig(args.figure, dpi=80)


if __name__ == "__main__":
    main()
