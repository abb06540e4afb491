"""Checks of the picked fault target: against a fault of known geometry, and its shape.

:func:`kinematic_agreement` renders kinematic runs with one planar basement fault and compares
the stored ``fault`` label with the fault's true trace on the output grid, computed here from
the fault's plane (x(d) = x_base - direction (H - d) cot dip) and, on a time axis, from the
two-way time through the cell velocities of each trace; nothing of the picking
(:mod:`demseis.labels.picks`) is used. :func:`shape_counts` counts loops and flat rungs of
stored labels, the things a picked line must not have.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from scipy import ndimage

from demseis.errors import InputError
from demseis.generator.config.layout import grid_of, time_axis_of, trace_spacing, trace_x
from demseis.generator.config.sampling import SEED_DEM, plan_run, rng_at
from demseis.generator.config.settings import Config, load_config, parse_config
from demseis.generator.engines import get_engine
from demseis.generator.engines.kinematic import kinematic_faults
from demseis.generator.render.section import (empty_shard, imaging_input, render_state,
                                              renders_by_snapshot, state_maps)
from demseis.generator.render.survey import labels_at_traces
from demseis.labels import loop_count, rung_fraction


def planar_fault_sweep(domain: str, throw_m: tuple[float, float], taper: float,
                       n_runs: int) -> Config:
    """A kinematic sweep of ``n_runs`` runs with one planar fault each (dips 35-80 degrees,
    normal or reverse, either direction, throws uniform in ``throw_m`` tapering by ``taper``)
    in a 2000 x 800 m box with 25 m traces: 4 ms two-way time on 5 m cells (``domain =
    "time"``) or 10 m depth cells (``"depth"``); noise-free, 30 Hz."""
    raw = load_config(preset="tiny").to_dict()
    raw["sweep"].update(seed=3, n_runs=n_runs, dip_deg={"dist": "uniform", "low": 35, "high": 80},
                        throw_m={"dist": "uniform", "low": throw_m[0], "high": throw_m[1]},
                        fault_kind={"dist": "choice", "values": ["normal", "reverse"]},
                        fault_x_frac={"dist": "uniform", "low": 0.3, "high": 0.7},
                        dip_direction={"dist": "choice", "values": ["right", "left"]},
                        throw_taper=taper, snr_db="inf", freq_hz=30)
    raw["model"].update(engine="kinematic", width_m=2000.0, height_m=800.0, n_snapshots=3)
    raw["grid"]["cell_m"] = 5.0 if domain == "time" else 10.0
    raw["output"] = {"domain": domain, "dt_s": 0.004, "trace_spacing_m": 25.0}
    return parse_config(raw)


def true_trace(cfg: Config, fault: Any, fraction: float, vp_cell: np.ndarray,
               ) -> tuple[np.ndarray, np.ndarray]:
    """The true trace of a planar kinematic fault on the output grid, and its throw there in
    output samples.

    Parameters
    ----------
    cfg : the sweep (its grid, traces and time axis).
    fault : a planar :class:`demseis.generator.engines.kinematic.KinematicFault`.
    fraction : share of the final throw reached (the snapshot's).
    vp_cell : (nz, ntr) interval velocity of each depth cell under each trace.

    Returns
    -------
    trace : (H, W) bool, the pixels whose trace lies within half a trace spacing of the plane at
        the pixel's depth (one per row where the plane is steeper than a pixel's diagonal).
    throw : (H, W) float64 throw (output samples) of the fault at each pixel's depth (0 off it).
    """
    if fault.radius_m is not None:
        raise InputError("true_trace is for planar faults")
    grid = grid_of(cfg)
    H = cfg.model.height_m
    xs = trace_x(cfg)
    dx = trace_spacing(cfg)
    cot = 1.0 / np.tan(np.radians(fault.dip_deg))
    t_s = time_axis_of(cfg)
    nz = grid.nz
    if t_s is None:
        depth = np.repeat(((np.arange(nz) + 0.5) * grid.cell_m)[:, None], xs.size, axis=1)
        vp_at = None
    else:
        # depth of every sample's two-way time in every trace: cell by cell, linear inside
        tops = np.vstack([np.zeros((1, xs.size)),
                          np.cumsum(2.0 * grid.cell_m / vp_cell, axis=0)])   # (nz + 1, ntr)
        depth = np.full((t_s.size, xs.size), np.nan)
        for j in range(xs.size):
            depth[:, j] = np.interp(t_s, tops[:, j], np.arange(nz + 1) * grid.cell_m,
                                    right=np.nan)
        row = np.clip(np.floor(np.nan_to_num(depth, nan=0.0) / grid.cell_m).astype(int), 0,
                      nz - 1)
        vp_at = np.take_along_axis(vp_cell, row, axis=0)
    x_plane = fault.x_m - fault.direction * (H - depth) * cot
    u = (depth - fault.centre_m) / fault.half_length_m
    throw_m = fraction * fault.throw_m * np.clip(1.0 - fault.taper * u**2, 0.0, None)
    on = np.abs(xs[None, :] - x_plane) <= 0.5 * dx
    on &= np.isfinite(depth) & (throw_m > 0)
    if vp_at is None:
        throw = throw_m / grid.cell_m
    else:
        throw = 2.0 * throw_m / (vp_at * float(cfg.output.dt_s))
    return on, np.where(on, np.nan_to_num(throw), 0.0)


def kinematic_agreement(cfg: Config, runs: list[int]) -> list[dict[str, float]]:
    """Per faulted sample of kinematic ``runs`` (one planar basement fault, no population):
    the share of label pixels within one pixel (8-neighbourhood) of the true trace
    (``on_trace``), and the share of true-trace pixels whose throw is at least
    ``min_throw_samples`` with a label pixel within one pixel (``found``).

    Raises
    ------
    InputError
        The sweep is not kinematic, or a run has more than one fault.
    """
    if cfg.model.engine != "kinematic":
        raise InputError("kinematic_agreement needs [model] engine = 'kinematic'")
    engine = get_engine("kinematic")
    min_throw = float(cfg.labels.min_throw_samples)
    near = np.ones((3, 3), bool)
    out = []
    for run in runs:
        spec = plan_run(cfg, run)
        er = engine.simulate(cfg, spec)
        faults = kinematic_faults(cfg, spec.params, run, er.info, rng_at(cfg, run, SEED_DEM))
        if len(faults) != 1:
            raise InputError(f"run {run} has {len(faults)} faults; the check needs one")
        arrays, params = empty_shard(cfg, spec)
        groups = dict(renders_by_snapshot(spec))
        for state in engine.states(cfg, er, sorted(groups)):
            fraction = state.snapshot / (cfg.model.n_snapshots - 1)
            if fraction == 0:
                continue
            render_state(cfg, er, groups[state.snapshot], state, arrays, params)
            maps = labels_at_traces(cfg, state_maps(state, arrays))
            vp_cell = imaging_input(cfg, state, maps, spec.params).vp_cell
            label = arrays["fault"][groups[state.snapshot][0].sample].astype(bool)
            trace, throw = true_trace(cfg, faults[0], fraction, vp_cell)
            visible = trace & (throw >= min_throw)
            near_trace = ndimage.binary_dilation(trace, near)
            near_label = ndimage.binary_dilation(label, near)
            out.append({
                "run": run, "snapshot": state.snapshot, "dip_deg": faults[0].dip_deg,
                "label_px": int(label.sum()), "visible_px": int(visible.sum()),
                "on_trace": float((label & near_trace).sum() / max(label.sum(), 1)),
                "found": float((visible & near_label).sum() / max(visible.sum(), 1)),
            })
    return out


def shape_counts(fault: np.ndarray, fault_id: np.ndarray) -> dict[str, float]:
    """Loops and flat rungs of one sample's fault label.

    ``loops``: closed loops of the whole mask (two faults that cross twice, or a splay that
    rejoins its fault, enclose one); ``instance_loops``: summed over the faults one by one;
    ``rung_fraction``: :func:`demseis.labels.rung_fraction` of the whole mask (its direction
    fit also sees two neighbouring faults' ends); ``instance_rung_fraction``: the share of
    label pixels whose own fault's line is within 12 degrees of horizontal over 9 x 9 pixels.
    Both fractions are 0 for an empty label.
    """
    mask = np.asarray(fault) > 0
    fid = np.asarray(fault_id)
    ids = np.unique(fid[mask])
    if not mask.any():
        return {"loops": 0, "instance_loops": 0, "rung_fraction": 0.0,
                "instance_rung_fraction": 0.0}
    flat = sum(rung_fraction(mask & (fid == k)) * int((mask & (fid == k)).sum()) for k in ids)
    return {"loops": loop_count(mask),
            "instance_loops": int(sum(loop_count(mask & (fid == k)) for k in ids)),
            "rung_fraction": float(rung_fraction(mask)),
            "instance_rung_fraction": float(flat / mask.sum())}
