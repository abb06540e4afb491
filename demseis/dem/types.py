"""Parameters of the DEM: the element :class:`Material` and the basement :class:`NormalFault`.

The particle :class:`demseis.types.Snapshot` the DEM returns lives in :mod:`demseis.types`.

Coordinates: x to the right, y up, metres. The model box is ``0 <= x <= width_m`` and
``0 <= y <= height_m`` before faulting (y = 0 is the top of the basement).
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class Material:
    """Mechanical parameters of the elements and their contacts (SI units).

    Attributes
    ----------
    density_kg_m3 : element density; mass m = rho * pi * r**2 (unit thickness).
    kn_n_m : normal spring stiffness Kn.
    ks_ratio : shear stiffness as a fraction of Kn (Ks = ks_ratio * Kn).
    friction : inter-element friction coefficient mu.
    cohesion_n : contact cohesion C0 in newtons (slider |Fs| <= C0 + mu * Fn). The default
        5e7 N is ~10% of mu * Fn at 1 km depth: brittle near the surface, frictional at depth;
        with C0 = 0 a 45 deg basement fault only makes a broad monocline (docs/dem.md).
    bond_strain : bond-breaking strain r0 (bond breaks when d - R > r0 * R).
    model : ``"frictional"`` (all bonds start broken) or ``"bonded"`` (bonds between initial
        neighbours).
    damping_scale : global viscous damping eta = dt * damping_scale (N s / m per second of dt).
        The paper's 3.0e9 makes the terminal sinking speed of the smallest element (m g / eta,
        ~1.4 m/s at Kn = 1e10) slower than the basement subsides, so the hanging wall detaches
        from its base; 3.0e8 (terminal speeds 14-57 m/s) keeps it in contact. See docs/dem.md.
    gravity_m_s2 : gravitational acceleration.
    """

    density_kg_m3: float = 2500.0
    kn_n_m: float = 1.0e10
    ks_ratio: float = 0.5
    friction: float = 0.4
    cohesion_n: float = 5.0e7
    bond_strain: float = 0.02
    model: str = "frictional"
    damping_scale: float = 3.0e8
    gravity_m_s2: float = 9.81


@dataclass(frozen=True)
class NormalFault:
    """Basement normal fault imposed by moving the hanging-wall base and side wall.

    Attributes
    ----------
    x_m : x where the basement fault meets the base of the model (y = 0).
    dip_deg : fault dip in degrees, 30-70 typical; the hanging wall is on the side the fault
        dips towards (``dip_direction``).
    throw_m : target vertical throw of the basement fault.
    dip_direction : ``"right"`` (hanging wall at larger x) or ``"left"``.
    speed_m_s : wall speed along dip; small enough to be quasi-static.
    """

    x_m: float = 2500.0
    dip_deg: float = 45.0
    throw_m: float = 450.0
    dip_direction: str = "right"
    speed_m_s: float = 5.0
