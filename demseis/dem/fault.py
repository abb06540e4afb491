"""Normal faulting of an assembly by moving its basement, with syn-tectonic sedimentation.

Geometry (dip towards +x; ``dip_direction="left"`` is run mirrored and mirrored back):

- fixed: the left wall ``x = 0``, the footwall base ``y = 0, x <= x_f`` and the footwall's
  fault face, the segment from ``(x_f, 0)`` down along the dip;
- moving down-dip at ``speed * (cos d, -sin d)``: the hanging-wall base (from the fault to the
  right edge) and the right wall, until the vertical throw reaches ``throw_m``.

Sedimentation: at 1/4 and 1/2 of each interval between snapshots, wherever the top surface
lies below the initial surface (``height_m``), new elements of that interval's growth layer fill
the accommodation. They are cut from the run's own dense settled packing (so a growth layer is
as dense as the pre-kinematic ones), get new ids and ``deposited=True``, and settle in place.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from demseis.dem import detmath
from demseis.dem.assembly import Assembly
from demseis.dem.engine import Engine, time_step, validate_material
from demseis.dem.types import Material, NormalFault
from demseis.types import Snapshot
from demseis.errors import InputError


def validate_fault(fault: NormalFault, width_m: float) -> None:
    """Raise :class:`InputError` naming the first bad field of ``fault``."""
    if not (0 < fault.x_m < width_m):
        raise InputError(f"NormalFault.x_m={fault.x_m} must lie inside (0, {width_m}) m")
    if not (10.0 <= fault.dip_deg <= 80.0):
        raise InputError(f"NormalFault.dip_deg={fault.dip_deg} is out of range (allowed 10-80)")
    if not (math.isfinite(fault.throw_m) and fault.throw_m >= 0):
        raise InputError(f"NormalFault.throw_m={fault.throw_m} must be >= 0")
    if fault.dip_direction not in ("right", "left"):
        raise InputError(f"NormalFault.dip_direction={fault.dip_direction!r}; allowed "
                         "'right' or 'left'")
    if not (math.isfinite(fault.speed_m_s) and 0 < fault.speed_m_s <= 100):
        raise InputError(f"NormalFault.speed_m_s={fault.speed_m_s} is out of range (0, 100]")


def surface_profile(xy: np.ndarray, radius: np.ndarray, x_edges: np.ndarray) -> np.ndarray:
    """Top surface elevation per column: max of (y + r) over elements centred in the column.

    Parameters
    ----------
    xy : (n, 2) float64; radius : (n,) float64; x_edges : (m + 1,) column edges (m).

    Returns
    -------
    (m,) float64 top elevation (m); -inf where a column holds no element.
    """
    col = np.searchsorted(x_edges, xy[:, 0], side="right") - 1
    ok = (col >= 0) & (col < x_edges.size - 1)
    top = np.full(x_edges.size - 1, -np.inf)
    np.maximum.at(top, col[ok], xy[ok, 1] + radius[ok])
    return top


def _deposit(eng: Engine, x_lo: float, x_hi: float, level_m: float, template_xy: np.ndarray,
             template_r: np.ndarray, template_w: float, template_h: float,
             rng: np.random.Generator) -> int:
    """Fill the space between the top surface and ``level_m`` over [x_lo, x_hi] with disks.

    The new disks are cut from a dense settled packing (``template_*``, the run's own initial
    pack, shifted by a random offset and repeated periodically in x): every template disk whose
    bottom clears the local surface (the highest disk top within one r_max either side) and
    whose centre lies below ``level_m`` is added. Starting dense matters: a loose deposit of
    cohesive disks can stay loose (columns held by cohesion). Returns the number added.
    """
    rmax = float(template_r.max())
    gap = 0.1 * float(template_r.min())
    ncol = max(int(np.ceil((x_hi - x_lo) / (0.5 * rmax))), 1)
    edges = np.linspace(x_lo, x_hi, ncol + 1)
    top = surface_profile(eng.pos, eng.radius, edges)
    finite = np.isfinite(top)
    if not finite.any():
        return 0
    top[~finite] = -np.inf
    # floor under a disk: the highest surface within +-r_max (3 columns of r_max/2 each side)
    floor = top.copy()
    for sft in range(1, 4):
        floor[sft:] = np.maximum(floor[sft:], top[:-sft])
        floor[:-sft] = np.maximum(floor[:-sft], top[sft:])
    floor[~np.isfinite(floor)] = np.min(top[finite])
    lowest = float(floor.min())
    if level_m - lowest < 2 * float(template_r.min()):
        return 0
    # template window: interior of the pack (away from its base and surface)
    depth = level_m - lowest + 2 * rmax
    y0 = max(0.5 * (template_h - depth), 2 * rmax)
    shift = rng.uniform(0.0, template_w)
    sel_y = (template_xy[:, 1] >= y0) & (template_xy[:, 1] < y0 + depth)
    txy = template_xy[sel_y]
    tr = template_r[sel_y]
    reps = int(np.ceil((x_hi - x_lo) / template_w)) + 1
    xs = []
    ys = []
    rs = []
    for k in range(reps):
        x = (txy[:, 0] + shift) % template_w + x_lo + k * template_w
        y = txy[:, 1] - y0 + lowest
        ok = (x - tr >= x_lo) & (x + tr <= x_hi) & (y <= level_m)
        xs.append(x[ok])
        ys.append(y[ok])
        rs.append(tr[ok])
    x = np.concatenate(xs)
    y = np.concatenate(ys)
    r = np.concatenate(rs)
    col = np.clip(((x - x_lo) / (edges[1] - edges[0])).astype(int), 0, ncol - 1)
    keep = y - r > floor[col] + gap
    if not keep.any():
        return 0
    # The column floor is a cut, not a guarantee: next to a scarp an existing disk whose centre
    # is up to r + r_max away sideways can still reach the new disk. An overlap of metres is a
    # force of ~1e11 N that blows the run up, so check every candidate against its neighbours.
    keep[keep] = _clear_of(eng.pos, eng.radius, np.c_[x[keep], y[keep]], r[keep], gap)
    if not keep.any():
        return 0
    eng.add_elements(np.c_[x[keep], y[keep]], r[keep])
    return int(keep.sum())


def _clear_of(pos: np.ndarray, radius: np.ndarray, new_xy: np.ndarray, new_r: np.ndarray,
              gap: float) -> np.ndarray:
    """(m,) bool: which new disks keep at least ``gap`` from every existing disk."""
    from scipy.spatial import cKDTree

    tree = cKDTree(pos)
    reach = new_r + float(radius.max()) + gap
    ok = np.ones(new_r.shape[0], dtype=bool)
    for i, near in enumerate(tree.query_ball_point(new_xy, reach)):
        if near:
            dxy = pos[near] - new_xy[i]
            d = np.sqrt(dxy[:, 0] * dxy[:, 0] + dxy[:, 1] * dxy[:, 1])
            ok[i] = bool(np.all(d >= radius[near] + new_r[i] + gap))
    return ok


def simulate(asm: Assembly, fault: NormalFault, material: Material = Material(), *,
             n_snapshots: int = 6, sedimentation: bool = True,
             rng: np.random.Generator | int | None = None,
             progress: Callable[[float], None] | None = None,
             settle_steps: int | None = None) -> list[Snapshot]:
    """Fault ``asm`` by moving the hanging-wall base and side wall down-dip.

    Parameters
    ----------
    asm : Assembly from :func:`demseis.dem.build_assembly`.
    fault : NormalFault (fault position, dip, throw, dip direction, wall speed).
    material : contact model and constants; ``model="bonded"`` bonds initial contacts.
    n_snapshots : >= 2; snapshot k is taken at throw k / (n_snapshots - 1) * fault.throw_m.
    sedimentation : fill hanging-wall accommodation with growth layers.
    rng : Generator or int seed (sediment radii/positions).
    progress : optional callable(fraction of the run done).
    settle_steps : steps of relaxation in the faulting walls before snapshot 0 (default
        enough for the contacts to load up: ~2 s of model time).

    Returns
    -------
    list of Snapshot, ``n_snapshots`` long.

    Raises
    ------
    demseis.errors.SimulationError
        NaN, kinetic-energy blow-up, or an element leaving the box.
    """
    validate_material(material)
    validate_fault(fault, asm.width_m)
    if not isinstance(n_snapshots, (int, np.integer)) or n_snapshots < 2:
        raise InputError(f"n_snapshots={n_snapshots!r} must be an integer >= 2")
    if rng is None:
        rng = np.random.default_rng(0)
    elif isinstance(rng, (int, np.integer)):
        rng = np.random.default_rng(int(rng))
    W, H = asm.width_m, asm.height_m
    mirror = fault.dip_direction == "left"
    xf = W - fault.x_m if mirror else fault.x_m
    xy0 = asm.xy.copy()
    if mirror:
        xy0[:, 0] = W - xy0[:, 0]
    dip = math.radians(fault.dip_deg)
    cd, sd = float(detmath.cos(dip)), float(detmath.sin(dip))  # same bits on every CPU
    rmin, rmax = asm.radius_min_m, asm.radius_max_m

    # dt from Eq. 5 with the smallest radius that can ever occur (sediment included)
    dt = time_step(min(rmin, float(asm.radius.min())), material.density_kg_m3,
                   material.kn_n_m)
    eng = Engine(xy0, asm.radius, material, dt_s=dt)

    dip_total = fault.throw_m / sd
    L = dip_total + 4 * rmax
    top = 3.0 * H + 10 * rmax
    walls = np.array([
        [0.0, 0.0, 0.0, top],                       # left wall (fixed)
        [-rmax, 0.0, xf, 0.0],                      # footwall base (fixed)
        [xf, 0.0, xf + L * cd, -L * sd],            # footwall fault face (fixed)
        [xf, 0.0, W + rmax, 0.0],                   # hanging-wall base (moves)
        [W, 0.0, W, top],                           # hanging-wall side wall (moves)
    ])
    eng.set_walls(walls)
    eng.box = np.array([-4 * rmax, W + dip_total * cd + 4 * rmax,
                        -fault.throw_m - 4 * rmax, top])
    eng.vmax_limit = max(100.0, 20 * fault.speed_m_s)
    if material.model == "bonded":
        eng.bond_initial_contacts()
    else:
        eng.rebuild()

    layer = asm.layer.astype(np.int16).copy()
    ids = asm.ids.astype(np.int64).copy()
    deposited = np.zeros(asm.n, dtype=bool)
    next_id = int(ids.max()) + 1 if ids.size else 0
    next_layer = asm.n_layers

    # relax in the fault walls, then take the reference
    if settle_steps is None:
        settle_steps = int(2.0 / eng.dt)
    n_interval = n_snapshots - 1
    steps_per_interval = max(int(math.ceil(dip_total / n_interval / (fault.speed_m_s * eng.dt))),
                             1) if fault.throw_m > 0 else 0
    total_steps = settle_steps + steps_per_interval * n_interval
    v_dip = dip_total / n_interval / (steps_per_interval * eng.dt) if steps_per_interval else 0.0
    done = 0

    def report():
        if progress is not None and total_steps > 0:
            progress(min(done / total_steps, 1.0))

    eng.run(settle_steps)
    done += settle_steps
    report()

    def snap(k: int, applied_dip: float) -> Snapshot:
        xy = eng.pos.copy()
        if mirror:
            xy[:, 0] = W - xy[:, 0]
        return Snapshot(index=k, step=eng.steps, throw_m=float(applied_dip * sd), ids=ids.copy(),
                        xy=xy, radius=eng.radius.copy(), layer=layer.copy(),
                        deposited=deposited.copy())

    snaps = [snap(0, 0.0)]
    moving = np.array([3, 4])
    applied = 0.0
    for k in range(1, n_snapshots):
        grew = False
        q = steps_per_interval // 4
        for part, nsteps in enumerate((q, q, steps_per_interval - 2 * q)):
            eng.wall_vel[:] = 0.0
            eng.wall_vel[moving] = (v_dip * cd, -v_dip * sd)
            eng.run(nsteps)
            done += nsteps
            applied += nsteps * eng.dt * v_dip
            report()
            if part < 2 and sedimentation:
                n_before = eng.n
                added = _deposit(eng, 0.0, W + applied * cd, H, xy0, asm.radius, W, H, rng)
                if added:
                    ids = np.concatenate([ids, np.arange(next_id, next_id + added)])
                    next_id += added
                    layer = np.concatenate([layer, np.full(added, next_layer, np.int16)])
                    deposited = np.concatenate([deposited, np.ones(added, bool)])
                    grew = True
                    assert eng.n == n_before + added
        if grew:
            next_layer += 1
        snaps.append(snap(k, applied))
    return snaps
