"""Numba kernels of the 2D DEM (hot loops only; validation lives in the Python wrappers).

Conventions shared by every kernel
----------------------------------
- ``pos``, ``vel``, ``force``: (n, 2) float64, metres, m/s, newtons (per metre of thickness).
- ``radius``: (n,) float64 metres; ``inv_mass``: (n,) float64 1/kg (0 freezes an element);
  ``mass``: (n,) float64 kg; ``eta``: (n,) float64 viscous damping coefficient N s/m.
- Neighbour (Verlet) list in ELL layout: ``nbr`` (n, K) int32 holds, in row ``i``, the partners
  ``j > i`` with ``|x_j - x_i| < r_i + r_j + skin`` at the last rebuild; ``n_nbr`` (n,) int32 the
  row lengths. Pair history lives beside it: ``shear`` (n, K) float64 accumulated tangential
  displacement X_s (m) and ``bond`` (n, K) uint8 (0 none, 1 intact tensile bond, 2 brittle
  bond: tensile, and broken also by shear).
- Walls are straight segments ``walls`` (nw, 4) float64 ``[x0, y0, x1, y1]`` moving with
  ``wall_vel`` (nw, 2) m/s; ``wall_shear`` (n, nw) float64 is the element-wall X_s history.

Force law (the paper's Eq. 1-4 with the slider correction of docs/physics.md)
-------------------------------------------------------------------------
With d the centre distance, R = r_i + r_j and n the unit vector from i to j:

- bonded pair (``bond`` 1 or 2): F_n = Kn (R - d) (repulsive > 0, attractive < 0) until
  d - R > r0 R, then the bond breaks for ever;
- other pairs: F_n = Kn (R - d) if d < R, else 0 and the history (X_s, flag) is reset;
- tangential: X_s += (v_j - v_i) . t dt,  F_s = -Ks X_s,  |F_s| <= C + mu max(F_n, 0)
  (Mohr-Coulomb slider: on slip, X_s is reset onto the cap). C = C0 on a flagged pair
  (``bond`` 1 or 2) and ``c0_heal * C0`` on an unflagged one. A brittle bond
  (``bond == 2``, the brittle model) also breaks for ever when its shear force reaches the
  cap (tension or shear, whichever first): strain softening.
- per-element material ``cmat`` (n, 4) = [Kn, mu, C0, r0]; a pair takes the smaller value of
  each (the weaker element controls the contact), Ks = ks_ratio * Kn.

Force on j: F_n n + F_s t; on i the opposite. Each element also feels -eta v and -m g y-hat.
Integration: velocity Verlet (kick-drift-kick), damping evaluated with the half-step velocity.
"""

from __future__ import annotations

import numpy as np
from numba import njit

STATUS_OK = 0
STATUS_NAN = 1
STATUS_KE = 2
STATUS_BOX = 3
STATUS_NBR_OVERFLOW = 4


@njit(cache=True)
def build_neighbours(pos, radius, skin, nbr, n_nbr, shear, bond, new_nbr, new_n, new_shear,
                     new_bond, cell_head, cell_next):
    """Rebuild the half Verlet list with a cell grid, carrying pair history over.

    Parameters
    ----------
    pos : (n, 2) float64 centres (m).
    radius : (n,) float64 radii (m).
    skin : float Verlet skin (m); pairs with d < r_i + r_j + skin are listed.
    nbr, n_nbr, shear, bond : the current list and its history (see module docstring).
    new_nbr, new_n, new_shear, new_bond : scratch arrays of the same shapes, overwritten.
    cell_head : (m,) int64 scratch, m >= number of cells; cell_next : (n,) int64 scratch.

    Returns
    -------
    int
        0 on success, 1 if a row would exceed the capacity K (nothing is then changed).
    Pair history (X_s, bond) of pairs that stay listed is copied; new pairs start at 0 and
    unbonded. The results are copied back into ``nbr``/``n_nbr``/``shear``/``bond``.
    """
    n = pos.shape[0]
    cap = nbr.shape[1]
    if n == 0:
        return 0
    rmax = 0.0
    xmin = pos[0, 0]
    xmax = pos[0, 0]
    ymin = pos[0, 1]
    ymax = pos[0, 1]
    for i in range(n):
        if radius[i] > rmax:
            rmax = radius[i]
        xmin = min(xmin, pos[i, 0])
        xmax = max(xmax, pos[i, 0])
        ymin = min(ymin, pos[i, 1])
        ymax = max(ymax, pos[i, 1])
    cs = 2.0 * rmax + skin
    ncx = int((xmax - xmin) / cs) + 1
    ncy = int((ymax - ymin) / cs) + 1
    # bound the grid size by the scratch (degenerate spreads would only slow, not break)
    while ncx * ncy > cell_head.shape[0]:
        cs *= 1.5
        ncx = int((xmax - xmin) / cs) + 1
        ncy = int((ymax - ymin) / cs) + 1
    for c in range(ncx * ncy):
        cell_head[c] = -1
    for i in range(n):
        cx = int((pos[i, 0] - xmin) / cs)
        cy = int((pos[i, 1] - ymin) / cs)
        c = cy * ncx + cx
        cell_next[i] = cell_head[c]
        cell_head[c] = i
    for i in range(n):
        new_n[i] = 0
    for i in range(n):
        xi = pos[i, 0]
        yi = pos[i, 1]
        ri = radius[i]
        cx = int((xi - xmin) / cs)
        cy = int((yi - ymin) / cs)
        for ddy in range(-1, 2):
            yy = cy + ddy
            if yy < 0 or yy >= ncy:
                continue
            for ddx in range(-1, 2):
                xx = cx + ddx
                if xx < 0 or xx >= ncx:
                    continue
                j = cell_head[yy * ncx + xx]
                while j >= 0:
                    if j > i:
                        dx = pos[j, 0] - xi
                        dy = pos[j, 1] - yi
                        cut = ri + radius[j] + skin
                        if dx * dx + dy * dy < cut * cut:
                            k = new_n[i]
                            if k >= cap:
                                return 1
                            new_nbr[i, k] = j
                            new_shear[i, k] = 0.0
                            new_bond[i, k] = 0
                            for q in range(n_nbr[i]):
                                if nbr[i, q] == j:
                                    new_shear[i, k] = shear[i, q]
                                    new_bond[i, k] = bond[i, q]
                                    break
                            new_n[i] = k + 1
                    j = cell_next[j]
    for i in range(n):
        m = new_n[i]
        n_nbr[i] = m
        for k in range(m):
            nbr[i, k] = new_nbr[i, k]
            shear[i, k] = new_shear[i, k]
            bond[i, k] = new_bond[i, k]
    return 0


@njit(cache=True, error_model="numpy")
def pair_forces(pos, vel, radius, nbr, n_nbr, shear, bond, cmat, ks_ratio, c0_heal, dt, force):
    """Add the pair (normal + tangential) forces to ``force`` and update the pair history.

    Parameters
    ----------
    pos, vel : (n, 2) float64 positions (m) and velocities (m/s).
    radius : (n,) float64 radii (m).
    nbr, n_nbr, shear, bond : Verlet list and history, updated in place (X_s, broken bonds).
        ``bond``: 0 none, 1 tensile bond, 2 brittle bond (see module doc).
    cmat : (n, 4) float64 per-element contact material [Kn (N/m), mu, C0 (N), r0]; a pair
        uses the smaller of its two elements' values. A (1, 4) array gives every element
        that row (uniform mechanics).
    ks_ratio : float Ks / Kn.
    c0_heal : float fraction of C0 that a contact without a bond (0) carries: 1 in the
        frictional and bonded models (every contact is cohesive), 0 in the brittle model
        (cohesion lives only on the initial bonds and is lost when they break).
    dt : float time step (s), for the X_s increment.
    force : (n, 2) float64, accumulated into (N).

    Returns
    -------
    int number of bonds broken in tension during this call.

    Notes
    -----
    One (1, 4) ``cmat`` runs a loop on that row's scalars, which reads no ``cmat`` per pair
    (``min(x, x) == x``: the forces are the same to the bit); ``c0_heal == 1`` runs a loop
    without the healed-cohesion select (see ``_make_pair_forces``).
    """
    a = (pos, vel, radius, nbr, n_nbr, shear, bond, cmat, ks_ratio, c0_heal, dt, force)
    if cmat.shape[0] > 1:
        return _pair_forces_layered_healed(*a) if c0_heal == 1.0 else _pair_forces_layered(*a)
    return _pair_forces_healed(*a) if c0_heal == 1.0 else _pair_forces_uniform(*a)


@njit(cache=True, inline="always")
def _slider(fs, xs, cap, ks):
    """Coulomb slider of a contact: the shear force ``fs`` clamped to ``[-cap, cap]`` and the
    shear displacement history ``xs``, reset at the cap to the elastic part ``-fs / ks``.
    Returns ``(fs, xs)``."""
    if fs > cap:
        return cap, -cap / ks
    if fs < -cap:
        return -cap, cap / ks
    return fs, xs


def _make_pair_forces(layered: bool, healed: bool = False):
    """The loop of :func:`pair_forces`, compiled with ``layered`` and ``healed`` constants.

    ``layered`` False reads ``cmat[0]`` once, not per pair: the closure constant lets Numba and
    LLVM drop the per-pair minima (a runtime flag cost about 10% of the DEM's time).
    ``healed`` True is for ``c0_heal == 1`` (every contact cohesive): the cap starts at C0
    without the select (``c0 * 1.0 == c0``: same bits; another 2-4%).
    """

    @njit(cache=True, error_model="numpy")
    def kernel(pos, vel, radius, nbr, n_nbr, shear, bond, cmat, ks_ratio, c0_heal, dt, force):
        n = pos.shape[0]
        nbroken = 0
        kn0 = cmat[0, 0]
        mu0 = cmat[0, 1]
        c00 = cmat[0, 2]
        r00 = cmat[0, 3]
        ks0 = ks_ratio * kn0
        for i in range(n):
            xi = pos[i, 0]
            yi = pos[i, 1]
            ri = radius[i]
            kni = cmat[i, 0] if layered else kn0
            mui = cmat[i, 1] if layered else mu0
            c0i = cmat[i, 2] if layered else c00
            r0i = cmat[i, 3] if layered else r00
            fxi = 0.0
            fyi = 0.0
            for k in range(n_nbr[i]):
                j = nbr[i, k]
                dx = pos[j, 0] - xi
                dy = pos[j, 1] - yi
                rr = ri + radius[j]
                d2 = dx * dx + dy * dy
                b = bond[i, k]
                if b != 0:
                    d = np.sqrt(d2)
                    r0 = min(r0i, cmat[j, 3]) if layered else r0i
                    if d - rr > r0 * rr:
                        bond[i, k] = 0
                        b = 0
                        nbroken += 1
                        if d >= rr:
                            shear[i, k] = 0.0
                            continue
                else:
                    if d2 >= rr * rr:
                        shear[i, k] = 0.0  # (the flag is 0 already)
                        continue
                    d = np.sqrt(d2)
                if layered:
                    kn = min(kni, cmat[j, 0])
                    mu = min(mui, cmat[j, 1])
                    c0 = min(c0i, cmat[j, 2])
                    ks = ks_ratio * kn
                else:
                    kn = kni
                    mu = mui
                    c0 = c0i
                    ks = ks0
                inv_d = 1.0 / d
                nx = dx * inv_d
                ny = dy * inv_d
                fn = kn * (rr - d)
                # tangent t = (-ny, nx); relative velocity of j w.r.t. i
                vt = (vel[j, 0] - vel[i, 0]) * (-ny) + (vel[j, 1] - vel[i, 1]) * nx
                xs = shear[i, k] + vt * dt
                fs = -ks * xs
                cap = c0 if (healed or b != 0) else c0 * c0_heal
                if fn > 0.0:
                    cap += mu * fn
                if b == 2 and (fs > cap or fs < -cap):
                    # a brittle bond that slips breaks for ever: cohesion and tension are lost
                    bond[i, k] = 0
                    cap = c0 * c0_heal
                    if fn > 0.0:
                        cap += mu * fn
                fs, xs = _slider(fs, xs, cap, ks)
                shear[i, k] = xs
                fx = fn * nx - fs * ny
                fy = fn * ny + fs * nx
                force[j, 0] += fx
                force[j, 1] += fy
                fxi -= fx
                fyi -= fy
            force[i, 0] += fxi
            force[i, 1] += fyi
        return nbroken

    return kernel


_pair_forces_uniform = _make_pair_forces(False)
_pair_forces_layered = _make_pair_forces(True)
_pair_forces_healed = _make_pair_forces(False, True)
_pair_forces_layered_healed = _make_pair_forces(True, True)


@njit(cache=True, inline="always")
def _segment_offset(px, py, ex, ey, l2):
    """Vector from the closest point of a segment to a point.

    The segment runs from the origin along (ex, ey) (squared length l2); (px, py) is the point
    relative to the segment start. The closest point is clamped to the segment, so its ends
    act as rounded corners. Returns (dx, dy) in metres.
    """
    s = (px * ex + py * ey) / l2
    if s < 0.0:
        s = 0.0
    elif s > 1.0:
        s = 1.0
    return px - s * ex, py - s * ey

@njit(cache=True, inline="always")
def _wall_segment(walls, w):
    """Wall ``w`` of ``walls`` (rows x0, y0, x1, y1) as its start (ax, ay), its vector
    (ex, ey) and its squared length l2."""
    ax = walls[w, 0]
    ay = walls[w, 1]
    ex = walls[w, 2] - ax
    ey = walls[w, 3] - ay
    return ax, ay, ex, ey, ex * ex + ey * ey


@njit(cache=True, inline="always")
def _wall_contact(i, w, ax, ay, ex, ey, l2, pos, vel, radius, wall_vel, wall_shear, kn, ks, mu,
                  dt, force):
    """Force of wall ``w`` (segment from (ax, ay) along (ex, ey), squared length l2) on element
    ``i``, accumulated into ``force``; updates the X_s history ``wall_shear[i, w]``."""
    dx, dy = _segment_offset(pos[i, 0] - ax, pos[i, 1] - ay, ex, ey, l2)
    d2 = dx * dx + dy * dy
    ri = radius[i]
    if d2 >= ri * ri or d2 == 0.0:
        wall_shear[i, w] = 0.0
        return
    d = np.sqrt(d2)
    nx = dx / d
    ny = dy / d
    fn = kn * (ri - d)
    vt = (vel[i, 0] - wall_vel[w, 0]) * (-ny) + (vel[i, 1] - wall_vel[w, 1]) * nx
    xs = wall_shear[i, w] + vt * dt
    fs = -ks * xs
    fs, xs = _slider(fs, xs, mu * fn, ks)
    wall_shear[i, w] = xs
    force[i, 0] += fn * nx - fs * ny
    force[i, 1] += fn * ny + fs * nx


@njit(cache=True)
def wall_forces(pos, vel, radius, walls, wall_vel, wall_shear, kn, ks, mu, dt, force):
    """Add disk-segment wall forces (normal spring + frictional slider, no cohesion).

    Parameters
    ----------
    pos, vel : (n, 2) float64; radius : (n,) float64.
    walls : (nw, 4) float64 segments [x0, y0, x1, y1] (m); wall_vel : (nw, 2) float64 (m/s).
    wall_shear : (n, nw) float64 element-wall X_s history (m), updated in place.
    kn, ks, mu, dt : stiffnesses (N/m), friction coefficient, time step (s).
    force : (n, 2) float64, accumulated into (N).

    Notes
    -----
    The contact point is the closest point of the segment to the centre, so segment ends act as
    rounded corners. Overlap = r - distance; the normal points from the wall to the element.
    """
    n = pos.shape[0]
    nw = walls.shape[0]
    for w in range(nw):
        ax, ay, ex, ey, l2 = _wall_segment(walls, w)
        for i in range(n):
            _wall_contact(i, w, ax, ay, ex, ey, l2, pos, vel, radius, wall_vel, wall_shear, kn, ks,
                          mu, dt, force)

@njit(cache=True)
def build_wall_candidates(pos, radius, walls, skin, cand, n_cand):
    """List, per wall, the elements whose disk is within ``skin`` of the segment.

    pos : (n, 2) float64; radius : (n,) float64; walls : (nw, 4) float64; skin : float (m).
    cand : (nw, n) int32 output element indices; n_cand : (nw,) int32 output counts.
    """
    n = pos.shape[0]
    for w in range(walls.shape[0]):
        ax, ay, ex, ey, l2 = _wall_segment(walls, w)
        m = 0
        for i in range(n):
            dx, dy = _segment_offset(pos[i, 0] - ax, pos[i, 1] - ay, ex, ey, l2)
            cut = radius[i] + skin
            if dx * dx + dy * dy < cut * cut:
                cand[w, m] = i
                m += 1
        n_cand[w] = m


@njit(cache=True)
def wall_forces_listed(pos, vel, radius, walls, wall_vel, wall_shear, kn, ks, mu, dt, force,
                       cand, n_cand):
    """:func:`wall_forces` restricted to the candidates of :func:`build_wall_candidates`.

    Elements off a wall's list are farther than the skin from it, so they feel no force and
    their X_s with it is already 0 (reset when they left contact).
    """
    for w in range(walls.shape[0]):
        ax, ay, ex, ey, l2 = _wall_segment(walls, w)
        for q in range(n_cand[w]):
            i = cand[w, q]
            _wall_contact(i, w, ax, ay, ex, ey, l2, pos, vel, radius, wall_vel, wall_shear, kn, ks,
                          mu, dt, force)

@njit(cache=True)
def body_forces(vel, mass, eta, gravity, force):
    """Set ``force`` to gravity plus global viscous damping: F = -eta v - m g y-hat.

    vel : (n, 2) float64 m/s; mass, eta : (n,) float64 kg, N s/m; gravity : float m/s^2;
    force : (n, 2) float64 overwritten (N).
    """
    for i in range(vel.shape[0]):
        force[i, 0] = -eta[i] * vel[i, 0]
        force[i, 1] = -eta[i] * vel[i, 1] - mass[i] * gravity


@njit(cache=True)
def run_steps(n_steps, dt, pos, vel, force, radius, mass, inv_mass, eta, gravity,
              cmat, ks_ratio, c0_heal, wall_kn, wall_ks, wall_mu,
              nbr, n_nbr, shear, bond, pos_ref, skin,
              new_nbr, new_n, new_shear, new_bond, cell_head, cell_next,
              walls, wall_vel, wall_shear, box, vmax_limit, check_every,
              cand, n_cand, wall_disp):
    """Advance the assembly ``n_steps`` velocity-Verlet steps.

    Parameters
    ----------
    n_steps : int; dt : float time step (s).
    pos, vel, force : (n, 2) float64 state, updated in place. ``force`` must hold the forces
        of the current positions on entry (call
        :meth:`demseis.dem.integrator.Integrator.compute_forces` once first).
    radius, mass, inv_mass, eta : (n,) float64.
    gravity : float (m/s^2); cmat, ks_ratio, c0_heal : contact material (see pair_forces).
    wall_kn, wall_ks, wall_mu : float wall stiffnesses (N/m) and friction coefficient.
    nbr ... cell_next : Verlet list, its history, its rebuild scratch (see build_neighbours).
    pos_ref : (n, 2) float64 positions at the last rebuild; skin : float (m). The list is
        rebuilt when an element has moved more than skin/2 since then.
    walls, wall_vel, wall_shear : moving segment walls (walls are advanced by wall_vel dt).
    cand, n_cand : per-wall candidate lists (see build_wall_candidates), rebuilt with the
        Verlet list; wall_disp : (1,) float64 distance the fastest wall moved since the last
        rebuild. A rebuild happens when an element moved > skin/2 or a wall moved > skin/2,
        so element-wall contacts cannot be missed.
    box : (4,) float64 [xmin, xmax, ymin, ymax]; an element centre outside stops the run.
    vmax_limit : float (m/s); a speed above it is reported as a kinetic-energy blow-up.
    check_every : int steps between the NaN / speed / box checks.

    Returns
    -------
    status : int  (STATUS_OK, STATUS_NAN, STATUS_KE, STATUS_BOX, STATUS_NBR_OVERFLOW)
    steps_done : int
    bad : int  index of the offending element (-1 if none)
    n_rebuilds : int
    n_broken : int  bonds broken
    """
    n = pos.shape[0]
    nw = walls.shape[0]
    half = 0.5 * dt
    lim2 = 0.25 * skin * skin
    vw = 0.0
    for w in range(nw):
        vw = max(vw, np.sqrt(wall_vel[w, 0] ** 2 + wall_vel[w, 1] ** 2))
    n_rebuilds = 0
    n_broken = 0
    for step in range(n_steps):
        maxd2 = 0.0
        for i in range(n):
            vel[i, 0] += half * force[i, 0] * inv_mass[i]
            vel[i, 1] += half * force[i, 1] * inv_mass[i]
            pos[i, 0] += dt * vel[i, 0]
            pos[i, 1] += dt * vel[i, 1]
            ddx = pos[i, 0] - pos_ref[i, 0]
            ddy = pos[i, 1] - pos_ref[i, 1]
            dd = ddx * ddx + ddy * ddy
            if dd > maxd2:
                maxd2 = dd
        for w in range(nw):
            walls[w, 0] += dt * wall_vel[w, 0]
            walls[w, 1] += dt * wall_vel[w, 1]
            walls[w, 2] += dt * wall_vel[w, 0]
            walls[w, 3] += dt * wall_vel[w, 1]
        wall_disp[0] += vw * dt
        if maxd2 > lim2 or wall_disp[0] > 0.5 * skin:
            if not (maxd2 < 1e300):
                return STATUS_NAN, step, _first_bad(pos, vel), n_rebuilds, n_broken
            st = build_neighbours(pos, radius, skin, nbr, n_nbr, shear, bond, new_nbr, new_n,
                                  new_shear, new_bond, cell_head, cell_next)
            if st != 0:
                return STATUS_NBR_OVERFLOW, step, -1, n_rebuilds, n_broken
            for i in range(n):
                pos_ref[i, 0] = pos[i, 0]
                pos_ref[i, 1] = pos[i, 1]
            if nw > 0:
                build_wall_candidates(pos, radius, walls, skin, cand, n_cand)
            wall_disp[0] = 0.0
            n_rebuilds += 1
        body_forces(vel, mass, eta, gravity, force)
        n_broken += pair_forces(pos, vel, radius, nbr, n_nbr, shear, bond, cmat, ks_ratio,
                                c0_heal, dt, force)
        if nw > 0:
            wall_forces_listed(pos, vel, radius, walls, wall_vel, wall_shear, wall_kn, wall_ks,
                               wall_mu, dt, force, cand, n_cand)
        for i in range(n):
            vel[i, 0] += half * force[i, 0] * inv_mass[i]
            vel[i, 1] += half * force[i, 1] * inv_mass[i]
        if (step + 1) % check_every == 0 or step == n_steps - 1:
            st, bad = check_state(pos, vel, box, vmax_limit)
            if st != STATUS_OK:
                return st, step + 1, bad, n_rebuilds, n_broken
    return STATUS_OK, n_steps, -1, n_rebuilds, n_broken


@njit(cache=True)
def _first_bad(pos, vel):
    for i in range(pos.shape[0]):
        s = pos[i, 0] + pos[i, 1] + vel[i, 0] + vel[i, 1]
        if not (abs(s) < 1e300):
            return i
    return -1


@njit(cache=True)
def check_state(pos, vel, box, vmax_limit):
    """Stability check: NaN/inf, speed above ``vmax_limit`` (m/s), centre outside ``box``.

    Returns (status, index of the first offending element or -1).
    """
    v2lim = vmax_limit * vmax_limit
    for i in range(pos.shape[0]):
        x = pos[i, 0]
        y = pos[i, 1]
        v2 = vel[i, 0] * vel[i, 0] + vel[i, 1] * vel[i, 1]
        if not (abs(x) + abs(y) + v2 < 1e300):
            return STATUS_NAN, i
        if v2 > v2lim:
            return STATUS_KE, i
        if x < box[0] or x > box[1] or y < box[2] or y > box[3]:
            return STATUS_BOX, i
    return STATUS_OK, -1
