"""Parameters of the DEM: the element :class:`Material` and the basement :class:`NormalFault`.

The particle :class:`demseis.types.Snapshot` the DEM returns lives in :mod:`demseis.types`.

Coordinates: x to the right, y up, metres. The model box is ``0 <= x <= width_m`` and
``0 <= y <= height_m`` before faulting (y = 0 is the top of the basement).
"""

from __future__ import annotations

from dataclasses import dataclass

from demseis.parameters import MATERIAL_FIELDS, PARAMS


def _default(field: str) -> object:
    return PARAMS[MATERIAL_FIELDS.get(field, field)].default


@dataclass(frozen=True)
class Material:
    """Mechanical parameters of the elements and their contacts (SI units).

    Defaults and allowed ranges are declared once in :mod:`demseis.parameters` (``demseis
    params``); :func:`demseis.dem.integrator.validate_material` checks against them.

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
    model : ``"frictional"`` (all bonds start broken; every contact, new or old, carries C0:
        cohesion heals, so deformation stays distributed: the ductile end), ``"bonded"``
        (tensile bonds between initial neighbours) or ``"brittle"`` (bonds between initial
        neighbours that break in tension at r0 or in shear at C0 + mu Fn; C0 lives only on
        the bonds, new contacts are frictional: strain softening that localises slip).
    damping_scale : global viscous damping eta = dt * damping_scale (N s / m per second of dt).
        The paper's 3.0e9 makes the terminal sinking speed of the smallest element (m g / eta,
        ~1.4 m/s at Kn = 1e10) slower than the basement subsides, so the hanging wall detaches
        from its base; 3.0e8 (terminal speeds 14-57 m/s) keeps it in contact. See docs/dem.md.
    gravity_m_s2 : gravitational acceleration.
    """

    density_kg_m3: float = _default("density_kg_m3")
    kn_n_m: float = _default("kn_n_m")
    ks_ratio: float = _default("ks_ratio")
    friction: float = _default("friction")
    cohesion_n: float = _default("cohesion_n")
    bond_strain: float = _default("bond_strain")
    model: str = _default("model")
    damping_scale: float = _default("damping_scale")
    gravity_m_s2: float = _default("gravity_m_s2")


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
    dip_deg: float = _default("dip_deg")
    throw_m: float = _default("throw_m")
    dip_direction: str = _default("dip_direction")
    speed_m_s: float = _default("wall_speed_m_s")


#: A brittle cover, calibrated at seed scale (5 km x 2.77 km, 45 deg, 450 m throw): bonds
#: between touching neighbours that break in tension (r0 = 0.005) or shear (C0 = 1.4e9 N +
#: mu Fn), cohesion lost with them. The mid-depth horizon steps 299 m (0.66 of the throw)
#: within 100 m across a ~70 deg master fault (docs/dem.md). ``Material()`` is the ductile end.
BRITTLE = Material(model="brittle", cohesion_n=1.4e9, bond_strain=0.005)
