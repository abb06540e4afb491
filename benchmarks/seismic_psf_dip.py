"""How much of a planar reflector the PSF keeps, by dip; prints one JSON line.

Usage: ``PYTHONPATH=. python benchmarks/seismic_psf_dip.py [--angle-deg 30 --freq 30]``

A planar interface (Vp 2500 over 3500 m/s, constant density) through the centre of a
200 x 240 grid of 10 m cells, rendered in 1-D and with the PSF (depth and 2 ms time). For
each dip: the PSF's peak |amplitude| over the 1-D peak, and the same for the rms, over the
central half of the rows and columns. Three rasterisations of the same plane:

- ``area``: each cell takes the fraction of its area below the interface (8 x 8 sub-samples),
  i.e. the plane anti-aliased in both directions;
- ``vertical``: a cell cut by the interface takes the fraction of its height below it, at
  the column's centre (anti-aliased along z only);
- ``staircase``: a cell is in the lower medium when its centre is (what rasterising gives);
- ``smoothed``: the staircase after the generator's default smoothing (Gaussian 0.7 cells,
  3 x 3 median; ``demseis.seismic.smooth``).
"""

from __future__ import annotations

import argparse
import json
import math

import numpy as np

from demseis.seismic.forward import synthetic_sections, time_axis
from demseis.seismic.properties import PropertyModel, smooth
from demseis.seismic.psf import psf_sections


def plane(nz: int, nx: int, cell: float, dip_deg: float, kind: str) -> np.ndarray:
    """Vp of the planar interface of the module docstring."""
    z = (np.arange(nz) + 0.5)[:, None] * cell
    x = (np.arange(nx) + 0.5)[None, :] * cell
    zi = 0.5 * nz * cell + (x - 0.5 * nx * cell) * math.tan(math.radians(dip_deg))
    if kind == "area":
        sub = (np.arange(8) + 0.5) / 8.0 - 0.5
        frac = np.zeros((nz, nx))
        for dz in sub:
            for dx in sub:
                zz = z + dz * cell
                zs = zi + dx * cell * math.tan(math.radians(dip_deg))
                frac += (zz > zs) / 64.0
        return 2500.0 + 1000.0 * frac
    if kind == "vertical":
        return 2500.0 + 1000.0 * np.clip((z + 0.5 * cell - zi) / cell, 0.0, 1.0)
    vp = np.where(z > zi, 3500.0, 2500.0)
    return smooth(vp, PropertyModel()) if kind == "smoothed" else vp


def run(angle_deg: float = 30.0, freq: float = 30.0,
        dips=(15, 20, 25, 35, 40, 45, 50, 60, 70, 80)) -> dict:
    nz, nx, cell = 200, 240, 10.0
    t_s = time_axis(nz, cell, 2500.0, 0.002)
    out: dict[str, dict[str, list[float]]] = {}
    for kind in ("area", "vertical", "staircase", "smoothed"):
        for domain in ("depth", "time"):
            peaks, rmss = [], []
            for dip in dips:
                vp = plane(nz, nx, cell, dip, kind)
                rho = np.full_like(vp, 2300.0)
                ts = t_s if domain == "time" else None
                a = synthetic_sections(vp, rho, cell, [freq], domain, t_s=ts)[0]
                b = psf_sections(vp, rho, cell, [freq], angle_deg, domain, t_s=ts)[0]
                sl = (slice(a.shape[0] // 4, 3 * a.shape[0] // 4), slice(nx // 4, 3 * nx // 4))
                a, b = a[sl].astype(np.float64), b[sl].astype(np.float64)
                peaks.append(round(float(np.abs(b).max() / np.abs(a).max()), 3))
                rmss.append(round(float(np.sqrt((b ** 2).sum() / (a ** 2).sum())), 3))
            out[f"{kind}_{domain}"] = {"peak_ratio": peaks, "rms_ratio": rmss}
    return {"benchmark": "seismic_psf_dip", "max_angle_deg": angle_deg, "freq_hz": freq,
            "taper_deg": 5.0, "dips_deg": list(dips), "results": out}


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--angle-deg", type=float, default=30.0)
    p.add_argument("--freq", type=float, default=30.0)
    a = p.parse_args()
    print(json.dumps(run(a.angle_deg, a.freq)))


if __name__ == "__main__":
    main()
