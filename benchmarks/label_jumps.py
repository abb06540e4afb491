"""How the rock moved across a DEM store's fault labels, read from its particles: how much of
the jump that a label's slip measures is throw (vertical) and how much is opening
(horizontal), beside the throw the picks read from the slip (slip x sin(dip)) and the jump of
the rendered reference map.

For every label cell of the depth-grid label maps at the traces (what the picks draw from) of
the first ``--runs`` done runs' faulted snapshots: the elements of snapshot 0 whose depth
is within ``--band`` m of the cell's and whose x lies ``--inner`` to ``--outer`` m to one
side give that side's median displacement since snapshot 0
(:func:`demseis.labels.displacement_history`); the right side's minus the left side's is
the rock's jump ``(dx, dy)`` across the label (:func:`side_jump`). Beside it, the jump of the
rendered reference elevation ``y0`` along the cell's row over two traces either side, less
the trend of the four pairs beyond (:func:`reference_jump`), and the label's ``slip_m`` and
``slip_m * sin(dip_deg)``. Per slip band (``benchmarks/labels_visibility.py``'s), the line
gives the cells and the medians of: the slip, the picks' throw, ``|dy|``, ``|dx|``, the
jump's length, the rendered jump, and ``|dy|`` over the picks' throw (``throw_ratio``).

    PYTHONPATH=$PWD python benchmarks/label_jumps.py STORE [--runs 8]
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

from labels_visibility import SLIP_EDGES_M, slip_band_keys  # noqa: E402  (benchmarks/ on path)


def side_jump(ex: np.ndarray, ey: np.ndarray, ux: np.ndarray, uy: np.ndarray, x: float,
              y: float, inner: float, outer: float, band: float
              ) -> tuple[float, float] | None:
    """(dx, dy): the median displacement of the elements right of ``x`` minus that of those
    left of it, each side taking the elements at ``inner`` to ``outer`` m from ``x`` and within
    ``band`` m of elevation ``y``; None where a side has fewer than 2 elements."""
    near = np.abs(ey - y) < band
    left = near & (ex > x - outer) & (ex < x - inner)
    right = near & (ex > x + inner) & (ex < x + outer)
    if left.sum() < 2 or right.sum() < 2:
        return None
    return (float(np.median(ux[right]) - np.median(ux[left])),
            float(np.median(uy[right]) - np.median(uy[left])))


def reference_jump(y0_row: np.ndarray, c: int, half: int = 2, trend: int = 4) -> float | None:
    """|jump| of ``y0_row`` from trace ``c - half`` to ``c + half``, less ``2 half`` times the
    median pair jump of the ``trend`` pairs beyond either end; None near an edge or where a
    value is NaN (no rock)."""
    d = np.diff(y0_row)
    lo, hi = c - half, c + half
    if lo - trend < 0 or hi + trend > d.size:
        return None
    inner = d[lo:hi]
    outer = np.r_[d[lo - trend:lo], d[hi:hi + trend]]
    if not (np.isfinite(inner).all() and np.isfinite(outer).all()):
        return None
    return float(abs(inner.sum() - inner.size * np.median(outer)))


def measure_store(path: str, runs: int, inner: float, outer: float, band: float) -> dict:
    """Per slip band, the medians of the module docstring over the first ``runs`` done runs."""
    import zarr

    from demseis.datasets.status import shard_status
    from demseis.generator.config.layout import grid_of, trace_x
    from demseis.generator.config.settings import stored_config
    from demseis.generator.engines import get_engine
    from demseis.generator.render.section import renders_by_snapshot, state_maps
    from demseis.generator.render.survey import labels_at_traces, reference_points
    from demseis.generator.sweep.rerender import dem_attempts, stored_run
    from demseis.labels import displacement_history

    root = zarr.open_group(path, mode="r")
    cfg = stored_config(dict(root.attrs)["config"])
    engine = get_engine(cfg.model.engine)
    if not engine.particles:
        raise SystemExit(f"{path}: engine {cfg.model.engine!r} stores no particles")
    grid = grid_of(cfg)
    xt = trace_x(cfg)
    depth = (np.arange(grid.nz) + 0.5) * grid.cell_m
    stored = {k: None for k in root.array_keys()}
    attempts = dem_attempts(Path(path))
    rows: list[tuple[float, float, float, float, float]] = []
    for run in np.flatnonzero(shard_status(path) == 1)[:runs]:
        result = stored_run(Path(path), int(run), cfg, attempts)
        parts = result.snapshots
        history = displacement_history(parts)
        snaps = [k for k, _ in renders_by_snapshot(result.spec)]
        for state, snap in zip(engine.states(cfg, result, snaps), snaps):
            if snap == 0:
                continue
            disp, birth = history[snap]
            old = birth == 0                    # the elements of snapshot 0, moved since then
            ex, ey = parts[snap].xy[old, 0], parts[snap].xy[old, 1]
            ux, uy = disp[old, 0], disp[old, 1]
            maps = labels_at_traces(cfg, state_maps(state, stored))
            _, y0, _ = reference_points(state.reference, xt, depth)
            slip, dip = maps["slip_m"], maps["dip_deg"]
            for r, c in zip(*np.nonzero((maps["fault"] > 0) & (slip > 0))):
                jump = side_jump(ex, ey, ux, uy, float(xt[c]), grid.top_m - depth[r], inner,
                                 outer, band)
                ref = reference_jump(y0[r], int(c))
                if jump is None or ref is None:
                    continue
                rows.append((float(slip[r, c]), float(slip[r, c] * np.sin(np.radians(dip[r, c]))),
                             abs(jump[0]), abs(jump[1]), ref))
        print(f"run {run}: {len(rows)} label cells", file=sys.stderr)
    a = np.array(rows, dtype=float).reshape(-1, 5)
    out = {}
    for key, lo, hi in zip(slip_band_keys(), SLIP_EDGES_M[:-1], SLIP_EDGES_M[1:]):
        b = a[(a[:, 0] >= lo) & (a[:, 0] < hi)]
        if not len(b):
            out[key] = {"cells": 0}
            continue
        med = lambda v: round(float(np.median(v)), 2)  # noqa: E731
        out[key] = {"cells": int(len(b)), "slip_m": med(b[:, 0]), "picks_throw_m": med(b[:, 1]),
                    "particle_dy_m": med(b[:, 3]), "particle_dx_m": med(b[:, 2]),
                    "particle_jump_m": med(np.hypot(b[:, 2], b[:, 3])),
                    "rendered_jump_m": med(b[:, 4]), "throw_ratio": med(b[:, 3] / b[:, 1])}
    return out


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("store")
    ap.add_argument("--runs", type=int, default=8, help="first N done runs")
    ap.add_argument("--inner", type=float, default=30.0, help="elements from this far, m")
    ap.add_argument("--outer", type=float, default=90.0, help="to this far either side, m")
    ap.add_argument("--band", type=float, default=30.0, help="within this of the depth, m")
    args = ap.parse_args(argv)
    by_slip = measure_store(args.store, args.runs, args.inner, args.outer, args.band)
    print(json.dumps({"benchmark": "label_jumps", "store": Path(args.store).name,
                      "runs": args.runs, "inner_m": args.inner, "outer_m": args.outer,
                      "band_m": args.band, "by_slip": by_slip}))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
