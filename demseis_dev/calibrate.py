"""Biaxial test of an element assembly: bulk friction angle and cohesion of a Material.

A rectangular sample (a settled pack, gravity then switched off) sits between four walls: the
bottom is fixed, the left/right walls are servo-controlled to hold the confining stress
sigma3, and the top wall moves down at a constant strain rate after an isotropic
consolidation. The peak axial stress sigma1 at two or more confinements gives the
Mohr-Coulomb envelope

    sigma1 = 2 c cos(phi) / (1 - sin(phi)) + sigma3 (1 + sin(phi)) / (1 - sin(phi)).

Stresses are 2D (force per metre of thickness / wall length, Pa).
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from demseis.dem.assembly import settle_pack
from demseis.dem.integrator import Integrator
from demseis.dem.types import Material
from demseis.errors import InputError


def _wall_normal_forces(eng: Integrator) -> np.ndarray:
    """Normal force (N/m) each wall of ``eng`` carries: sum of Kn * overlap of its contacts."""
    out = np.zeros(eng.walls.shape[0])
    for w, (x0, y0, x1, y1) in enumerate(eng.walls):
        e = np.array([x1 - x0, y1 - y0])
        p = eng.pos - (x0, y0)
        s = np.clip(p @ e / (e @ e), 0.0, 1.0)
        d = np.hypot(*(p - s[:, None] * e).T)
        ov = eng.radius - d
        out[w] = eng.kn * ov[ov > 0].sum()
    return out


def biaxial_test(material: Material = Material(), sigma3_pa: float = 10e6, *,
                 width_m: float = 400.0, height_m: float = 800.0, strain_rate_s: float = 0.001,
                 max_axial_strain: float = 0.08, seed: int = 0, cache_dir=None) -> dict:
    """Peak axial stress of a biaxial test at confining stress ``sigma3_pa``.

    Returns
    -------
    dict with ``sigma3_pa``, ``peak_sigma1_pa``, ``axial_strain_at_peak``, ``curve``
    ((k, 2) axial strain, sigma1), ``n``.
    """
    if not (sigma3_pa > 0):
        raise InputError(f"sigma3_pa={sigma3_pa} must be > 0")
    pack = settle_pack(width_m, height_m, material=material, rng=seed, cache_dir=cache_dir)
    mat0 = replace(material, gravity_m_s2=0.0)
    xy, r = pack.xy, pack.radius
    mass = material.density_kg_m3 * math.pi * r**2
    eng = Integrator(xy, r, mat0, eta=1.0 * mass)
    top = float(np.max(xy[:, 1] + r))
    big = 10 * width_m
    # walls: 0 bottom, 1 left, 2 right, 3 top (long enough to stay covered)
    eng.set_walls(np.array([[-big, 0.0, big, 0.0], [0.0, -big, 0.0, big],
                            [width_m, -big, width_m, big], [-big, top, big, top]]))
    chunk = 20
    kn_eff = eng.kn * 4.0

    def servo(target_side, target_top, move_top):
        f = _wall_normal_forces(eng)
        h = eng.walls[3, 1] - eng.walls[0, 1]
        w = eng.walls[2, 0] - eng.walls[1, 0]
        dt_c = chunk * eng.dt
        # side walls: move outward when over-stressed
        v_side = 0.5 * (f[1] - target_side * h) / kn_eff / dt_c
        eng.wall_vel[1, 0] = -v_side
        eng.wall_vel[2, 0] = v_side
        if move_top is None:
            v_top = 0.5 * (f[3] - target_top * w) / kn_eff / dt_c
            eng.wall_vel[3] = (0.0, v_top)
        else:
            eng.wall_vel[3] = (0.0, -move_top)
        return f, h, w

    # isotropic consolidation
    for _ in range(400):
        servo(sigma3_pa, sigma3_pa, None)
        eng.run(chunk)
    h0 = eng.walls[3, 1] - eng.walls[0, 1]
    v_top = strain_rate_s * h0
    curve = []
    while True:
        f, h, w = servo(sigma3_pa, 0.0, v_top)
        strain = (h0 - h) / h0
        curve.append((strain, f[3] / w))
        if strain >= max_axial_strain:
            break
        eng.run(chunk)
    c = np.array(curve)
    k = int(np.argmax(c[:, 1]))
    return {"sigma3_pa": float(sigma3_pa), "peak_sigma1_pa": float(c[k, 1]),
            "axial_strain_at_peak": float(c[k, 0]), "curve": c, "n": eng.n}


def mohr_coulomb_fit(sigma3_pa, sigma1_pa) -> tuple[float, float]:
    """Friction angle (deg) and cohesion (Pa) from peak (sigma3, sigma1) pairs: the least-squares
    line sigma1 = a + b sigma3, b = (1 + sin phi) / (1 - sin phi), a = 2 c cos phi / (1 - sin phi).
    """
    s3 = np.asarray(sigma3_pa, float)
    s1 = np.asarray(sigma1_pa, float)
    if s3.size < 2:
        raise InputError("need at least two confinements")
    b, a = np.polyfit(s3, s1, 1)
    sin_phi = (b - 1) / (b + 1)
    phi = math.asin(max(min(sin_phi, 1.0), -1.0))
    c = a * (1 - sin_phi) / (2 * math.cos(phi))
    return math.degrees(phi), float(c)
