"""Fault populations over a stretching base: faults per section, their dips and slips, run time.

Usage::

    PYTHONPATH=. python benchmarks/dem_stretch.py --stretch 0.05 0.1 0.2 -0.1 --runs 3 \\
        [--set cohesion_n=4e8 --set friction=0.6 ...] [--single]

A quick-sized box (2500 x 1100 m, r 12.5-25 m, 16 layers, 4 snapshots), brittle contacts
(bond_strain 0.005, by default cohesion_n 6e8 N and friction 0.8: the tuned cover of
docs/dem.md; ``--set`` overrides any sweep key), ``structure = "none"``, one run per seed
(``--runs``), one core. For the last snapshot of each
run it prints the labelled fault instances (``fault_id`` of :func:`demseis.labels.label_maps`,
the engine's states), per instance its median true dip (``dip_deg``) and largest slip
(``slip_m``), and the seconds of the DEM run. ``--single`` also times the ``quick`` preset's
single-fault run 0 for comparison.
"""

from __future__ import annotations

import argparse
import json
import time

import numpy as np

from demseis.generator.config.sampling import plan_run
from demseis.generator.config.settings import load_config, parse_config
from demseis.generator.engines import get_engine


def _value(text: str):
    try:
        return json.loads(text)
    except json.JSONDecodeError:
        return text


def config(stretch: float, seed: int, extra: dict) -> dict:
    sweep = {"seed": seed, "n_runs": 1, "structure": "none", "base_stretch": stretch,
             "contact_model": "brittle", "bond_strain": 0.005, "cohesion_n": 6.0e8,
             "friction": 0.8, "n_layers": 16, "freq_hz": 30, **extra}
    return {"name": "stretch", "sweep": sweep,
            "model": {"width_m": 2500.0, "height_m": 1100.0, "n_snapshots": 4},
            "grid": {"cell_m": 10.0}}


def measure(cfg) -> dict:
    engine = get_engine("dem")
    spec = plan_run(cfg, 0)
    t0 = time.perf_counter()
    run = engine.simulate(cfg, spec)
    secs = time.perf_counter() - t0
    last = cfg.model.n_snapshots - 1
    state = next(iter(engine.states(cfg, run, [last])))
    fid, dip, slip = (np.asarray(state.labels[k]) for k in ("fault_id", "dip_deg", "slip_m"))
    ids = np.unique(fid[fid > 0])
    dips = np.array([np.median(dip[fid == i]) for i in ids])
    slips = np.array([slip[fid == i].max() for i in ids])
    return {"seconds": secs, "n_faults": int(ids.size), "dips": dips, "slips": slips,
            "steps": int(run.snapshots[-1].step), "n_elements": int(run.snapshots[-1].n)}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--stretch", type=float, nargs="+", default=[0.05, 0.1, 0.2])
    ap.add_argument("--runs", type=int, default=1)
    ap.add_argument("--set", action="append", default=[], help="sweep key=value (JSON value)")
    ap.add_argument("--single", action="store_true")
    args = ap.parse_args()
    extra = {k: _value(v) for k, v in (s.split("=", 1) for s in args.set)}
    if args.single:
        cfg = load_config(preset="quick")
        m = measure(cfg)
        print(f"quick single fault run 0: {m['seconds']:.1f} s, {m['steps']} steps, "
              f"{m['n_faults']} labelled faults")
    for e in args.stretch:
        rows = [measure(parse_config(config(e, seed, extra))) for seed in range(args.runs)]
        dips = np.concatenate([r["dips"] for r in rows])
        slips = np.concatenate([r["slips"] for r in rows])
        q = (lambda a, p: float(np.percentile(a, p)) if a.size else float("nan"))
        print(f"base_stretch {e:+.2f} {extra}: faults/section {[r['n_faults'] for r in rows]}, "
              f"dip median {q(dips, 50):.0f} (p10-p90 {q(dips, 10):.0f}-{q(dips, 90):.0f}) deg, "
              f"slip {q(slips, 0):.1f}-{q(slips, 100):.0f} m (median {q(slips, 50):.0f}), "
              f"run {np.mean([r['seconds'] for r in rows]):.1f} s, "
              f"{rows[0]['steps']} steps, {rows[0]['n_elements']} elements", flush=True)


if __name__ == "__main__":
    main()
