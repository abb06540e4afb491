"""Basement boundary conditions as plain data: faults, the blocks between them, their motion.

A :class:`FaultSystem` is 1-5 :class:`BasementFault` s (none for ``structure="none"``) ordered
by their position ``x_m`` at the base of the model (y = 0). The faults cut the basement into ``n_faults + 1`` rigid blocks
(block 0 is left of the first fault). :func:`block_kinematics` turns the description into the
motion of every block; :func:`demseis.dem.simulate` turns that motion into moving walls.

Kinematics (all faults move together: each fault's slip is the same fraction of its total)
------------------------------------------------------------------------------------------
Let ``a = +1`` for a fault dipping right (its hanging wall is the block on its right) and
``a = -1`` for one dipping left, ``d`` its dip, ``s`` its slip along dip so far.

- ``normal``: the hanging-wall block moves down-dip relative to the footwall block, by
  ``s (a cos d, -sin d)``: extension, the section lengthens.
- ``reverse``: the hanging-wall block moves up-dip, by ``-s (a cos d, -sin d)``: contraction,
  the section shortens.
- ``listric``: the fault is a circular arc of radius ``radius_m`` through ``(x_m, 0)`` with dip
  ``d`` at the top, flattening with depth (centre ``(x_m + a R sin d, R cos d)``, on the
  hanging-wall side). The hanging-wall block is a rigid body that rotates about that centre
  (towards the fault: rollover), so its base follows the arc. Approximation: the whole
  hanging-wall block rotates rigidly; its far end therefore rises once it lies farther than
  ``R sin d`` from the fault (use an erosion surface or a large radius), and a listric fault
  must bound an end block (its hanging wall is block 0 or the last block), because a rotating
  block cannot carry a further fault. The slip of a listric fault is the arc length ``R θ``;
  its throw, the drop of the hanging-wall corner, is ``R (cos(d - θ) - cos d)``.

Relative velocities fix the blocks up to one common velocity. The **reference block** (at
rest) is the highest translating block at the end of the run (ties: the leftmost): no
translating basement block rises above its start, so a reverse fault lowers its footwall
instead of lifting its hanging wall out of the model. For one normal fault this is the
footwall: the fixed footwall base of the NormalFault boundary condition.

Structures (generators of fault lists): :func:`domino` (a synthetic set dipping one way),
:func:`graben`, :func:`horst`, :func:`half_graben` and :func:`draw_fault_system` (a random
structure for a sweep).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from demseis.dem import detmath

from demseis.errors import InputError
from demseis.parameters import MAX_BASEMENT_FAULTS, PARAMS

KINDS = PARAMS["fault_kind"].choices
STRUCTURES = PARAMS["structure"].choices
MAX_FAULTS = MAX_BASEMENT_FAULTS


@dataclass(frozen=True)
class BasementFault:
    """One basement fault.

    Attributes
    ----------
    x_m : x where the fault meets the top of the basement (y = 0) before faulting.
    dip_deg : dip at the top of the basement (10-80 degrees).
    throw_m : final vertical throw (m), the offset of the basement top across the fault.
    dip_direction : ``"right"`` (hanging wall at larger x) or ``"left"``.
    kind : ``"normal"``, ``"reverse"`` or ``"listric"`` (normal sense, curved).
    radius_m : radius of curvature of a listric fault (m); ignored otherwise.
    """

    x_m: float
    dip_deg: float = 45.0
    throw_m: float = 450.0
    dip_direction: str = "right"
    kind: str = "normal"
    radius_m: float = 5000.0

    @property
    def sign(self) -> int:
        """+1 if the hanging wall is on the right, -1 if on the left."""
        return 1 if self.dip_direction == "right" else -1

    @property
    def max_listric_throw_m(self) -> float:
        """Largest throw allowed on a listric fault: 80% of the depth of its arc's bottom."""
        return 0.8 * self.radius_m * (1.0 - math.cos(math.radians(self.dip_deg)))

    def slip_m(self, throw_m: float | None = None) -> float:
        """Slip along the fault (m) that gives ``throw_m`` (default: the final throw)."""
        t = self.throw_m if throw_m is None else throw_m
        d = math.radians(self.dip_deg)
        if self.kind == "listric":
            return self.radius_m * (d - math.acos(math.cos(d) + t / self.radius_m))
        return t / float(detmath.sin(d))

    def throw_at_slip(self, slip_m: float) -> float:
        """Vertical throw (m) after ``slip_m`` of slip along the fault."""
        d = math.radians(self.dip_deg)
        if self.kind == "listric":
            return self.radius_m * (math.cos(d - slip_m / self.radius_m) - math.cos(d))
        return slip_m * float(detmath.sin(d))


@dataclass(frozen=True)
class FaultSystem:
    """1-5 basement faults, left to right, moving together.

    Attributes
    ----------
    faults : the faults, strictly increasing ``x_m``; empty for ``structure="none"`` (a
        basement without faults: one block, at rest unless the base stretches).
    speed_m_s : slip rate of the fault with the largest total slip (the master); the others
        slip in proportion so that every fault reaches its throw at the end.
    structure : name of the structure that generated the list (a label, not used by the DEM).
    """

    faults: tuple[BasementFault, ...]
    speed_m_s: float = 5.0
    structure: str = "single"

    @property
    def master(self) -> int:
        """Index of the fault with the largest total slip (first of ties); -1 without faults."""
        if not self.faults:
            return -1
        slips = [f.slip_m() for f in self.faults]
        return int(np.argmax(slips))

    @property
    def master_slip_m(self) -> float:
        """Total slip of the master fault (m); 0 without faults."""
        return self.faults[self.master].slip_m() if self.faults else 0.0

    def mirrored(self, width_m: float) -> "FaultSystem":
        """The same system seen from behind (x -> width - x, directions swapped)."""
        flip = {"right": "left", "left": "right"}
        faults = tuple(BasementFault(width_m - f.x_m, f.dip_deg, f.throw_m, flip[f.dip_direction],
                                     f.kind, f.radius_m) for f in reversed(self.faults))
        return FaultSystem(faults, self.speed_m_s, self.structure)

    def throws_at(self, fraction: float) -> np.ndarray:
        """(n_faults,) throw of every fault when the run is ``fraction`` (0-1) done."""
        return np.array([f.throw_at_slip(fraction * f.slip_m()) for f in self.faults])


def check_fault_fields(where: str, f, width_m: float) -> None:
    """Raise :class:`InputError` for a bad ``x_m``, ``dip_deg``, ``throw_m`` or
    ``dip_direction`` of ``f`` (a BasementFault or NormalFault), naming it ``where.field``."""
    if not (0 < f.x_m < width_m):
        raise InputError(f"{where}.x_m={f.x_m} must lie inside (0, {width_m}) m")
    PARAMS["dip_deg"].check_value(f.dip_deg, f"{where}.dip_deg", InputError)
    if not (math.isfinite(f.throw_m) and f.throw_m >= 0):
        raise InputError(f"{where}.throw_m={f.throw_m} must be >= 0")
    PARAMS["dip_direction"].check_value(f.dip_direction, f"{where}.dip_direction", InputError)


def validate_system(system: FaultSystem, width_m: float, min_spacing_m: float = 0.0) -> None:
    """Raise :class:`InputError` naming the first bad field of ``system``."""
    faults = system.faults
    if system.structure == "none":
        if faults != ():
            raise InputError(f"FaultSystem.structure='none' has no faults, got {faults!r}")
    elif not isinstance(faults, tuple) or not (1 <= len(faults) <= MAX_FAULTS):
        raise InputError(f"FaultSystem.faults must be a tuple of 1-{MAX_FAULTS} BasementFault, "
                         f"got {faults!r}")
    if not (math.isfinite(system.speed_m_s) and 0 < system.speed_m_s <= 100):
        raise InputError(f"FaultSystem.speed_m_s={system.speed_m_s} is out of range (0, 100]")
    for i, f in enumerate(faults):
        where = f"FaultSystem.faults[{i}]"
        check_fault_fields(where, f, width_m)
        if f.kind not in KINDS:
            raise InputError(f"{where}.kind={f.kind!r}; allowed {', '.join(KINDS)}")
        if f.kind == "listric":
            if not (math.isfinite(f.radius_m) and f.radius_m > 0):
                raise InputError(f"{where}.radius_m={f.radius_m} must be > 0")
            if f.throw_m > f.max_listric_throw_m:
                raise InputError(
                    f"{where}.throw_m={f.throw_m} is too large for a listric fault of radius "
                    f"{f.radius_m} m and dip {f.dip_deg} deg (allowed <= "
                    f"{f.max_listric_throw_m:.1f} m, 80% of the arc's depth)")
            end = (i == len(faults) - 1) if f.dip_direction == "right" else (i == 0)
            if not end:
                raise InputError(f"{where}: a listric fault must bound an end block (its "
                                 "hanging wall must be the first or last block)")
        if i and not (f.x_m - faults[i - 1].x_m > min_spacing_m):
            raise InputError(f"{where}.x_m={f.x_m}: faults must be ordered by x with more "
                             f"than {min_spacing_m:g} m between them")


@dataclass(frozen=True)
class BlockMotion:
    """Motion of one basement block per metre of master slip.

    Attributes
    ----------
    x_left_m, x_right_m : extent of the block's top at y = 0 before faulting.
    velocity : (2,) translation per metre of master slip (of the block, or for a rotating
        block of its footwall, which carries the rotation centre).
    centre_m : (2,) rotation centre before faulting (rotating blocks only, else None).
    omega : rotation angle (rad, counter-clockwise positive) per metre of master slip.
    """

    x_left_m: float
    x_right_m: float
    velocity: tuple[float, float]
    centre_m: tuple[float, float] | None = None
    omega: float = 0.0

    @property
    def rotates(self) -> bool:
        return self.centre_m is not None

    def displace(self, points: np.ndarray, slip_m: float) -> np.ndarray:
        """Positions of ``points`` (k, 2) of this block after ``slip_m`` of master slip."""
        p = np.asarray(points, dtype=np.float64)
        shift = np.array([slip_m * self.velocity[0], slip_m * self.velocity[1]])
        if not self.rotates:
            return p + shift
        c = np.asarray(self.centre_m)
        th = self.omega * slip_m
        rot = np.array([[math.cos(th), -math.sin(th)], [math.sin(th), math.cos(th)]])
        return c + (p - c) @ rot.T + shift


def block_kinematics(system: FaultSystem, width_m: float) -> list[BlockMotion]:
    """Motion of every block of ``system`` (see the module docstring), block 0 first."""
    faults = system.faults
    master_slip = system.master_slip_m
    scale = [f.slip_m() / master_slip if master_slip > 0 else 0.0 for f in faults]
    n = len(faults)
    vel = [(0.0, 0.0)]
    rot: dict[int, tuple[tuple[float, float], float]] = {}
    for i, f in enumerate(faults):
        d = math.radians(f.dip_deg)
        cd, sd = float(detmath.cos(d)), float(detmath.sin(d))  # same bits on every CPU
        if f.kind == "listric":
            hw = i + 1 if f.sign > 0 else i
            centre = (f.x_m + f.sign * f.radius_m * sd, f.radius_m * cd)
            rot[hw] = (centre, f.sign * scale[i] / f.radius_m)
            vel.append(vel[-1])  # placeholder: a rotating block translates with its footwall
            continue
        k = 1.0 if f.kind == "normal" else -1.0
        # right block minus left block = k * scale * (cos d, -a sin d)
        vx, vy = vel[-1]
        vel.append((vx + k * scale[i] * cd, vy - k * f.sign * scale[i] * sd))
    # a rotating block translates with its footwall, the neighbour across its fault
    for b in rot:
        vel[b] = vel[1] if b == 0 else vel[b - 1]
    translating = [b for b in range(n + 1) if b not in rot]
    ref = max(translating, key=lambda b: (vel[b][1], -b))
    rx, ry = vel[ref]
    edges = [-math.inf] + [f.x_m for f in faults] + [math.inf]
    out = []
    for b in range(n + 1):
        v = (vel[b][0] - rx, vel[b][1] - ry)
        centre, omega = rot.get(b, (None, 0.0))
        out.append(BlockMotion(max(edges[b], 0.0), min(edges[b + 1], width_m), v, centre, omega))
    return out


# ---------------------------------------------------------------- structures (generators)

def single(x_m: float, dip_deg: float = 45.0, throw_m: float = 450.0,
           dip_direction: str = "right", kind: str = "normal",
           radius_m: float = 5000.0) -> FaultSystem:
    """One basement fault (``kind`` normal, reverse or listric)."""
    return FaultSystem((BasementFault(x_m, dip_deg, throw_m, dip_direction, kind, radius_m),),
                       structure="single")


def domino(n_faults: int, x_first_m: float, spacing_m: float, dip_deg: float = 45.0,
           throw_m: float = 200.0, dip_direction: str = "right",
           kind: str = "normal") -> FaultSystem:
    """A synthetic set: ``n_faults`` parallel faults ``spacing_m`` apart, all dipping one way.

    The blocks translate (they do not rotate), so the basement steps down (normal) or up
    (reverse) one throw per fault: a staircase of domino blocks without block rotation.
    """
    faults = tuple(BasementFault(x_first_m + k * spacing_m, dip_deg, throw_m, dip_direction, kind)
                   for k in range(n_faults))
    return FaultSystem(faults, structure="domino")


def graben(x_centre_m: float, width_m: float, dip_deg: float = 60.0, throw_m: float = 200.0,
           kind: str = "normal") -> FaultSystem:
    """Two faults dipping towards each other, ``width_m`` apart at the basement top: the block
    between them drops (normal) by ``throw_m`` relative to both shoulders."""
    h = 0.5 * width_m
    return FaultSystem((BasementFault(x_centre_m - h, dip_deg, throw_m, "right", kind),
                        BasementFault(x_centre_m + h, dip_deg, throw_m, "left", kind)),
                       structure="graben")


def horst(x_centre_m: float, width_m: float, dip_deg: float = 60.0, throw_m: float = 200.0,
          kind: str = "normal") -> FaultSystem:
    """Two faults dipping away from each other: the block between them stays high and both
    flanks drop (normal) by ``throw_m``."""
    h = 0.5 * width_m
    return FaultSystem((BasementFault(x_centre_m - h, dip_deg, throw_m, "left", kind),
                        BasementFault(x_centre_m + h, dip_deg, throw_m, "right", kind)),
                       structure="horst")


def half_graben(x_m: float, dip_deg: float = 55.0, throw_m: float = 300.0,
                dip_direction: str = "right", radius_m: float = 5000.0) -> FaultSystem:
    """One listric master fault whose hanging wall rotates towards it (rollover)."""
    return FaultSystem((BasementFault(x_m, dip_deg, throw_m, dip_direction, "listric",
                                      radius_m),), structure="half_graben")


def draw_fault_system(rng: np.random.Generator, width_m: float, *, structure: str,
                      n_faults: int = 1, kind: str = "normal", dip_deg: float = 55.0,
                      throw_m: float = 200.0, spacing_frac: float = 0.2,
                      listric_radius_m: float = 5000.0,
                      dip_direction: str | None = None) -> FaultSystem:
    """A fault system of the named ``structure``, placed at random across ``width_m``.

    Parameters
    ----------
    rng : the run's generator (position and direction draws).
    structure : one of :data:`STRUCTURES`.
    n_faults : faults of a ``domino`` set (1-5); ``single``/``half_graben`` use 1, graben and
        horst 2.
    kind : fault kind of ``single`` / ``domino`` / ``graben`` / ``horst`` (a half-graben is
        listric).
    dip_deg, throw_m : dip and throw of every fault (a listric throw is capped at its
        allowed maximum).
    spacing_frac : fault spacing (domino; shrunk so that the set spans at most 80% of the
        width) or block width (graben, horst; at most 70%) as a fraction of ``width_m``.
    listric_radius_m : radius of a listric fault.
    dip_direction : ``"right"``/``"left"``; None draws it.
    """
    if structure not in STRUCTURES:
        raise InputError(f"structure={structure!r}; allowed {', '.join(STRUCTURES)}")
    if structure == "none":
        return FaultSystem((), structure="none")
    direction = dip_direction or ("right" if rng.random() < 0.5 else "left")
    spacing = spacing_frac * width_m
    if structure == "domino":
        if not (1 <= n_faults <= MAX_FAULTS):
            raise InputError(f"n_faults={n_faults} is out of range (1-{MAX_FAULTS})")
        if n_faults > 1:  # the set spans at most 80% of the width
            spacing = min(spacing, 0.8 * width_m / (n_faults - 1))
        span = (n_faults - 1) * spacing
        x0 = rng.uniform(0.1 * width_m, 0.9 * width_m - span)
        system = domino(n_faults, x0, spacing, dip_deg, throw_m, direction, kind)
    elif structure in ("graben", "horst"):
        if spacing > 0.7 * width_m:
            raise InputError(f"a {structure} {spacing:.0f} m wide does not fit in "
                             f"{width_m:.0f} m (at most 70% of the width)")
        xc = rng.uniform(0.15 * width_m + 0.5 * spacing, 0.85 * width_m - 0.5 * spacing)
        make = graben if structure == "graben" else horst
        system = make(xc, spacing, dip_deg, throw_m, kind)
    else:
        x = rng.uniform(0.3 * width_m, 0.7 * width_m)
        k = "listric" if structure == "half_graben" else kind
        f = BasementFault(x, dip_deg, throw_m, direction, k, listric_radius_m)
        if k == "listric":
            f = BasementFault(x, dip_deg, min(throw_m, f.max_listric_throw_m), direction, k,
                              listric_radius_m)
        system = FaultSystem((f,), structure=structure)
    return system
