"""Cost of the 2-D PSF imaging beside the 1-D render, side by side; prints one JSON line.

Usage: ``NUMBA_NUM_THREADS=1 PYTHONPATH=. python benchmarks/seismic_psf.py [--repeats 21]``

The snapshot is the one of ``python -m demseis_dev.bench seismic`` (the last, throw 450 m, of the kinematic
toy sequence on 512 x 288 cells of 10 m). Each repeat times, back to back so that machine load
hits all alike: the whole per-snapshot render (element properties -> property grids ->
sections) with the 1-D convolution and with the PSF, and the section step alone
(``synthetic_sections`` vs ``psf_sections``), for one frequency (20 Hz) and for 20/40/60 Hz,
in depth (constant angle 30 deg; 30 deg with a 2 km aperture, 4 blended windows) and in time
(2 ms, 4 windows). Reported: medians of wall-clock and of process-CPU ms (the better estimate
on a loaded machine) and the ratios PSF / 1-D of the medians.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # demseis_dev: the checkout's

import numpy as np

from demseis.seismic.forward import synthetic_sections, time_axis
from demseis.seismic.properties import (PropertyModel, draw_layer_properties, element_properties,
                                        property_grids)
from demseis.seismic.psf import psf_sections
from demseis.types import Grid
from demseis_dev.toys import faulted_sequence


def run(nx: int = 512, nz: int = 288, cell_m: float = 10.0, repeats: int = 21,
        angle_deg: float = 30.0) -> dict:
    """Medians (ms) of the 1-D and PSF renders of one toy snapshot; see the module docstring."""
    rng = np.random.default_rng(0)
    snap = faulted_sequence(nx * cell_m, nz * cell_m, rng=rng)[-1]
    grid = Grid.covering(nx * cell_m, nz * cell_m, cell_m)
    model = PropertyModel().validate()
    lp = draw_layer_properties(int(snap.layer.max()) + 1, model, rng)
    t_s = time_axis(grid.nz, cell_m, model.vp_lower_bound_m_s, 0.002)

    def grids():
        ve, re = element_properties(snap.ids, snap.layer, lp, model, 0)
        return property_grids(snap.xy, snap.radius, ve, re, snap.layer, grid, model)

    vp_g, rho_g = grids()
    f1, f3 = (20.0,), (20.0, 40.0, 60.0)
    cases = {}
    for fr, tag in ((f1, "1f"), (f3, "3f")):
        cases[f"section_depth_1d_{tag}"] = lambda fr=fr: synthetic_sections(vp_g, rho_g, cell_m, fr)
        cases[f"section_depth_psf_{tag}"] = lambda fr=fr: psf_sections(
            vp_g, rho_g, cell_m, fr, angle_deg)
        cases[f"section_depth_psf_aperture_{tag}"] = lambda fr=fr: psf_sections(
            vp_g, rho_g, cell_m, fr, angle_deg, aperture_m=2000.0)
        cases[f"section_time_1d_{tag}"] = lambda fr=fr: synthetic_sections(
            vp_g, rho_g, cell_m, fr, "time", t_s=t_s)
        cases[f"section_time_psf_{tag}"] = lambda fr=fr: psf_sections(
            vp_g, rho_g, cell_m, fr, angle_deg, "time", t_s=t_s)
        cases[f"snapshot_depth_1d_{tag}"] = lambda fr=fr: synthetic_sections(*grids(), cell_m, fr)
        cases[f"snapshot_depth_psf_{tag}"] = lambda fr=fr: psf_sections(
            *grids(), cell_m, fr, angle_deg)
        cases[f"snapshot_time_1d_{tag}"] = lambda fr=fr: synthetic_sections(
            *grids(), cell_m, fr, "time", t_s=t_s)
        cases[f"snapshot_time_psf_{tag}"] = lambda fr=fr: psf_sections(
            *grids(), cell_m, fr, angle_deg, "time", t_s=t_s)
    for fn in cases.values():            # warm-up: Numba cache load, FFT plans
        fn()
    wall: dict[str, list[float]] = {k: [] for k in cases}
    cpu: dict[str, list[float]] = {k: [] for k in cases}
    for _ in range(repeats):
        for name, fn in cases.items():
            t0, c0 = time.perf_counter(), time.process_time()
            fn()
            wall[name].append(time.perf_counter() - t0)
            cpu[name].append(time.process_time() - c0)
    med = {k: round(float(np.median(v)) * 1e3, 2) for k, v in wall.items()}
    med_cpu = {k: round(float(np.median(v)) * 1e3, 2) for k, v in cpu.items()}

    def ratios(m):
        out = {}
        for k in m:
            if "_psf" in k:
                base = k.replace("_psf_aperture", "_1d").replace("_psf", "_1d")
                out[k + "_over_1d"] = round(m[k] / m[base], 2)
        return out

    return {
        "benchmark": "seismic_psf",
        "nz": grid.nz, "nx": grid.nx, "nt_time": int(t_s.size), "cell_m": cell_m,
        "n_elements": int(snap.ids.shape[0]), "max_angle_deg": angle_deg,
        "repeats": repeats, "cpu": platform.processor() or platform.machine(),
        "numba_threads": os.environ.get("NUMBA_NUM_THREADS", "default"),
        "loadavg_1min": round(os.getloadavg()[0], 2),
        "median_ms": med, "ratio_of_medians": ratios(med),
        "median_cpu_ms": med_cpu, "ratio_of_cpu_medians": ratios(med_cpu),
    }


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--nx", type=int, default=512)
    p.add_argument("--nz", type=int, default=288)
    p.add_argument("--repeats", type=int, default=21)
    p.add_argument("--angle-deg", type=float, default=30.0)
    a = p.parse_args()
    print(json.dumps(run(a.nx, a.nz, repeats=a.repeats, angle_deg=a.angle_deg)))


if __name__ == "__main__":
    main()
