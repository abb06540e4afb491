"""Physical sanity of a config: refuse sweeps that cannot make a fault or are not quasi-static.

A single parameter's range cannot express these: each rule combines several keys. Every rule
is checked at the sweep's worst corner (the extreme values its specs can produce), so a config
that passes can never draw a run that breaks a rule. The derivations are in docs/dem.md
("Physical sanity of a config").

Symbols: ρ density, Kn normal stiffness, r_min / r_max radii, m = ρπr² (unit thickness),
dt = 0.25 sqrt(m_min / Kn) (Eq. 5), η = dt · damping_scale, g gravity, v wall speed, δ dip.

The declared ranges (:mod:`demseis.parameters`) already hold gravity at Earth's, friction at
>= 0.2 and damping at >= 3e8: every config has an overburden, shear strength (a frictionless,
cohesionless pack flows like a fluid instead of faulting) and dissipation. The rules left
combine the mechanics with the model's wall speed and the fault's dip and throw:

1. Quasi-static wall: v ≤ 1e-2 · c with c = 2 sqrt(Kn / (πρ)), the p-wave speed of a chain of
   disks (spacing 2r, spring Kn, mass ρπr²; independent of r). The wall then moves
   v · dt = (v / c) · r_min / 2 ≤ 0.5% of r_min per step. At the default Kn and ρ (c = 2257 m/s)
   the default 5 m/s is 2.2e-3 c; 10 m/s (4.4e-3 c) was measured within 2× of the run-to-run
   floor, 20 m/s (8.9e-3 c) still makes a fault, 100 m/s (4.4e-2 c) makes none.
2. The hanging wall follows its base: the terminal sinking speed of the smallest element,
   m_min g / η, must be ≥ v sin δ: slower, even a free element cannot keep up with the base
   (at the paper's damping 3e9 it was 0.41 v sin δ and the hanging wall detached; the default
   damping gives 4.1 v sin δ at 45°).
3. Damping dissipates: the run lasts at least one kinetic-energy relaxation time of the
   heaviest element, τ = m_max / η ≤ T = max(throw / (v sin δ), |base_stretch| W / v) (a run
   lasts the longer of its slip and its base stretch; without a basement fault,
   ``structure = "none"``, only the stretch).
"""

from __future__ import annotations

import math
from typing import Any

from demseis.errors import ConfigError
from demseis.generator.config.params import Fixed, GridSpec, spec_values_hint

#: largest wall speed as a fraction of the p-wave speed 2 sqrt(Kn / (πρ)) (rule 1)
MAX_WALL_MACH = 1.0e-2
#: terminal sinking speed of the smallest element over the basement's vertical speed (rule 2)
MIN_TERMINAL_OVER_WALL = 1.0


def p_wave_speed_m_s(kn_n_m: float, density_kg_m3: float) -> float:
    """Longitudinal wave speed of a chain of touching disks, 2 sqrt(Kn / (π ρ)) (m/s)."""
    return 2.0 * math.sqrt(kn_n_m / (math.pi * density_kg_m3))


def check_physics(cfg: Any) -> None:
    """Raise :class:`ConfigError` with the reason if ``cfg`` cannot make a quasi-static fault.

    ``cfg`` is a :class:`demseis.generator.config.settings.Config`; see the module docstring for the rules.
    """
    def rng_of(key: str) -> tuple[float, float]:
        lo, hi = spec_values_hint(cfg.sweep.params[key])
        return float(lo), float(hi)

    m = cfg.model
    g_lo, _ = rng_of("gravity_m_s2")
    rho_lo, rho_hi = rng_of("density_kg_m3")
    kn_lo, kn_hi = rng_of("kn_n_m")
    d_lo, d_hi = rng_of("damping_scale")
    dip_lo, dip_hi = rng_of("dip_deg")
    throw_lo, _ = rng_of("throw_m")
    v = m.wall_speed_m_s
    sin_hi = math.sin(math.radians(dip_hi))

    c = p_wave_speed_m_s(kn_lo, rho_hi)
    if v > MAX_WALL_MACH * c:
        raise ConfigError(
            f"model.wall_speed_m_s = {v:g} is not quasi-static: it must be <= "
            f"{MAX_WALL_MACH:g} x the p-wave speed 2 sqrt(kn_n_m / (pi density_kg_m3)) = "
            f"{c:.4g} m/s (at kn_n_m = {kn_lo:g}, density_kg_m3 = {rho_hi:g}), i.e. <= "
            f"{MAX_WALL_MACH * c:.3g} m/s")
    # rule 2: slowest terminal speed at the smallest g, Kn, density and the largest damping
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
    # rule 3: longest relaxation time (largest density and Kn, smallest damping)
    m_max_hi = rho_hi * math.pi * m.radius_max_m**2
    dt_hi = 0.25 * math.sqrt(rho_hi * math.pi * m.radius_min_m**2 / kn_hi)
    tau = m_max_hi / (dt_hi * d_lo)
    # a run lasts the longer of its slip and its base stretch (|base_stretch| * width) at v;
    # a run without basement fault (structure "none") only the stretch
    stretch = cfg.sweep.params["base_stretch"]
    if isinstance(stretch, (Fixed, GridSpec)) or stretch.dist == "choice":
        listed = (stretch.value,) if isinstance(stretch, Fixed) else stretch.values
        stretch_lo = min(abs(float(x)) for x in listed)
    else:                                  # a distribution: as close to 0 as its range allows
        s_lo, s_hi = rng_of("base_stretch")
        stretch_lo = 0.0 if s_lo <= 0.0 <= s_hi else min(abs(s_lo), abs(s_hi))
    t_stretch = stretch_lo * m.width_m / v
    spec = cfg.sweep.params["structure"]
    structures = ((spec.value,) if isinstance(spec, Fixed) else
                  spec.values if isinstance(spec, GridSpec) else tuple(spec.values or ()))
    t_slip = throw_lo / (v * sin_hi)
    t_run = min(max(t_slip, t_stretch), t_stretch if "none" in structures else math.inf)
    if tau > t_run:
        what = (f"throw {throw_lo:g} m at {v:g} m/s and dip {dip_hi:g} deg"
                if t_run == t_slip else
                f"base stretch {stretch_lo:g} x width {m.width_m:g} m at {v:g} m/s")
        raise ConfigError(
            f"sweep.damping_scale down to {d_lo:g} is too weak: the heaviest element's "
            f"kinetic energy relaxes in m / eta = {tau:.3g} s, longer than the shortest run "
            f"({what}: {t_run:.3g} s), so the run is dynamic; raise damping_scale, throw_m or "
            "|base_stretch|, or lower wall_speed_m_s")
