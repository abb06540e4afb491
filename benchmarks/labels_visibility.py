"""Where a store's fault labels and its seismic disagree: labels without a visible offset,
visible offsets without a label, empty rock, per sample.

For every done run of a store with particle snapshots (or of a kinematic store: its states are
recomputed from its parameters), each rendered snapshot's reference map (where each point's rock
was before deformation, :class:`demseis.generator.engines.State`) is evaluated on the output
grid: the reference elevation ``y0`` of the rock at every (time or depth) sample of every trace.
A reflector that crosses from trace ``j`` to ``j+1`` keeps its ``y0``; so the *visible offset*
between two traces at a sample is the jump of ``y0`` across three trace pairs beyond the row's
local trend (:func:`demseis.labels.offsets.pair_offsets`), converted to output samples through
the interval velocity (two-way time) or the cell size (depth). A pair with an offset of at
least ``--min-offset`` samples is a visible offset.

Per sample (every stored sample of a snapshot shares its labels) the line reports:

- ``label_visible``: the share of label pixels within ``--tol`` px of a visible offset;
- ``offset_labelled``: the share of visible-offset pixels within ``--tol`` px of a label;
- ``no_rock``: the share of output pixels holding no rock (the space above a subsided surface);
- ``chaos``: the share of pixels whose 5x5 neighbourhood holds visible offsets on 3 rows or more
  in 3 or more different columns pairs (a collapse zone, not a fault);
- ``label_in_chaos``: the share of label pixels in such a neighbourhood.

Per slip band of the labels (``slip_m`` of the label pixel, the bands of
``benchmarks/learnability.py``'s recall by slip) the line also pools, over the faulted
samples, the label pixels (``pixels``), the share of them on a visible offset
(``visible``, as ``label_visible``) and the median of the largest offset in samples within
``--tol`` px of each (``median_offset``): ``label_visible_by_slip``.

One JSON line per store with the medians and the per-sample lists (``--per-sample``).

    PYTHONPATH=$PWD python benchmarks/labels_visibility.py STORE [--runs N] [--tol 2]
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np
from scipy.ndimage import binary_dilation, grey_dilation, uniform_filter

from demseis.labels.offsets import pair_offsets


def sample_measures(fault: np.ndarray, offset: np.ndarray, rock: np.ndarray, min_offset: float,
                    tol: int) -> dict[str, float]:
    """The measures of one sample (see the module docstring)."""
    vis = np.zeros(fault.shape, dtype=bool)
    o = np.nan_to_num(offset, nan=0.0) >= min_offset
    vis[:, :-1] |= o
    vis[:, 1:] |= o
    lab = fault > 0
    fp = np.ones((2 * tol + 1, 2 * tol + 1), dtype=bool)
    vis_near = binary_dilation(vis, fp) if vis.any() else vis
    lab_near = binary_dilation(lab, fp) if lab.any() else lab
    # chaos: visible offsets in many column pairs and rows of a small window
    rows_hit = uniform_filter(vis.astype(float), size=(5, 1)) * 5 >= 3
    chaos = uniform_filter(rows_hit.astype(float), size=(1, 5)) * 5 >= 3
    chaos = binary_dilation(chaos, np.ones((3, 3), bool)) & (uniform_filter(vis.astype(float), 5) * 25 >= 9)
    out = {
        "label_px": int(lab.sum()),
        "offset_px": int(vis.sum()),
        "label_visible": float((lab & vis_near).sum() / lab.sum()) if lab.any() else float("nan"),
        "offset_labelled": float((vis & lab_near).sum() / vis.sum()) if vis.any() else float("nan"),
        "no_rock": float((~rock).mean()),
        "chaos": float(chaos.mean()),
        "label_in_chaos": float((lab & chaos).sum() / lab.sum()) if lab.any() else float("nan"),
    }
    return out


#: slip bands (m) of ``label_visible_by_slip``: the edges of learnability.py's recall by slip
SLIP_EDGES_M = (0.0, 10.0, 20.0, 40.0, 80.0, 160.0, np.inf)


def slip_band_keys() -> list[str]:
    """The names of the bands of :data:`SLIP_EDGES_M` (``below`` for slips under 10 m)."""
    return ["below" if lo == 0.0 else f"{lo:g}-{hi:g}"
            for lo, hi in zip(SLIP_EDGES_M[:-1], SLIP_EDGES_M[1:])]


def label_offsets_by_slip(fault: np.ndarray, offset: np.ndarray, slip: np.ndarray,
                          min_offset: float, tol: int) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """Per slip band: (visible, largest offset) of each label pixel of the band.

    ``offset`` is the (H, W - 1) offset in samples between traces j and j + 1 (NaN: none);
    a pixel takes the larger of its two pairs, and a label pixel the largest within ``tol`` px
    (a (2 tol + 1) square, as ``label_visible``). Visible: that offset is at least
    ``min_offset``.
    """
    o = np.nan_to_num(offset, nan=0.0)
    px = np.zeros(fault.shape)
    px[:, :-1] = o
    px[:, 1:] = np.maximum(px[:, 1:], o)
    near = grey_dilation(px, size=(2 * tol + 1, 2 * tol + 1))
    lab = fault > 0
    out = {}
    for key, lo, hi in zip(slip_band_keys(), SLIP_EDGES_M[:-1], SLIP_EDGES_M[1:]):
        m = lab & (slip > 0) & (slip >= lo) & (slip < hi)
        out[key] = (near[m] >= min_offset, near[m])
    return out


def pooled_by_slip(parts: list[dict[str, tuple[np.ndarray, np.ndarray]]]
                   ) -> dict[str, dict[str, float | int | None]]:
    """:func:`label_offsets_by_slip` of many samples pooled per band."""
    res = {}
    for key in slip_band_keys():
        vis = np.concatenate([p[key][0] for p in parts]) if parts else np.zeros(0, bool)
        off = np.concatenate([p[key][1] for p in parts]) if parts else np.zeros(0)
        res[key] = {"pixels": int(vis.size),
                    "visible": round(float(vis.mean()), 4) if vis.size else None,
                    "median_offset": round(float(np.median(off)), 3) if off.size else None}
    return res


def state_reference_on_output(cfg, state, arrays_like, params
                              ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(y0, rock, samples-per-metre) of ``state`` (of a run with parameters ``params``) on the
    output grid (rows, traces): the reference elevation at every strata point taken to the
    time axis by linear interpolation (or the cell centres in depth)."""
    from demseis.generator.config.layout import grid_of, time_axis_of, trace_x
    from demseis.generator.render.section import imaging_input, state_maps
    from demseis.generator.render.survey import (fine_depths, labels_at_traces, reference_points,
                                                 substeps)
    from demseis.seismic.forward import depth_to_time

    grid = grid_of(cfg)
    t_s = time_axis_of(cfg)
    maps = labels_at_traces(cfg, state_maps(state, arrays_like))
    img = imaging_input(cfg, state, maps, params)
    n = substeps(cfg)
    z = fine_depths(cfg, grid.nz)
    _, y0, _ = reference_points(state.reference, trace_x(cfg), z)
    dz = grid.cell_m / n
    if t_s is None:
        y0c = y0.reshape(grid.nz, n, -1)[:, n // 2]
        return y0c, np.isfinite(y0c), np.full(y0c.shape, 1.0 / grid.cell_m)
    rock = np.isfinite(y0).astype(np.float64)
    vp = img.vp
    y0t = depth_to_time(np.nan_to_num(y0, nan=0.0), vp, dz, t_s, method="linear", fill=0.0)
    rockt = depth_to_time(rock, vp, dz, t_s, method="nearest", fill=0.0) > 0.5
    vpt = depth_to_time(vp, vp, dz, t_s, method="nearest", fill=float(np.median(vp)))
    y0t = np.where(rockt, y0t, np.nan)
    return y0t, rockt, 2.0 / (vpt * float(cfg.output.dt_s))


def measure_store(path: str, runs: int | None, min_offset: float, tol: int
                  ) -> tuple[list[dict], dict]:
    """Per-sample measures of the first ``runs`` done runs of ``path``, and the label pixels'
    offsets by slip band pooled over the faulted samples (:func:`pooled_by_slip`)."""
    import zarr

    from demseis.datasets.status import shard_status
    from demseis.generator.config.sampling import plan_run
    from demseis.generator.config.settings import stored_config
    from demseis.generator.engines import get_engine
    from demseis.generator.render.section import renders_by_snapshot
    from demseis.generator.sweep.rerender import dem_attempts, stored_run

    root = zarr.open_group(path, mode="r")
    cfg = stored_config(dict(root.attrs)["config"])
    engine = get_engine(cfg.model.engine)
    done = np.flatnonzero(shard_status(path) == 1)
    if runs is not None:
        done = done[:runs]
    fault = root["fault"]
    slip = root["slip_m"] if "slip_m" in root.array_keys() else None
    S = cfg.samples_per_run
    attempts = dem_attempts(Path(path)) if engine.particles else {}
    stored = {k: None for k in root.array_keys()}
    out = []
    parts = []
    for run in done:
        if engine.particles:
            er = stored_run(Path(path), int(run), cfg, attempts)
        else:
            er = engine.simulate(cfg, plan_run(cfg, int(run)))
        spec = er.spec
        groups = renders_by_snapshot(spec)
        for state, (snap, renders) in zip(engine.states(cfg, er, [k for k, _ in groups]), groups):
            y0, rock, scale = state_reference_on_output(cfg, state, stored, spec.params)
            off = pair_offsets(y0, scale)
            for r in renders:
                i = int(run) * S + r.sample
                f = np.asarray(fault[i])
                m = sample_measures(f, off, rock, min_offset, tol)
                if slip is not None and int(snap) > 0:
                    parts.append(label_offsets_by_slip(f, off, np.asarray(slip[i]), min_offset,
                                                       tol))
                m.update(run=int(run), snapshot=int(snap), sample=i, freq_hz=float(r.freq_hz))
                out.append(m)
        print(f"run {run}: {len(out)} samples", file=sys.stderr)
    return out, pooled_by_slip(parts)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("store")
    ap.add_argument("--runs", type=int, help="first N done runs (default all)")
    ap.add_argument("--min-offset", type=float, default=1.0, help="visible offset, samples")
    ap.add_argument("--tol", type=int, default=2, help="distance tolerance, px")
    ap.add_argument("--per-sample", action="store_true", help="include every sample's measures")
    args = ap.parse_args(argv)
    rows, by_slip = measure_store(args.store, args.runs, args.min_offset, args.tol)
    keys = ("label_visible", "offset_labelled", "no_rock", "chaos", "label_in_chaos")
    faulted = [r for r in rows if r["snapshot"] > 0]
    line = {"benchmark": "labels_visibility", "store": Path(args.store).name,
            "samples": len(rows), "min_offset": args.min_offset, "tol": args.tol}
    for k in keys:
        v = np.array([r[k] for r in faulted], dtype=float)
        line[f"median_{k}"] = float(np.nanmedian(v)) if np.isfinite(v).any() else None
    line["pooled_label_visible"] = float(
        np.nansum([r["label_visible"] * r["label_px"] for r in faulted])
        / max(1, sum(r["label_px"] for r in faulted if np.isfinite(r["label_visible"]))))
    line["pooled_offset_labelled"] = float(
        np.nansum([r["offset_labelled"] * r["offset_px"] for r in faulted])
        / max(1, sum(r["offset_px"] for r in faulted if np.isfinite(r["offset_labelled"]))))
    line["label_visible_by_slip"] = by_slip
    if args.per_sample:
        line["per_sample"] = rows
    print(json.dumps(line))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
