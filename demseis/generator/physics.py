"""Physical sanity of a config: refuse sweeps that cannot make a fault or are not quasi-static.

A single parameter's range cannot express these: each rule combines several keys. Every rule
is checked at the sweep's worst corner (the extreme values its specs can produce), so a config
that passes can never draw a run that breaks a rule. The derivations are in docs/dem.md
("Physical sanity of a config").

Symbols: ρ density, Kn normal stiffness, r_min / r_max radii, m = ρπr² (unit thickness),
dt = 0.25 sqrt(m_min / Kn) (Eq. 5), η = dt · damping_scale, g gravity, v wall speed, δ dip.

1. ``gravity_m_s2 > 0``: without gravity there is no overburden, so no normal force for the
   Coulomb slider and nothing pulls the cover after the sinking basement.
2. Shear strength: μ_eff = μ + C0 / F_ref ≥ 0.05, F_ref = ρ g (H/2) · 2 r̄ the contact force of
   lithostatic load at mid-depth. μ = 0 with C0 = 0 is a granular fluid (the quick model's "fault"
   mask then covers 3× the pixels of the default material: diffuse flow, not a slip surface);
   μ = 0.05 with C0 = 0 is the weakest material measured to localise a fault.
3. Quasi-static wall: v ≤ 1e-2 · c with c = 2 sqrt(Kn / (πρ)), the p-wave speed of a chain of
   disks (spacing 2r, spring Kn, mass ρπr²; independent of r). The wall then moves
   v · dt = (v / c) · r_min / 2 ≤ 0.5% of r_min per step. At the default Kn and ρ (c = 2257 m/s)
   the default 5 m/s is 2.2e-3 c; 10 m/s (4.4e-3 c) was measured within 2× of the run-to-run
   floor, 20 m/s (8.9e-3 c) still makes a fault, 100 m/s (4.4e-2 c) makes none.
4. The hanging wall follows its base: the terminal sinking speed of the smallest element,
   m_min g / η, must be ≥ v sin δ: slower, even a free element cannot keep up with the base
   (at the paper's damping 3e9 it was 0.41 v sin δ and the hanging wall detached; the default
   damping gives 4.1 v sin δ at 45°).
5. Damping dissipates: ``damping_scale > 0`` and the run lasts at least one kinetic-energy
   relaxation time of the heaviest element, τ = m_max / η ≤ T = throw / (v sin δ).
"""

from __future__ import annotations

import math
from typing import Any

from demseis.errors import ConfigError

#: smallest effective friction coefficient (μ + C0 / F_ref) accepted (rule 2)
MIN_EFFECTIVE_FRICTION = 0.05
#: largest wall speed as a fraction of the p-wave speed 2 sqrt(Kn / (πρ)) (rule 3)
MAX_WALL_MACH = 1.0e-2
#: terminal sinking speed of the smallest element over the basement's vertical speed (rule 4)
MIN_TERMINAL_OVER_WALL = 1.0


def p_wave_speed_m_s(kn_n_m: float, density_kg_m3: float) -> float:
    """Longitudinal wave speed of a chain of touching disks, 2 sqrt(Kn / (π ρ)) (m/s)."""
    return 2.0 * math.sqrt(kn_n_m / (math.pi * density_kg_m3))


def check_physics(cfg: Any) -> None:
    """Raise :class:`ConfigError` with the reason if ``cfg`` cannot make a quasi-static fault.

    ``cfg`` is a :class:`demseis.generator.config.Config`; see the module docstring for the rules.
    """
    from demseis.generator.params import spec_values_hint

    def rng_of(key: str) -> tuple[float, float]:
        lo, hi = spec_values_hint(cfg.sweep.params[key])
        return float(lo), float(hi)

    m = cfg.model
    g_lo, _ = rng_of("gravity_m_s2")
    rho_lo, rho_hi = rng_of("density_kg_m3")
    kn_lo, kn_hi = rng_of("kn_n_m")
    mu_lo, _ = rng_of("friction")
    c0_lo, _ = rng_of("cohesion_n")
    d_lo, d_hi = rng_of("damping_scale")
    dip_lo, dip_hi = rng_of("dip_deg")
    throw_lo, _ = rng_of("throw_m")
    v = m.wall_speed_m_s
    sin_hi = math.sin(math.radians(dip_hi))

    if g_lo <= 0:
        raise ConfigError("sweep.gravity_m_s2 must be > 0: without gravity there is no "
                          "overburden, no frictional strength and nothing pulls the cover "
                          "after the sinking basement, so no fault forms")
    r_mean = 0.5 * (m.radius_min_m + m.radius_max_m)
    f_ref = rho_lo * g_lo * 0.5 * m.height_m * 2.0 * r_mean
    mu_eff = mu_lo + c0_lo / f_ref
    if mu_eff < MIN_EFFECTIVE_FRICTION:
        raise ConfigError(
            f"sweep.friction down to {mu_lo:g} with sweep.cohesion_n down to {c0_lo:g} N gives "
            f"contacts almost no shear strength (friction + cohesion / {f_ref:.3g} N = "
            f"{mu_eff:.3g} < {MIN_EFFECTIVE_FRICTION:g}): the assembly flows like a fluid "
            "instead of faulting; raise friction or cohesion_n")
    c = p_wave_speed_m_s(kn_lo, rho_hi)
    if v > MAX_WALL_MACH * c:
        raise ConfigError(
            f"model.wall_speed_m_s = {v:g} is not quasi-static: it must be <= "
            f"{MAX_WALL_MACH:g} x the p-wave speed 2 sqrt(kn_n_m / (pi density_kg_m3)) = "
            f"{c:.4g} m/s (at kn_n_m = {kn_lo:g}, density_kg_m3 = {rho_hi:g}), i.e. <= "
            f"{MAX_WALL_MACH * c:.3g} m/s")
    if d_lo <= 0:
        raise ConfigError("sweep.damping_scale must be > 0: without damping the work of the "
                          "moving wall stays in the assembly as elastic waves (a dynamic run, "
                          "not a quasi-static one)")
    # rule 4: slowest terminal speed at the smallest g, Kn, density and the largest damping
    m_min_lo = rho_lo * math.pi * m.radius_min_m**2
    dt = 0.25 * math.sqrt(m_min_lo / kn_lo)
    v_term = m_min_lo * g_lo / (dt * d_hi)
    if v_term < MIN_TERMINAL_OVER_WALL * v * sin_hi:
        raise ConfigError(
            f"sweep.damping_scale up to {d_hi:g} is too strong for model.wall_speed_m_s = {v:g}: "
            f"the smallest element sinks at most m g / eta = {v_term:.3g} m/s, below "
            f"{MIN_TERMINAL_OVER_WALL:g} x the basement's vertical speed ({v * sin_hi:.3g} m/s "
            f"at dip {dip_hi:g} deg), so the hanging wall detaches from its base; lower "
            "damping_scale or wall_speed_m_s")
    # rule 5: longest relaxation time (largest density and Kn, smallest damping)
    m_max_hi = rho_hi * math.pi * m.radius_max_m**2
    dt_hi = 0.25 * math.sqrt(rho_hi * math.pi * m.radius_min_m**2 / kn_hi)
    tau = m_max_hi / (dt_hi * d_lo)
    t_run = throw_lo / (v * sin_hi)
    if tau > t_run:
        raise ConfigError(
            f"sweep.damping_scale down to {d_lo:g} is too weak: the heaviest element's "
            f"kinetic energy relaxes in m / eta = {tau:.3g} s, longer than the shortest run "
            f"(throw {throw_lo:g} m at {v:g} m/s and dip {dip_hi:g} deg: {t_run:.3g} s), so "
            "the run is dynamic; raise damping_scale or throw_m, or lower wall_speed_m_s")
