"""demseis DEM vs LAMMPS (serial) on the same settled pack: throughput, and a physics peer check.

Usage::

    NUMBA_NUM_THREADS=1 python benchmarks/dem_vs_lammps.py [--steps 2000] [--repeats 3]
        [--pack FILE.npz] [--peer] [--peer-steps 20000]

Prints ONE JSON line.

Throughput: the settled seed-scale pack (about 11,000 disks, radii 12.5-25 m, 5 km wide) runs
``--steps`` steps in each code, alternately ``--repeats`` times (the machine is shared, so both
are timed side by side and medians are compared). Element-steps/s = n x steps / loop seconds;
LAMMPS' loop seconds are its "Loop time"; demseis' the wall time of ``Integrator.run``. CPU-time
rates are reported too (LAMMPS: loop time x its "% CPU use").

Matched settings (SI units, 2D, per metre of thickness):

- contact: LAMMPS ``pair gran/hooke/history Kn Kt 0 0 mu 0`` (no normal/tangential damping,
  dampflag 0) with Kn = Material.kn_n_m, Kt = ks_ratio * Kn, mu = friction. Both codes use
  F_n = Kn * overlap and an incremental tangential spring capped at mu F_n;
- no rotation: LAMMPS integrates with ``fix nve`` (translation only), so omega stays 0 and the
  contact velocity has no omega x r term - as in demseis;
- masses: ``set type 1 density/disc rho`` gives m = rho pi r^2 (LAMMPS 2021's ``density``
  would use the sphere volume); demseis uses m = rho pi r^2;
- damping: ``fix viscous eta`` with eta = dt * damping_scale, as demseis' global damping;
- gravity: ``fix gravity g vector 0 -1 0``; 2D: ``dimension 2``, ``fix enforce2d``;
- walls: ``fix wall/gran hooke/history`` planes at the pack's left, right and bottom with the
  same Kn, Kt, mu (demseis: segment walls at the same places);
- time step: the paper's Eq. 5, dt = 0.25 sqrt(m_min / Kn), in both;
- neighbour lists: LAMMPS ``neighbor <skin> bin`` with demseis' skin, ``check yes``;
  ``newton on`` (measured as fast as ``off`` here; DEMSEIS_LMP_NEWTON=off switches).

Peer check (``--peer``): both codes start from the same loose, unsettled arrangement
(:func:`demseis.dem.assembly.loose_grid` of the seed-scale radii in a narrower box) and settle
under gravity for ``--peer-steps`` steps; the packing fraction of the region below the settled
surface and the mean coordination number (contacts with overlap > 0, disk-disk only) are
compared.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import re
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from demseis.dem import Material  # noqa: E402,F401
from demseis.dem.assembly import draw_radii, loose_grid  # noqa: E402
from demseis.dem.integrator import Integrator, time_step  # noqa: E402
from demseis_dev.bench import BENCH_MATERIAL, load_pack, pack_walls, seed_pack  # noqa: E402


def write_lammps_data(path: Path, xy: np.ndarray, radius: np.ndarray, box: tuple) -> None:
    """LAMMPS data file, atom_style sphere: id type diameter density x y z."""
    xlo, xhi, ylo, yhi = box
    n = radius.size
    with open(path, "w") as f:
        f.write("demseis pack\n\n")
        f.write(f"{n} atoms\n1 atom types\n\n")
        f.write(f"{xlo:.6f} {xhi:.6f} xlo xhi\n{ylo:.6f} {yhi:.6f} ylo yhi\n"
                "-0.5 0.5 zlo zhi\n\nAtoms # sphere\n\n")
        for i in range(n):
            f.write(f"{i + 1} 1 {2 * radius[i]:.9f} 1.0 {xy[i, 0]:.9f} {xy[i, 1]:.9f} 0\n")


NEWTON = os.environ.get("DEMSEIS_LMP_NEWTON", "on")


def lammps_input(data: Path, mat: Material, dt: float, skin: float, walls: np.ndarray,
                 n_steps: int, dump: Path | None) -> str:
    kn = mat.kn_n_m
    kt = mat.ks_ratio * kn
    mu = mat.friction
    eta = dt * mat.damping_scale
    (xlo, _, _, _), (xhi, _, _, _), (_, ylo, _, _) = walls[0], walls[1], walls[2]
    lines = [
        "units si", "dimension 2", "atom_style sphere", "atom_modify map array",
        "boundary f f p", f"newton {NEWTON}", "comm_modify vel yes",
        f"read_data {data}",
        f"set type 1 density/disc {mat.density_kg_m3}",
        f"pair_style gran/hooke/history {kn} {kt} 0.0 0.0 {mu} 0",
        "pair_coeff * *",
        f"neighbor {skin} bin", "neigh_modify delay 0 every 1 check yes",
        f"fix wl all wall/gran hooke/history {kn} {kt} 0.0 0.0 {mu} 0 xplane {xlo} {xhi}",
        f"fix wb all wall/gran hooke/history {kn} {kt} 0.0 0.0 {mu} 0 yplane {ylo} NULL",
        f"fix grav all gravity {mat.gravity_m_s2} vector 0 -1 0",
        f"fix visc all viscous {eta}",
        "fix integ all nve", "fix e2d all enforce2d",
        f"timestep {dt}", "thermo 1000", "thermo_modify lost error",
        f"run {n_steps}",
    ]
    if dump is not None:
        lines.append(f"write_dump all custom {dump} id x y radius modify sort id")
    return "\n".join(lines) + "\n"


def run_lammps(workdir: Path, xy, radius, mat, dt, skin, walls, n_steps, dump=False):
    """Run lmp serially; returns (loop_s, cpu_fraction, final xy or None)."""
    data = workdir / "pack.data"
    span = float(radius.max()) * 20
    box = (walls[0, 0] - span, walls[1, 0] + span, walls[2, 1] - span,
           float(np.max(xy[:, 1] + radius)) + span)
    write_lammps_data(data, xy, radius, box)
    dump_path = workdir / "final.dump" if dump else None
    inp = workdir / "in.bench"
    inp.write_text(lammps_input(data, mat, dt, skin, walls, n_steps, dump_path))
    env = dict(os.environ, OMP_NUM_THREADS="1")
    out = subprocess.run(["lmp", "-in", str(inp), "-log", "none", "-nocite"], cwd=workdir,
                         capture_output=True, text=True, env=env)
    if out.returncode != 0:
        raise RuntimeError(f"lmp failed: {out.stdout[-2000:]}\n{out.stderr[-2000:]}")
    m = re.search(r"Loop time of ([0-9.eE+-]+) on 1 procs for (\d+) steps with (\d+) atoms",
                  out.stdout)
    if not m:
        raise RuntimeError(f"no Loop time in lmp output:\n{out.stdout[-2000:]}")
    loop = float(m.group(1))
    c = re.search(r"([0-9.]+)% CPU use", out.stdout)
    cpu_frac = float(c.group(1)) / 100 if c else float("nan")
    final = None
    if dump:
        rows = np.loadtxt(dump_path, skiprows=9)
        rows = rows[np.argsort(rows[:, 0])]
        final = rows[:, 1:3]
    return loop, cpu_frac, final


def run_demseis(xy, radius, mat, walls, n_steps, skin):
    eng = Integrator(xy, radius, mat, skin_m=skin)
    eng.set_walls(walls)
    eng.run(5)  # compile / load the Numba cache, build the list
    t0 = time.perf_counter()
    c0 = time.process_time()
    eng.run(n_steps)
    return time.perf_counter() - t0, time.process_time() - c0, eng


def packing_and_coordination(xy, radius, width_lo, width_hi, base):
    """Packing fraction below the settled surface (minus 2 r_max) and mean disk coordination."""
    rmax = float(radius.max())
    top = np.sort(xy[:, 1] + radius)[-max(5, radius.size // 50):].mean()
    y_hi = top - 3 * rmax
    y_lo = base + 2 * rmax
    x_lo, x_hi = width_lo + 2 * rmax, width_hi - 2 * rmax
    # area of disks inside the window, by sampling a fine grid
    gx = np.arange(x_lo, x_hi, 1.0)
    gy = np.arange(y_lo, y_hi, 1.0)
    from scipy.spatial import cKDTree
    tree = cKDTree(xy)
    pts = np.stack(np.meshgrid(gx, gy), -1).reshape(-1, 2)
    d, idx = tree.query(pts, k=4, distance_upper_bound=2 * rmax)
    inside = np.zeros(len(pts), bool)
    for k in range(4):
        ok = np.isfinite(d[:, k])
        inside[ok] |= d[ok, k] < radius[idx[ok, k]]
    phi = inside.mean()
    pairs = tree.query_pairs(2 * rmax, output_type="ndarray")
    dd = np.hypot(*(xy[pairs[:, 0]] - xy[pairs[:, 1]]).T)
    contact = dd < radius[pairs[:, 0]] + radius[pairs[:, 1]]
    z = np.bincount(pairs[contact].ravel(), minlength=radius.size)
    # mean coordination of disks away from walls and surface
    sel = (xy[:, 0] > x_lo) & (xy[:, 0] < x_hi) & (xy[:, 1] > y_lo) & (xy[:, 1] < y_hi)
    return float(phi), float(z[sel].mean())


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--steps", type=int, default=2000)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--pack", default=None, help=".npz with x, y, radius (m)")
    ap.add_argument("--peer", action="store_true", help="also run the settling peer check")
    ap.add_argument("--peer-steps", type=int, default=20000)
    ap.add_argument("--peer-width", type=float, default=2000.0)
    args = ap.parse_args(argv)
    if shutil.which("lmp") is None:
        print(json.dumps({"benchmark": "dem_vs_lammps", "error": "lmp not found"}))
        return 1
    mat = BENCH_MATERIAL
    if args.pack:
        xy, radius = load_pack(args.pack)
    else:
        p = seed_pack()
        xy, radius = p.xy, p.radius
    dt = time_step(float(radius.min()), mat.density_kg_m3, mat.kn_n_m)
    skin = 0.3 * float(radius.min())
    walls = pack_walls(xy, radius)
    n = radius.size
    res = {"benchmark": "dem_vs_lammps", "n_elements": int(n), "steps": args.steps,
           "dt_s": dt, "skin_m": skin, "repeats": args.repeats,
           "numba_threads": os.environ.get("NUMBA_NUM_THREADS")}
    lmp_rate, lmp_cpu_rate, dem_rate, dem_cpu_rate = [], [], [], []
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        for _ in range(args.repeats):
            loop, frac, _ = run_lammps(tmp, xy, radius, mat, dt, skin, walls, args.steps)
            lmp_rate.append(n * args.steps / loop)
            lmp_cpu_rate.append(n * args.steps / (loop * frac))
            wall, cpu, _ = run_demseis(xy, radius, mat, walls, args.steps, skin)
            dem_rate.append(n * args.steps / wall)
            dem_cpu_rate.append(n * args.steps / cpu)
        res.update({
            "lammps_element_steps_per_s": statistics.median(lmp_rate),
            "demseis_element_steps_per_s": statistics.median(dem_rate),
            "ratio_demseis_over_lammps": statistics.median(dem_rate) / statistics.median(lmp_rate),
            "lammps_element_steps_per_cpu_s": statistics.median(lmp_cpu_rate),
            "demseis_element_steps_per_cpu_s": statistics.median(dem_cpu_rate),
            "ratio_cpu": statistics.median(dem_cpu_rate) / statistics.median(lmp_cpu_rate),
            "lammps_rates": lmp_rate, "demseis_rates": dem_rate,
        })
        if args.peer:
            rng = np.random.default_rng(7)
            w = args.peer_width
            n_peer = int(0.84 * w * 1200.0 / (math.pi * 339.0))
            r0 = draw_radii(n_peer, float(radius.min()), float(radius.max()), rng)
            xy0 = loose_grid(r0, 0.0, w, 0.0, rng, gap=0.05 * float(radius.min()))
            pw = np.array([[0.0, 0.0, 0.0, 1e5], [w, 0.0, w, 1e5], [0.0, 0.0, w, 0.0]])
            _, _, final_l = run_lammps(tmp, xy0, r0, mat, dt, skin, pw, args.peer_steps,
                                       dump=True)
            _, _, eng = run_demseis(xy0, r0, mat, pw, args.peer_steps, skin)
            phi_l, z_l = packing_and_coordination(final_l, r0, 0.0, w, 0.0)
            phi_d, z_d = packing_and_coordination(eng.pos, r0, 0.0, w, 0.0)
            res["peer"] = {"n": int(n_peer), "steps": args.peer_steps,
                           "packing_lammps": phi_l, "packing_demseis": phi_d,
                           "packing_rel_diff": abs(phi_d - phi_l) / phi_l,
                           "coordination_lammps": z_l, "coordination_demseis": z_d,
                           "coordination_rel_diff": abs(z_d - z_l) / z_l,
                           "median_position_diff_m": float(
                               np.median(np.hypot(*(eng.pos - final_l).T)))}
    print(json.dumps(res))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
