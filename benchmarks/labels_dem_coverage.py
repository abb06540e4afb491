"""DEM coverage of the slip-trace labels, per preset. Prints one JSON line.

Coverage = share of the cells whose displacement jump
(:func:`demseis_dev.coverage.jump_field`, from the particles, independent of the
extraction) is >= 2 x min_slip_m that lie within 2 cells of a fault label, pooled over the
snapshots after the first of each run: ``coverage`` for the ``fault`` mask (the slip-surface
lines), ``core_coverage`` for the fault core (``damage`` class 2: the fault mask and the shear
band's core around it). Also per run: rungs (worst snapshot), loops, whether every labelled cell
slips >= min_slip_m, the missed high-jump cells by their distance to the nearest label (cells),
and the median ``label_maps`` time per snapshot (seed preset: the figure to compare).

    python benchmarks/labels_dem_coverage.py [--runs quick:0,1 seed:0] [--cache DIR] \
        [--strand-sigma-cells 0] [--set KEY=VALUE ...] [--kinematic] [--ab-timing] \
        [--metric chessboard]

``--cache DIR`` pickles the DEM snapshots of each run there and reuses them (the labels are
what is measured). ``--kinematic`` adds the same coverage on the 32 planar kinematic faults of
tests/labels/test_traces.py (rigid blocks: one exact slip surface), for the labels and for the
true plane itself: the most a one-cell line on the true fault reaches under this definition.
``--set KEY=VALUE`` changes a ``[labels]`` key for the DEM runs (the value in TOML syntax, as in
a config file: ``--set min_trace_cells=8 --set min_dip_deg=12.5``); the kinematic faults keep
the defaults. ``--metric chessboard`` measures "within 2 cells" in the same box metric as the jump's ±2-cell
offsets (default: Euclidean distance).
"""

from __future__ import annotations

import argparse
import json
import os
import pickle
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # demseis_dev: the checkout's

import numpy as np


def _snapshots(preset: str, run: int, cache: str | None):
    path = os.path.join(cache, f"{preset}_{run}.pkl") if cache else None
    if path and os.path.exists(path):
        with open(path, "rb") as fh:
            return pickle.load(fh)
    from demseis.generator.config.sampling import plan_run
    from demseis.generator.config.settings import load_config
    from demseis.generator.engines import get_engine

    cfg = load_config(None, preset=preset)
    snaps = list(get_engine("dem").simulate(cfg, plan_run(cfg, run)).snapshots)
    if path:
        os.makedirs(cache, exist_ok=True)
        with open(path, "wb") as fh:
            pickle.dump(snaps, fh)
    return snaps


def parse_sets(items: list[str]) -> dict:
    """``["key=value", ...]`` (values in TOML syntax) as a dict; a bad item raises InputError."""
    import tomllib

    from demseis.errors import InputError

    out: dict = {}
    for item in items:
        key, eq, value = item.partition("=")
        if not eq or not key.strip():
            raise InputError(f"--set {item!r}: expected KEY=VALUE")
        try:
            out.update(tomllib.loads(f"{key.strip()} = {value.strip()}"))
        except tomllib.TOMLDecodeError as exc:
            raise InputError(f"--set {item!r}: the value is not TOML ({exc}); "
                             "strings need quotes, e.g. method='strain_band'") from None
    return out


def labels_config(base, strand_sigma_cells: float | None = None, sets: dict | None = None):
    """``base`` (a LabelConfig) with the overrides, validated like a ``[labels]`` table."""
    import dataclasses

    from demseis.labels import LabelConfig

    table = dataclasses.asdict(base)
    if strand_sigma_cells is not None:
        table["strand_sigma_cells"] = strand_sigma_cells
    table.update(sets or {})
    return LabelConfig.from_mapping(table)


#: distance bands (cells, lower bound excluded) of the high-jump cells that a label misses
MISS_BANDS = {"2-3": (2, 3), "3-5": (3, 5), "5-10": (5, 10), ">10": (10, np.inf)}


def _distance(fault: np.ndarray, metric: str) -> np.ndarray:
    """Distance (cells) of every cell to the nearest label cell in ``metric`` (inf: no label)."""
    from scipy import ndimage

    if not fault.any():
        return np.full(fault.shape, np.inf)
    if metric == "euclidean":
        return ndimage.distance_transform_edt(~fault)
    return ndimage.distance_transform_cdt(~fault, metric="chessboard").astype(np.float64)


def measure(preset: str, run: int, cache: str | None, strand_sigma_cells: float | None = None,
            metric: str = "euclidean", sets: dict | None = None) -> dict:
    """Coverage, rungs, loops, slip floor and label_maps time of one DEM run."""

    from demseis.generator.config.layout import grid_of
    from demseis.generator.config.settings import load_config
    from demseis.labels import (displacement_history, label_maps, loop_count, rung_fraction,
                                strain_history)
    from demseis_dev.coverage import jump_coverage, jump_field

    cfg = load_config(None, preset=preset)
    grid = grid_of(cfg)
    lc = labels_config(cfg.labels, strand_sigma_cells, sets)
    min_slip = lc.min_slip_for(grid.cell_m)
    snaps = _snapshots(preset, run, cache)
    hist = strain_history(snaps, lc)
    disp = displacement_history(snaps)
    n_hi = n_near = n_core = loops = 0
    rungs, times, slip_ok = [], [], True
    per_snap = []
    misses = dict.fromkeys(MISS_BANDS, 0)
    for k, snap in enumerate(snaps):
        t0 = time.perf_counter()
        maps = label_maps(snap, hist[k], grid, lc, displacement=disp[k])
        times.append(time.perf_counter() - t0)
        if k == 0:
            continue
        f = maps["fault"].astype(bool)
        jump, rock = jump_field(snap, disp[k][0], disp[k][1], grid)
        hi, near = jump_coverage(f, jump, rock, min_slip, metric=metric)
        n_hi += hi
        n_near += near
        n_core += jump_coverage(maps["damage"] == 2, jump, rock, min_slip, metric=metric)[1]
        per_snap.append(round(near / hi, 3) if hi else None)
        missed = (jump >= 2.0 * min_slip) & rock
        dist = _distance(f, metric)
        for band, (lo, up) in MISS_BANDS.items():
            misses[band] += int((missed & (dist > lo) & (dist <= up)).sum())
        if f.any():
            rungs.append(rung_fraction(f))
            loops += loop_count(f)
            slip_ok &= bool((maps["slip_m"][f] >= min_slip).all())
    return {"preset": preset, "run": run, "coverage": round(n_near / n_hi, 4) if n_hi else None,
            "core_coverage": round(n_core / n_hi, 4) if n_hi else None,
            "n_high_jump_cells": n_hi, "per_snapshot": per_snap,
            "max_rungs": round(max(rungs), 4) if rungs else None, "loops": loops,
            "slip_floor_ok": slip_ok, "misses_by_distance": misses,
            "label_maps_s_median": round(float(np.median(times[1:] or times)), 3)}


def ab_timing(preset: str, run: int, cache: str | None, repeats: int = 3) -> dict:
    """label_maps seconds per snapshot (snapshots 1..): single traces, strands without the
    fault core, and the defaults (strands and core), interleaved in one process so they see
    the same machine load; medians and their ratios."""
    import dataclasses

    from demseis.generator.config.layout import grid_of
    from demseis.generator.config.settings import load_config
    from demseis.labels import displacement_history, label_maps, strain_history

    cfg = load_config(None, preset=preset)
    grid = grid_of(cfg)
    configs = {"single": dataclasses.replace(cfg.labels, strand_sigma_cells=0.0,
                                             core_halfwidth_cells=0),
               "strands": dataclasses.replace(cfg.labels, core_halfwidth_cells=0),
               "core": cfg.labels}
    snaps = _snapshots(preset, run, cache)
    hist = strain_history(snaps, cfg.labels)
    disp = displacement_history(snaps)
    times: dict = {k: [] for k in configs}
    for _ in range(repeats):
        for k in range(1, len(snaps)):
            for name, lc in configs.items():
                t0 = time.perf_counter()
                label_maps(snaps[k], hist[k], grid, lc, displacement=disp[k])
                times[name].append(time.perf_counter() - t0)
    med = {k: float(np.median(v)) for k, v in times.items()}
    return {"preset": preset, "run": run, "repeats": repeats,
            "single_s": round(med["single"], 3), "strands_s": round(med["strands"], 3),
            "core_s": round(med["core"], 3),
            "ratio": round(med["strands"] / med["single"], 2),
            "core_ratio": round(med["core"] / med["strands"], 2)}


def kinematic(metric: str = "euclidean") -> dict:
    """Coverage of the labels (fault mask and fault core) and of the true plane on the planar
    kinematic faults."""
    from demseis.labels import LabelConfig, displacement_history, label_maps, strain_history
    from demseis.types import Grid, Snapshot
    from demseis_dev.coverage import jump_coverage, jump_field
    from demseis_dev.toys import disk_pack, fault_signed_distance, kinematic_fault

    width, height, cell = 2000.0, 1000.0, 10.0
    grid = Grid.covering(width, height, cell)
    zz, xx = np.meshgrid(grid.y_centres(), grid.x_centres(), indexing="ij")
    cfg = LabelConfig()
    labels, cores, plane = [], [], []
    for seed in (1, 2):
        xy, r = disk_pack(width, height, np.random.default_rng(seed))
        n = xy.shape[0]
        for dip in (35.0, 50.0, 65.0, 75.0):
            for slip in (60.0, 200.0):
                for x_m, side in ((1200.0, "right"), (800.0, "left")):
                    cur = kinematic_fault(xy, x_m=x_m, dip_deg=dip, slip_m=slip,
                                          dip_direction=side)
                    snaps = [Snapshot(k, k, 0.0, np.arange(n, dtype=np.int64), p, r,
                                      np.zeros(n, np.int16), np.zeros(n, bool))
                             for k, p in enumerate((xy, cur))]
                    hist = strain_history(snaps, cfg)
                    disp = displacement_history(snaps)
                    maps = label_maps(snaps[1], hist[1], grid, cfg, displacement=disp[1])
                    jump, rock = jump_field(snaps[1], disp[1][0], disp[1][1], grid)
                    th = np.radians(dip)
                    d = np.abs(fault_signed_distance(np.column_stack([xx.ravel(), zz.ravel()]),
                                                     x_m, dip, side)).reshape(xx.shape) / cell
                    line = d <= 0.5 * (abs(np.cos(th)) + abs(np.sin(th)))
                    # where both walls face each other, more than 5 cells above the base
                    trail = slip * np.cos(th) + 2 * cell
                    region = rock & (zz < height - slip * np.sin(th) - 2 * cell) & (zz > 5 * cell)
                    region &= (xx > trail) if side == "right" else (xx < width - trail)
                    for out, f in ((labels, maps["fault"]), (cores, maps["damage"] == 2),
                                   (plane, line)):
                        hi, near = jump_coverage(f, jump, region, cfg.min_slip_for(cell),
                                                 metric=metric)
                        out.append(near / hi)
    return {"cases": len(labels), "labels_median": round(float(np.median(labels)), 3),
            "labels_min": round(float(np.min(labels)), 3),
            "core_median": round(float(np.median(cores)), 3),
            "core_min": round(float(np.min(cores)), 3),
            "true_plane_median": round(float(np.median(plane)), 3),
            "true_plane_min": round(float(np.min(plane)), 3),
            "true_plane_max": round(float(np.max(plane)), 3)}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--runs", nargs="+", default=["quick:0,1,2,3", "seed:0"],
                    help="PRESET:RUN[,RUN...] items")
    ap.add_argument("--cache", default=None, help="directory for pickled DEM snapshots")
    ap.add_argument("--strand-sigma-cells", type=float, default=None,
                    help="override labels.strand_sigma_cells (0: single-scale traces, as before)")
    ap.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                    help="change a [labels] key for the DEM runs (TOML value); repeatable")
    ap.add_argument("--ab-timing", action="store_true",
                    help="also time label_maps: single traces, strands, strands + core, interleaved")
    ap.add_argument("--kinematic", action="store_true",
                    help="also the planar kinematic faults (lines, fault core and true plane)")
    ap.add_argument("--metric", choices=("euclidean", "chessboard"), default="euclidean",
                    help="distance for 'within 2 cells of a label'")
    args = ap.parse_args()
    from demseis.errors import DemseisError
    from demseis.labels import LabelConfig

    try:  # a bad --set fails here, before any DEM run
        sets = parse_sets(args.set)
        labels_config(LabelConfig(), args.strand_sigma_cells, sets)
    except DemseisError as exc:
        ap.error(str(exc))
    out: dict = {"benchmark": "labels_dem_coverage", "strand_sigma_cells": args.strand_sigma_cells,
                 "set": sets, "metric": args.metric, "runs": []}
    for item in args.runs:
        preset, _, runs = item.partition(":")
        for r in (runs or "0").split(","):
            out["runs"].append(measure(preset, int(r), args.cache, args.strand_sigma_cells,
                                       args.metric, sets))
    by: dict = {}
    for r in out["runs"]:
        by.setdefault(r["preset"], []).append(r)
    for key in ("coverage", "core_coverage"):
        out[key] = {p: round(sum(x[key] * x["n_high_jump_cells"] for x in rs)
                             / max(sum(x["n_high_jump_cells"] for x in rs), 1), 4)
                    for p, rs in by.items()}
    if args.ab_timing:
        out["label_maps_ab"] = [ab_timing(r["preset"], r["run"], args.cache) for r in out["runs"]]
    if args.kinematic:
        out["kinematic_planar"] = kinematic(args.metric)
    print(json.dumps(out))


if __name__ == "__main__":
    main()
