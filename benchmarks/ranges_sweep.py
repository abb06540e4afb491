"""Mechanics drawn over the whole declared ranges: which draws a config accepts, which are
affordable, and which of those run stably at seed scale (one JSON line per draw, then a summary).

Usage::

    NUMBA_NUM_THREADS=1 python benchmarks/ranges_sweep.py [--runs 8] [--seed 0]
        [--max-cost 2.0] [--timeout 600] [--max-draws 2000] [--ranges declared|stage]
        [--corners]

``--ranges stage`` draws over the wider domain the DEM accepts when called directly
(:meth:`demseis.parameters.Param.stage`; the config ranges before they were narrowed) instead
of the config ranges. ``--corners`` runs, instead of random draws, the two extreme corners of the
ranges for each contact model: ``strong`` (lightest, stiffest, most frictional and cohesive,
largest bond strain, least damped, strongest gravity: the most rigid cover) and ``weak`` (the
opposite, with cohesion 0), both with the largest strength contrast.

Each draw takes every mechanics parameter of :data:`demseis.parameters.PARAMS`
(``density_kg_m3``, ``kn_n_m``, ``ks_ratio``, ``friction``, ``cohesion_n``, ``bond_strain``,
``contact_model``, ``damping_scale``, ``gravity_m_s2``, ``strength_contrast``) from its declared
range: log-uniform where the range spans more than two decades (with a 10% chance of exactly 0
and log-uniform over the top six decades when the lower bound is 0), uniform otherwise, the
contact model uniformly among its choices. The draw is then

1. ``refused``: the seed-scale config with these values (5 km x 2.77 km, 48 layers, 45 deg,
   450 m, 3 snapshots) fails :func:`demseis.generator.config.settings.parse_config` (its range and
   physics checks, :mod:`demseis.generator.engines.physics`), with the reason;
2. ``too_costly``: accepted, but its time step makes a run more than ``--max-cost`` times as
   many steps as the default material's (steps ~ sqrt(Kn / density));
3. run (until ``--runs`` draws have run): settle the pack with the material, fault it with
   :func:`demseis.dem.simulate` (weak layers from :func:`demseis.dem.strata.layer_materials`
   in 4-layer sandstone/shale units), in a child process with ``--timeout``; ``stable`` or
   ``unstable`` (a :class:`~demseis.errors.SimulationError`, with its message) or ``timeout``.
"""

from __future__ import annotations

import argparse
import json
import math
import re
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from demseis.errors import ConfigError, SimulationError  # noqa: E402
from demseis.parameters import MATERIAL_FIELDS, PARAMS  # noqa: E402

MECHANICS = tuple(MATERIAL_FIELDS.values()) + ("strength_contrast",)
W, H, N_LAYERS = 5000.0, 2770.0, 48

def bounds(name: str, ranges: str) -> tuple[float, float]:
    """(lo, hi) of parameter ``name``: its config range, or its stage domain."""
    p = PARAMS[name].stage() if ranges == "stage" else PARAMS[name]
    return float(p.lo), float(p.hi)


def corners(ranges: str = "declared") -> list[tuple[str, dict]]:
    """The strong and weak corner of the ranges for each contact model (see the module doc)."""
    strong_hi = {"kn_n_m", "ks_ratio", "friction", "cohesion_n", "bond_strain", "gravity_m_s2",
                 "strength_contrast"}
    out = []
    for model in PARAMS["contact_model"].choices:
        for corner in ("strong", "weak"):
            values: dict = {"contact_model": model}
            for name in MECHANICS:
                if name == "contact_model":
                    continue
                lo, hi = bounds(name, ranges)
                pick_hi = (name in strong_hi) == (corner == "strong")
                values[name] = hi if pick_hi or name == "strength_contrast" else lo
            out.append((f"{corner}-{model}", values))
    return out


def draw(rng: np.random.Generator, ranges: str = "declared") -> dict:
    """One value per mechanics parameter over its config range (or its stage domain)."""
    out = {}
    for name in MECHANICS:
        p = PARAMS[name]
        if p.choices is not None:
            out[name] = str(rng.choice(p.choices))
            continue
        lo, hi = bounds(name, ranges)
        if lo == 0.0 and hi / 1e6 > 0 and hi > 100:
            v = 0.0 if rng.random() < 0.1 else float(10 ** rng.uniform(math.log10(hi) - 6,
                                                                         math.log10(hi)))
        elif lo > 0 and hi / lo > 100:
            v = float(10 ** rng.uniform(math.log10(lo), math.log10(hi)))
        else:
            v = float(rng.uniform(lo, hi))
        q = p.stage() if ranges == "stage" else p
        if q.lo_open and v <= lo:
            v = lo + 1e-9 * (hi - lo)
        if q.hi_open and v >= hi:
            v = hi - 1e-9 * (hi - lo)
        out[name] = v
    return out


def check(values: dict) -> str | None:
    """The config's refusal message, or None if it accepts the draw."""
    from demseis.generator.config.settings import parse_config

    raw = {"sweep": {**values, "dip_deg": 45.0, "throw_m": 450.0, "n_layers": N_LAYERS},
           "model": {"width_m": W, "height_m": H, "n_snapshots": 3}}
    try:
        parse_config(raw, source="ranges_sweep")
    except ConfigError as exc:
        return str(exc)
    return None


def cost_ratio(values: dict) -> float:
    """Steps of a run relative to the default material's (dt ~ sqrt(density / Kn))."""
    kn0, rho0 = PARAMS["kn_n_m"].default, PARAMS["density_kg_m3"].default
    return math.sqrt(values["kn_n_m"] / kn0 * rho0 / values["density_kg_m3"])


def run_one(values: dict, seed: int) -> dict:
    """Settle and fault the seed-scale model with ``values``; the outcome as a dict."""
    from demseis.dem import Material, NormalFault, build_assembly, settle_pack, simulate
    from demseis.dem.strata import alternation, layer_materials

    mat = Material(**{f: values[name] for f, name in MATERIAL_FIELDS.items()})
    t0 = time.process_time()
    try:
        pack = settle_pack(W, H, material=mat, rng=seed)
        asm = build_assembly(W, H, n_layers=N_LAYERS, pack=pack)
        s = values["strength_contrast"]
        layers = layer_materials(alternation(N_LAYERS, 4), mat, s) if s > 1 else None
        snaps = simulate(asm, NormalFault(), mat, n_snapshots=3, rng=seed,
                         layer_materials=layers)
    except SimulationError as exc:
        return {"status": "unstable", "error": str(exc),
                "cpu_s": round(time.process_time() - t0, 1)}
    return {"status": "stable", "steps": int(snaps[-1].step), "n_elements": int(asm.n),
            "cpu_s": round(time.process_time() - t0, 1)}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--runs", type=int, default=8)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--max-cost", type=float, default=2.0)
    ap.add_argument("--timeout", type=float, default=600.0)
    ap.add_argument("--max-draws", type=int, default=2000)
    ap.add_argument("--ranges", choices=("declared", "stage"), default="declared",
                    help="draw over the config ranges or the wider stage domains")
    ap.add_argument("--corners", action="store_true",
                    help="run the strong and weak corner per contact model, not random draws")
    ap.add_argument("--one", default=None, help=argparse.SUPPRESS)  # child: JSON of one draw
    args = ap.parse_args(argv)
    if args.one is not None:
        print(json.dumps(run_one(json.loads(args.one), args.seed)))
        return 0
    rng = np.random.default_rng(args.seed)
    counts = {"refused": 0, "too_costly": 0, "stable": 0, "unstable": 0, "timeout": 0}
    reasons: dict[str, int] = {}
    ran = 0
    fixed = corners(args.ranges) if args.corners else None
    for k in range(len(fixed) if fixed else args.max_draws):
        if not fixed and ran >= args.runs:
            break
        label, values = fixed[k] if fixed else (k, draw(rng, args.ranges))
        row = {"draw": label, **{n: (round(v, 6) if isinstance(v, float) else v)
                                 for n, v in values.items()}}
        why = check(values)
        if why is not None:
            counts["refused"] += 1
            key = re.sub(r"[-+]?\d[\d.e+-]*", "#", why)[:70]  # the rule, not the numbers
            reasons[key] = reasons.get(key, 0) + 1
            continue  # refused draws are counted, not printed one by one
        ratio = cost_ratio(values)
        row["cost_ratio"] = round(ratio, 2)
        if ratio > args.max_cost:
            counts["too_costly"] += 1
            print(json.dumps({**row, "status": "too_costly"}), flush=True)
            continue
        ran += 1
        t0 = time.time()
        try:
            out = subprocess.run([sys.executable, __file__, "--one", json.dumps(values),
                                  "--seed", str(args.seed)], capture_output=True, text=True,
                                 timeout=args.timeout)
            res = json.loads(out.stdout.strip().splitlines()[-1]) if out.returncode == 0 else {
                "status": "unstable", "error": out.stderr.strip()[-300:]}
        except subprocess.TimeoutExpired:
            res = {"status": "timeout"}
        counts[res["status"]] += 1
        print(json.dumps({**row, **res, "wall_s": round(time.time() - t0, 1)}), flush=True)
    print(json.dumps({"benchmark": "ranges_sweep", "ranges": args.ranges, "seed": args.seed,
                      "corners": args.corners, "runs": ran,
                      **counts, "refusal_reasons": reasons}))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
