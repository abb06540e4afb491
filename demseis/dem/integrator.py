"""The DEM state and its stepping loop (a thin Python shell around :mod:`demseis.dem._kernels`).

:class:`Integrator` owns the arrays of one assembly (positions, velocities, forces, the Verlet list
with its pair history, walls), advances them with :func:`demseis.dem._kernels.run_steps`, grows
the neighbour-list capacity when needed, and turns an unstable state into a
:class:`demseis.errors.SimulationError` that names the cause.
"""

from __future__ import annotations

import math

import numpy as np

from demseis.dem import _kernels as K
from demseis.dem.types import Material
from demseis.errors import InputError, SimulationError
from demseis.parameters import MATERIAL_FIELDS, PARAMS


#: contact models (declared in demseis.parameters)
MODELS = PARAMS["contact_model"].choices


def time_step(radius_min_m: float, density_kg_m3: float, kn_n_m: float) -> float:
    """Stable time step of the paper's Eq. 5: dt = 0.25 sqrt(m_min / Kn).

    Parameters
    ----------
    radius_min_m : smallest element radius (m); m_min = rho pi r_min^2 (unit thickness).
    density_kg_m3 : element density (kg/m^3).
    kn_n_m : normal stiffness (N/m).

    Returns
    -------
    float
        Time step in seconds.
    """
    m_min = density_kg_m3 * math.pi * radius_min_m**2
    return 0.25 * math.sqrt(m_min / kn_n_m)


def validate_material(material: Material) -> None:
    """Raise :class:`InputError` naming the first out-of-range field of ``material``.

    The ranges are the stage domains of :mod:`demseis.parameters` (:meth:`demseis.parameters.Param.stage`): the
    physical domain the DEM integrates, wider than the config ranges (which are the stable,
    affordable part of it), so analytic tests can switch gravity or damping off and per-layer
    materials can be softer than a config's.
    """
    for field, name in MATERIAL_FIELDS.items():
        PARAMS[name].stage().check_value(getattr(material, field), f"Material.{field}",
                                         InputError)


class Integrator:
    """Mutable DEM state: elements, pair history, walls; advanced by :meth:`run`.

    Parameters
    ----------
    pos : (n, 2) float64 centres (m), copied.
    radius : (n,) float64 radii (m), copied.
    material : Material
    dt_s : time step (s); default from Eq. 5 with the smallest radius present.
    eta : damping coefficient per element (N s/m), scalar or (n,); default
        ``dt * material.damping_scale`` (the paper's global damping).
    friction, cohesion_n : override the material's contact friction / cohesion (e.g. a
        frictionless settling stage).
    wall_friction : wall friction coefficient (default: the contact friction).
    skin_m : Verlet skin (m); default 0.3 * r_min, and at least enough for intact bonds.
    capacity : initial Verlet-list row capacity (grown automatically).
    mass_kg : override the element masses (scalar or (n,)); used for mass-scaled settling.
    """

    def __init__(self, pos: np.ndarray, radius: np.ndarray, material: Material, *,
                 dt_s: float | None = None, eta: float | np.ndarray | None = None,
                 friction: float | None = None, cohesion_n: float | None = None,
                 wall_friction: float | None = None, skin_m: float | None = None,
                 capacity: int = 12, mass_kg: np.ndarray | None = None) -> None:
        validate_material(material)
        self.material = material
        self.pos = np.ascontiguousarray(pos, dtype=np.float64).copy()
        self.radius = np.ascontiguousarray(radius, dtype=np.float64).copy()
        n = self.radius.shape[0]
        if self.pos.shape != (n, 2):
            raise InputError(f"pos has shape {self.pos.shape}; expected ({n}, 2)")
        if n and not (np.all(np.isfinite(self.pos)) and np.all(self.radius > 0)):
            raise InputError("positions must be finite and radii > 0")
        rmin = float(self.radius.min()) if n else 1.0
        self.dt = float(dt_s) if dt_s is not None else time_step(
            rmin, material.density_kg_m3, material.kn_n_m)
        self.mass = material.density_kg_m3 * math.pi * self.radius**2
        if mass_kg is not None:
            self.mass = np.broadcast_to(np.asarray(mass_kg, np.float64), (n,)).copy()
        self.inv_mass = 1.0 / self.mass
        self._eta_default = eta
        self.eta = self._make_eta(eta, n)
        self.vel = np.zeros((n, 2))
        self.force = np.zeros((n, 2))
        self.kn = float(material.kn_n_m)
        self.ks = float(material.ks_ratio * material.kn_n_m)
        self.mu = float(material.friction if friction is None else friction)
        self.c0 = float(material.cohesion_n if cohesion_n is None else cohesion_n)
        self.r0 = float(material.bond_strain)
        self.ks_ratio = float(material.ks_ratio)
        # brittle model: cohesion only on the initial bonds (lost when they break)
        self.c0_heal = 0.0 if material.model == "brittle" else 1.0
        # (1, 4): uniform mechanics (one row for every element); (n, 4) once set per element
        self.cmat = self._material_row()[None, :].copy()
        self.wall_mu = float(self.mu if wall_friction is None else wall_friction)
        rmax = float(self.radius.max()) if n else 1.0
        self.skin = float(skin_m) if skin_m is not None else max(
            0.3 * rmin, 1.2 * material.bond_strain * 2 * rmax)
        self.capacity = int(capacity)
        self._alloc_lists(n)
        self.walls = np.zeros((0, 4))
        self.wall_vel = np.zeros((0, 2))
        self.wall_shear = np.zeros((n, 0))
        self._wall_cand = np.zeros((0, n), np.int32)
        self._wall_ncand = np.zeros(0, np.int32)
        self._wall_disp = np.zeros(1)
        self.box = np.array([-np.inf, np.inf, -np.inf, np.inf])
        self.vmax_limit = 500.0
        self.check_every = 50
        self.steps = 0
        self.n_rebuilds = 0
        self.n_broken = 0
        self._forces_valid = False

    # ------------------------------------------------------------------ set-up helpers
    def _material_row(self) -> np.ndarray:
        """[Kn, mu, C0, r0] of the integrator's material (with the constructor's overrides)."""
        return np.array([self.kn, self.mu, self.c0, self.r0])

    def set_element_material(self, cmat: np.ndarray) -> None:
        """Per-element contact material: (n, 4) [Kn (N/m), mu, C0 (N), r0]; a pair uses the
        smaller value of its two elements. Kn above the integrator's Kn needs a smaller dt."""
        cmat = np.ascontiguousarray(cmat, dtype=np.float64)
        if cmat.shape != (self.n, 4) or not np.all(np.isfinite(cmat)) or np.any(cmat[:, 0] <= 0):
            raise InputError(f"cmat must be a finite ({self.n}, 4) array with Kn > 0, got shape "
                             f"{cmat.shape}")
        if cmat[:, 0].max() > self.kn * (1 + 1e-12):
            raise InputError(f"per-element Kn up to {cmat[:, 0].max():.3g} N/m exceeds the "
                             f"integrator's Kn {self.kn:.3g} N/m that sets dt")
        self.cmat = cmat.copy()
        self._forces_valid = False

    def _make_eta(self, eta, n):
        if eta is None:
            return np.full(n, self.dt * self.material.damping_scale)
        arr = np.asarray(eta, dtype=np.float64)
        if arr.ndim == 0:
            return np.full(n, float(arr))
        return np.ascontiguousarray(arr).copy()

    def _alloc_lists(self, n: int) -> None:
        k = self.capacity
        self.nbr = np.zeros((n, k), np.int32)
        self.n_nbr = np.zeros(n, np.int32)
        self.shear = np.zeros((n, k))
        self.bond = np.zeros((n, k), np.uint8)
        self._new_nbr = np.zeros((n, k), np.int32)
        self._new_n = np.zeros(n, np.int32)
        self._new_shear = np.zeros((n, k))
        self._new_bond = np.zeros((n, k), np.uint8)
        self._cell_head = np.zeros(max(4 * n, 64), np.int64)
        self._cell_next = np.zeros(n, np.int64)
        self.pos_ref = np.full((n, 2), np.inf)

    def _grow_capacity(self) -> None:
        old = (self.nbr, self.n_nbr, self.shear, self.bond)
        n = self.n
        self.capacity *= 2
        ref = self.pos_ref.copy()
        self._alloc_lists(n)
        k = old[0].shape[1]
        self.nbr[:, :k] = old[0]
        self.n_nbr[:] = old[1]
        self.shear[:, :k] = old[2]
        self.bond[:, :k] = old[3]
        self.pos_ref[:] = ref

    @property
    def n(self) -> int:
        return int(self.radius.shape[0])

    def set_walls(self, walls: np.ndarray, wall_vel: np.ndarray | None = None) -> None:
        """Replace the walls: (nw, 4) segments [x0, y0, x1, y1] and (nw, 2) velocities."""
        walls = np.ascontiguousarray(walls, dtype=np.float64).reshape(-1, 4).copy()
        nw = walls.shape[0]
        if wall_vel is None:
            wall_vel = np.zeros((nw, 2))
        self.walls = walls
        self.wall_vel = np.ascontiguousarray(wall_vel, dtype=np.float64).reshape(nw, 2).copy()
        if self.wall_shear.shape != (self.n, nw):
            self.wall_shear = np.zeros((self.n, nw))
        self._wall_cand = np.zeros((nw, self.n), np.int32)
        self._wall_ncand = np.zeros(nw, np.int32)
        self._refresh_wall_candidates()
        self._forces_valid = False

    def _refresh_wall_candidates(self) -> None:
        if self.walls.shape[0]:
            K.build_wall_candidates(self.pos, self.radius, self.walls, self.skin,
                                    self._wall_cand, self._wall_ncand)
        self._wall_disp[0] = 0.0

    def rebuild(self) -> None:
        """Rebuild the Verlet list now (keeps pair history of pairs that stay listed)."""
        while True:
            st = K.build_neighbours(self.pos, self.radius, self.skin, self.nbr, self.n_nbr,
                                    self.shear, self.bond, self._new_nbr, self._new_n,
                                    self._new_shear, self._new_bond, self._cell_head,
                                    self._cell_next)
            if st == 0:
                break
            self._grow_capacity()
        self.pos_ref[:] = self.pos
        self._refresh_wall_candidates()
        self._forces_valid = False

    def bond_initial_contacts(self, tol_frac: float = 0.05, flag: int = 1) -> int:
        """Bond every listed pair with d < (r_i + r_j)(1 + tol_frac).

        ``flag`` 1: tensile bonds (the bonded model); 2: brittle bonds (the brittle model:
        broken in tension or in shear, and the cohesion goes with them).
        Returns the number of bonds made.
        """
        self.rebuild()
        nb = 0
        for i in range(self.n):
            m = self.n_nbr[i]
            if m == 0:
                continue
            js = self.nbr[i, :m]
            dxy = self.pos[js] - self.pos[i]
            d = np.sqrt(dxy[:, 0] * dxy[:, 0] + dxy[:, 1] * dxy[:, 1])  # not hypot: libm's varies
            ok = d < (self.radius[i] + self.radius[js]) * (1 + tol_frac)
            self.bond[i, :m] = ok * np.uint8(flag)
            nb += int(ok.sum())
        return nb

    def compute_forces(self) -> None:
        """Evaluate the forces of the current state into ``self.force`` (no history change
        beyond what one evaluation does)."""
        K.body_forces(self.vel, self.mass, self.eta, self.material.gravity_m_s2, self.force)
        K.pair_forces(self.pos, self.vel, self.radius, self.nbr, self.n_nbr, self.shear,
                      self.bond, self.cmat, self.ks_ratio, self.c0_heal, self.dt, self.force)
        if self.walls.shape[0]:
            K.wall_forces(self.pos, self.vel, self.radius, self.walls, self.wall_vel,
                          self.wall_shear, self.kn, self.ks, self.wall_mu, self.dt, self.force)
        self._forces_valid = True

    # ------------------------------------------------------------------ stepping
    def run(self, n_steps: int) -> None:
        """Advance ``n_steps`` steps; raise :class:`SimulationError` on instability."""
        if not self._forces_valid:
            if not np.all(np.isfinite(self.pos_ref)):
                self.rebuild()
            self.compute_forces()
        done = 0
        while done < n_steps:
            st, k, bad, nreb, nbrk = K.run_steps(
                n_steps - done, self.dt, self.pos, self.vel, self.force, self.radius,
                self.mass, self.inv_mass, self.eta, self.material.gravity_m_s2,
                self.cmat, self.ks_ratio, self.c0_heal, self.kn, self.ks, self.wall_mu,
                self.nbr, self.n_nbr, self.shear, self.bond, self.pos_ref, self.skin,
                self._new_nbr, self._new_n, self._new_shear, self._new_bond,
                self._cell_head, self._cell_next,
                self.walls, self.wall_vel, self.wall_shear, self.box,
                self.vmax_limit, self.check_every,
                self._wall_cand, self._wall_ncand, self._wall_disp)
            done += k
            self.steps += k
            self.n_rebuilds += nreb
            self.n_broken += nbrk
            if st == K.STATUS_OK:
                continue
            if st == K.STATUS_NBR_OVERFLOW:
                # the step's drift was applied but its forces were not: finish it by hand
                self._grow_capacity()
                self.rebuild()
                self.compute_forces()
                self.vel += 0.5 * self.dt * self.force * self.inv_mass[:, None]
                done += 1
                self.steps += 1
                continue
            self._raise(st, bad)

    def _raise(self, st: int, bad: int) -> None:
        t = self.steps * self.dt
        where = ""
        if bad >= 0:
            where = (f" (element {bad} at x={self.pos[bad, 0]:.1f} m, y={self.pos[bad, 1]:.1f} m,"
                     f" speed {float(np.hypot(*self.vel[bad])):.3g} m/s)")
        if st == K.STATUS_NAN:
            raise SimulationError(f"DEM went unstable: NaN/inf in the state at step {self.steps} "
                                  f"(t={t:.1f} s){where}; reduce dt or Kn")
        if st == K.STATUS_KE:
            raise SimulationError(
                f"DEM went unstable: kinetic-energy blow-up at step {self.steps} (t={t:.1f} s): "
                f"an element exceeded {self.vmax_limit:.3g} m/s{where}")
        if st == K.STATUS_BOX:
            b = self.box
            raise SimulationError(
                f"DEM went unstable: an element left the box x in [{b[0]:.0f}, {b[1]:.0f}] m, "
                f"y in [{b[2]:.0f}, {b[3]:.0f}] m at step {self.steps} (t={t:.1f} s){where}")
        raise SimulationError(f"DEM stopped with unknown status {st}")

    def kinetic_energy(self) -> float:
        """Total kinetic energy (J per metre of thickness)."""
        return float(0.5 * np.sum(self.mass * np.sum(self.vel**2, axis=1)))

    def settle(self, max_steps: int, *, chunk: int = 500, v_tol_m_s: float = 0.05,
               min_steps: int = 0) -> int:
        """Run until the rms speed drops below ``v_tol_m_s`` (or ``max_steps``).

        Returns the number of steps run.
        """
        done = 0
        while done < max_steps:
            k = min(chunk, max_steps - done)
            self.run(k)
            done += k
            if done >= min_steps and self.n:
                vrms = math.sqrt(float(np.mean(np.sum(self.vel**2, axis=1))))
                if vrms < v_tol_m_s:
                    break
        return done

    # ------------------------------------------------------------------ topology edits
    def add_elements(self, pos: np.ndarray, radius: np.ndarray) -> None:
        """Append elements at rest (pair history of existing elements is kept)."""
        pos = np.asarray(pos, dtype=np.float64).reshape(-1, 2)
        radius = np.asarray(radius, dtype=np.float64).reshape(-1)
        m = radius.shape[0]
        if m == 0:
            return
        n = self.n
        self.pos = np.ascontiguousarray(np.vstack([self.pos, pos]))
        self.radius = np.concatenate([self.radius, radius])
        mass = self.material.density_kg_m3 * math.pi * radius**2
        self.mass = np.concatenate([self.mass, mass])
        self.inv_mass = 1.0 / self.mass
        if self.cmat.shape[0] > 1:
            self.cmat = np.vstack([self.cmat, np.tile(self._material_row(), (m, 1))])
        if self._eta_default is None or np.ndim(self._eta_default) == 0:
            add_eta = self._make_eta(self._eta_default, m)
        else:
            add_eta = np.full(m, float(np.mean(self.eta)))
        self.eta = np.concatenate([self.eta, add_eta])
        self.vel = np.ascontiguousarray(np.vstack([self.vel, np.zeros((m, 2))]))
        self.force = np.zeros((n + m, 2))
        old = (self.nbr, self.n_nbr, self.shear, self.bond)
        self._alloc_lists(n + m)
        self.nbr[:n] = old[0]
        self.n_nbr[:n] = old[1]
        self.shear[:n] = old[2]
        self.bond[:n] = old[3]
        self.wall_shear = np.vstack([self.wall_shear, np.zeros((m, self.walls.shape[0]))])
        self._wall_cand = np.zeros((self.walls.shape[0], n + m), np.int32)
        self.rebuild()

    def remove_elements(self, keep: np.ndarray) -> None:
        """Drop the elements where ``keep`` is False (erosion); the others keep their order,
        state and pair history (pairs with a removed element are dropped)."""
        keep = np.asarray(keep, dtype=bool).reshape(-1)
        if keep.shape[0] != self.n:
            raise InputError(f"keep has {keep.shape[0]} entries; expected {self.n}")
        if keep.all():
            return
        new_index = np.cumsum(keep) - 1
        new_index[~keep] = -1
        old_nbr, old_n = self.nbr[keep], self.n_nbr[keep]
        old_shear, old_bond = self.shear[keep], self.bond[keep]
        cols = np.arange(self.capacity)[None, :]
        listed = cols < old_n[:, None]
        mapped = np.where(listed, new_index[old_nbr], -1)
        valid = mapped >= 0
        # stable compaction of every row: valid entries first, in their old order
        order = np.argsort(~valid, axis=1, kind="stable")
        for name in ("pos", "radius", "mass", "inv_mass", "eta", "vel", "force", "wall_shear"):
            setattr(self, name, np.ascontiguousarray(getattr(self, name)[keep]))
        if self.cmat.shape[0] > 1:
            self.cmat = np.ascontiguousarray(self.cmat[keep])
        m = int(keep.sum())
        self._alloc_lists(m)
        self.n_nbr[:] = valid.sum(axis=1)
        self.nbr[:] = np.take_along_axis(np.where(valid, mapped, 0), order, axis=1)
        self.shear[:] = np.take_along_axis(np.where(valid, old_shear, 0.0), order, axis=1)
        self.bond[:] = np.take_along_axis(np.where(valid, old_bond, 0), order, axis=1)
        self._wall_cand = np.zeros((self.walls.shape[0], m), np.int32)
        self.rebuild()
