"""Faulting of an assembly by moving its basement blocks, with syn-tectonic sedimentation.

The basement is described by a :class:`demseis.dem.basement.FaultSystem` (a
:class:`NormalFault` is the one-fault case). Its blocks become walls that move with them:

- the left wall ``x = 0`` moves with block 0, the right wall ``x = width`` with the last block;
- every block's top (``y = 0`` between its faults; the outer ends reach ``r_max`` past the
  side walls) moves with the block;
- every fault has a face along its plane from ``(x_f, 0)`` downwards, one slip plus
  ``4 r_max`` long: a normal or listric fault's face belongs to its footwall (it is exposed as
  the hanging wall drops), a reverse fault's to its hanging wall (it overhangs the footwall).
  A listric face is a polyline of chords of its arc (< 2 degrees each).

For one normal fault dipping right this is the classic set-up: fixed left wall, footwall base
and fault face; the hanging-wall base and right wall moving down-dip at
``speed * (cos d, -sin d)``. A system whose faults all dip left is run mirrored and mirrored
back (so a left-dipping fault gives exactly the mirror of a right-dipping one).

A stretching base (``base_stretch`` e, a fraction of the width W): every block's top is cut
into pieces of at most ``4 r_max`` whose ends move horizontally by ``e x0 f`` (x0 the base point
each end started on, f the fraction of the run done): a rubber sheet fixed at x = 0 whose right
end, and the right wall, move by ``e W``. Side walls and fault faces translate with the base
point they stand on, on top of their block's motion. The pieces are re-placed on the exact
stretch every 50 steps and translate with their mean velocity in between; friction on them
drags the cover, which breaks into a fault population (``structure="none"``: no basement
fault at all). The run lasts the longer of the master slip and ``|e| W`` at ``speed_m_s``.

Sedimentation: at 1/4 and 1/2 of each interval between snapshots, wherever the top surface
lies below the initial surface (``height_m``), new elements of that interval's growth layer fill
the accommodation. They are cut from the run's own dense settled packing (so a growth layer is
as dense as the pre-kinematic ones), get new ids and ``deposited=True``, and settle in place.
Cut disks keep the packing's contact overlaps; ``relax_deposits=True`` shrinks them first until
no two of them overlap (:func:`_unoverlapped`).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Sequence

import numpy as np

from demseis.dem import detmath
from demseis.dem.assembly import Assembly
from demseis.dem.basement import (BasementFault, BlockMotion, FaultSystem, block_kinematics,
                                  check_fault_fields, validate_system)
from demseis.dem.integrator import Integrator, time_step, validate_material
from demseis.dem.types import Material, NormalFault
from demseis.types import Snapshot
from demseis.errors import InputError
from demseis.parameters import PARAMS


def validate_fault(fault: NormalFault, width_m: float) -> None:
    """Raise :class:`InputError` naming the first bad field of ``fault``."""
    check_fault_fields("NormalFault", fault, width_m)
    PARAMS["wall_speed_m_s"].check_value(fault.speed_m_s, "NormalFault.speed_m_s", InputError)


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


def _deposit(eng: Integrator, x_lo: float, x_hi: float, level_m: float, template_xy: np.ndarray,
             template_r: np.ndarray, template_w: float, template_h: float,
             rng: np.random.Generator, relax: bool = False) -> int:
    """Fill the space between the top surface and ``level_m`` over [x_lo, x_hi] with disks.

    The new disks are cut from a dense settled packing (``template_*``, the run's own initial
    pack, shifted by a random offset and repeated periodically in x): every template disk whose
    bottom clears the local surface (the highest disk top within one r_max either side) and
    whose centre lies below ``level_m`` is added. Starting dense matters: a loose deposit of
    cohesive disks can stay loose (columns held by cohesion). Returns the number added.

    ``relax``: the cut template disks keep the settled pack's contact overlaps (lithostatic,
    up to metres across the periodic seam); with ``relax`` they are shrunk until no two new
    disks overlap (:func:`_unoverlapped`) before they are checked against the existing ones.
    """
    rmax = float(template_r.max())
    rmin = float(template_r.min())
    gap = 0.1 * rmin
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
    if level_m - lowest < 2 * rmin:
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
    if relax:
        r = r.copy()
        r[keep], kept = _unoverlapped(np.c_[x[keep], y[keep]], r[keep], rmin)
        keep[keep] = kept
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


def _unoverlapped(xy: np.ndarray, r: np.ndarray, r_min: float) -> tuple[np.ndarray, np.ndarray]:
    """Radii at which no two of the disks ``xy, r`` overlap, and which disks to keep.

    Every overlapping pair gives each of its disks half the overlap to lose, and a disk loses the
    largest half it is given: then for any pair r_i' + r_j' <= r_i + r_j - overlap_ij = d_ij.
    A disk that would fall below ``r_min`` (the grain distribution's smallest, which sets the
    time step) is dropped instead; dropping only removes overlaps.

    Returns
    -------
    (m,) float64 radii; (m,) bool kept.
    """
    # lazy: see _clear_of
    from scipy.spatial import cKDTree

    if r.size < 2:
        return r.copy(), np.ones(r.size, dtype=bool)
    pairs = cKDTree(xy).query_pairs(2.0 * float(r.max()), output_type="ndarray")
    loss = np.zeros(r.size)
    if pairs.size:
        i, j = pairs[:, 0], pairs[:, 1]
        dxy = xy[i] - xy[j]
        half = 0.5 * (r[i] + r[j] - np.sqrt(dxy[:, 0] * dxy[:, 0] + dxy[:, 1] * dxy[:, 1]))
        np.maximum.at(loss, i, half)
        np.maximum.at(loss, j, half)
    out = r - loss
    return out, out >= r_min


def _clear_of(pos: np.ndarray, radius: np.ndarray, new_xy: np.ndarray, new_r: np.ndarray,
              gap: float) -> np.ndarray:
    """(m,) bool: which new disks keep at least ``gap`` from every existing disk."""
    # lazy: scipy.spatial takes ~0.3 s to import and only deposition during a run needs it;
    # `import demseis.dem` loads no scipy submodule
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


def as_system(fault: NormalFault | FaultSystem) -> FaultSystem:
    """The :class:`FaultSystem` of ``fault`` (a NormalFault is one normal fault)."""
    if isinstance(fault, FaultSystem):
        return fault
    if isinstance(fault, NormalFault):
        return FaultSystem((BasementFault(fault.x_m, fault.dip_deg, fault.throw_m,
                                          fault.dip_direction, "normal"),),
                           speed_m_s=fault.speed_m_s, structure="single")
    raise InputError(f"fault must be a NormalFault or a FaultSystem, got {type(fault).__name__}")


def _split(p0: np.ndarray, p1: np.ndarray, max_len: float) -> list[np.ndarray]:
    """Segments [x0, y0, x1, y1] that cut p0 -> p1 into pieces no longer than max_len."""
    k = max(int(math.ceil(math.sqrt(float((p1 - p0) @ (p1 - p0))) / max_len)), 1)
    pts = p0 + (p1 - p0) * np.linspace(0.0, 1.0, k + 1)[:, None]
    return [np.r_[pts[j], pts[j + 1]] for j in range(k)]


def basement_walls(system: FaultSystem, motions: list[BlockMotion], width_m: float,
                   height_m: float, rmax: float,
                   base_piece_m: float | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Walls of the basement blocks before faulting, the block each belongs to, and the x whose
    base stretch each follows.

    Order: left wall, then per block its top and the face of the fault on its right, then the
    right wall. Walls of a rotating block are cut into pieces of at most
    ``max(4 r_max, min(width, height) / 8)`` (each piece translates between wall updates).
    With ``base_piece_m`` (a stretching base) every block top is cut into pieces of at most
    that length, whose ends follow the stretch of the base (:func:`stretch_shift`).

    Returns
    -------
    walls : (nw, 4) float64 [x0, y0, x1, y1]; owner : (nw,) int64 block index;
    anchor : (nw,) float64: a block top's pieces NaN (each end stretches with the base point
    it starts on), every other wall the x of the base point it translates with (0 the left
    wall, ``width_m`` the right one, ``x_m`` the face of a fault).
    """
    top = 3.0 * height_m + 10 * rmax
    piece = max(4 * rmax, min(width_m, height_m) / 8)
    walls: list[np.ndarray] = []
    owner: list[int] = []
    anchor: list[float] = []

    def add(b: int, seg: np.ndarray, at: float) -> None:
        cut = piece if motions[b].rotates else None
        if math.isnan(at) and base_piece_m is not None:
            cut = base_piece_m if cut is None else min(cut, base_piece_m)
        for s in (_split(seg[:2], seg[2:], cut) if cut is not None else [seg]):
            walls.append(s)
            owner.append(b)
            anchor.append(at)

    last = len(motions) - 1
    if motions[0].rotates:  # split the lower side wall finely, the rest in one piece
        add(0, np.array([0.0, 0.0, 0.0, 1.5 * height_m]), 0.0)
        walls.append(np.array([0.0, 1.5 * height_m, 0.0, top]))
        owner.append(0)
        anchor.append(0.0)
    else:
        add(0, np.array([0.0, 0.0, 0.0, top]), 0.0)
    for b, m in enumerate(motions):
        x0 = -rmax if b == 0 else m.x_left_m
        x1 = width_m + rmax if b == last else m.x_right_m
        add(b, np.array([x0, 0.0, x1, 0.0]), math.nan)
        if b == last:
            break
        f = system.faults[b]
        d = math.radians(f.dip_deg)
        cd, sd = float(detmath.cos(d)), float(detmath.sin(d))  # same bits on every CPU
        a = f.sign
        xf = f.x_m
        if f.kind == "listric":
            fw = b if a > 0 else b + 1
            th_end = min(f.slip_m() / f.radius_m + 4 * rmax / f.radius_m, d)
            k = max(int(math.ceil(math.degrees(th_end) / 2.0)), 1)
            phi = d - np.linspace(0.0, th_end, k + 1)
            cx, cy = xf + a * f.radius_m * sd, f.radius_m * cd
            px = cx - a * f.radius_m * np.sin(phi)
            py = cy - f.radius_m * np.cos(phi)
            px[0], py[0] = xf, 0.0
            for j in range(k):
                walls.append(np.array([px[j], py[j], px[j + 1], py[j + 1]]))
                owner.append(fw)
                anchor.append(xf)
            continue
        L = f.slip_m() + 4 * rmax
        hw, fw = (b + 1, b) if a > 0 else (b, b + 1)
        add(fw if f.kind == "normal" else hw, np.array([xf, 0.0, xf + a * L * cd, -L * sd]), xf)
    if motions[last].rotates:
        add(last, np.array([width_m, 0.0, width_m, 1.5 * height_m]), width_m)
        walls.append(np.array([width_m, 1.5 * height_m, width_m, top]))
        owner.append(last)
        anchor.append(width_m)
    else:
        add(last, np.array([width_m, 0.0, width_m, top]), width_m)
    return np.array(walls), np.array(owner, dtype=np.int64), np.array(anchor)


def stretch_shift(x0_m: np.ndarray, width_m: float, end_shift_m: float) -> np.ndarray:
    """Horizontal displacement of base points that started at ``x0_m`` when the base's right
    end (``x = width_m``) has moved ``end_shift_m`` and its left end (``x = 0``) is fixed.

    The base stretches uniformly (a rubber sheet): ``u(x0) = end_shift * x0 / width``, clipped
    to [0, end_shift] outside the model (the basement reaches ``r_max`` past the side walls).
    A point's velocity is therefore linear in its present x as well:
    ``v(x) = v_end * x / (width + end_shift)``.
    """
    x = np.asarray(x0_m, dtype=np.float64)
    return end_shift_m * np.clip(x / width_m, 0.0, 1.0)


def wall_ends(wall0: np.ndarray, motion: BlockMotion, anchor_x: float, width_m: float,
              slip_m: float, end_shift_m: float) -> np.ndarray:
    """(2, 2) ends of a basement wall (``wall0`` [x0, y0, x1, y1] before faulting, its block's
    ``motion``, its ``anchor_x`` from :func:`basement_walls`) after ``slip_m`` of master slip
    and ``end_shift_m`` of base stretch: the block's displacement plus the stretch of the base
    points the ends started on (a block top's piece) or of its anchor (any other wall)."""
    ends = np.asarray(wall0, dtype=np.float64).reshape(2, 2)
    p = motion.displace(ends, slip_m)
    if end_shift_m != 0.0:
        x0 = ends[:, 0] if math.isnan(anchor_x) else np.full(2, anchor_x)
        p[:, 0] += stretch_shift(x0, width_m, end_shift_m)
    return p


def validate_stretch(base_stretch: float) -> None:
    """Raise :class:`InputError` unless ``base_stretch`` is a finite fraction in the declared
    range of ``base_stretch``."""
    PARAMS["base_stretch"].check_value(base_stretch, "base_stretch", InputError)


def _layer_cmat(asm: Assembly, layer_materials: Sequence[Material]) -> tuple[np.ndarray, float]:
    """(n, 4) per-element [Kn, mu, C0, r0] from one Material per layer, and the largest Kn."""
    if len(layer_materials) != asm.n_layers:
        raise InputError(f"layer_materials has {len(layer_materials)} entries; expected one per "
                         f"layer ({asm.n_layers})")
    rows = np.empty((asm.n_layers, 4))
    for k, m in enumerate(layer_materials):
        if not isinstance(m, Material):
            raise InputError(f"layer_materials[{k}] must be a Material, got {type(m).__name__}")
        validate_material(m)
        rows[k] = (m.kn_n_m, m.friction, m.cohesion_n, m.bond_strain)
    return rows[asm.layer], float(rows[:, 0].max())


def simulate(asm: Assembly, fault: NormalFault | FaultSystem, material: Material = Material(),
             *, n_snapshots: int = 6, sedimentation: bool = True,
             rng: np.random.Generator | int | None = None,
             progress: Callable[[float], None] | None = None,
             settle_steps: int | None = None,
             erosion_level_m: float | None = None,
             layer_materials: Sequence[Material] | None = None,
             base_stretch: float = 0.0, relax_deposits: bool = False) -> list[Snapshot]:
    """Fault ``asm`` by moving its basement blocks (see the module docstring).

    Parameters
    ----------
    asm : Assembly from :func:`demseis.dem.build_assembly`.
    fault : NormalFault (one normal fault) or FaultSystem (1-5 faults, normal, reverse,
        listric; :mod:`demseis.dem.basement`).
    material : contact model and constants; ``model="bonded"`` bonds initial contacts.
    n_snapshots : >= 2; snapshot k is taken when every fault has k / (n_snapshots - 1) of its
        slip (for planar faults: of its throw).
    sedimentation : fill accommodation below the initial surface with growth layers.
    rng : Generator or int seed (sediment radii/positions).
    progress : optional callable(fraction of the run done).
    settle_steps : steps of relaxation in the faulting walls before snapshot 0 (default
        enough for the contacts to load up: ~2 s of model time).
    erosion_level_m : if given, an erosion surface: at every sedimentation time and before
        every snapshot, elements whose centre lies above this elevation are removed (their ids
        no longer appear). Use ``asm.height_m`` to keep uplifted material inside the sample
        grid. None (default): nothing is removed.
    layer_materials : optional mechanical stratigraphy, one Material per pre-kinematic layer
        (``asm.n_layers``; see :func:`demseis.dem.strata.layer_materials`). Their contact
        fields (``kn_n_m``, ``friction``, ``cohesion_n``, ``bond_strain``) apply to the
        elements of that layer (a contact takes the smaller value of its two elements);
        ``material`` keeps the model, ``ks_ratio``, density, damping, gravity, the walls and
        the growth layers. dt follows the largest Kn.

    base_stretch : distributed extension (> 0) or shortening (< 0) of the base as a fraction of
        the width (-0.3 to 0.3; 0 = off): the top of every basement block is cut into pieces
        of at most ``4 r_max`` whose ends move horizontally with the base point they started on
        (:func:`stretch_shift`: left end fixed, right end and right wall moving by
        ``base_stretch * width``), on top of their block's motion; side walls and fault faces
        translate with the base point they stand on. The frictional pieces drag the cover.
        ``FaultSystem((), structure="none")`` is a basement without faults: only the stretch.
    relax_deposits : shrink the disks of every deposit until none of them overlap (they are cut
        from the settled pack, whose contacts hold its lithostatic overlaps: 0.1-2.3 m, whose
        elastic energy is released where the deposit has no overburden). Off by default: it
        changes the growth layers of every run with sedimentation.

    Returns
    -------
    list of Snapshot, ``n_snapshots`` long. ``Snapshot.throw_m`` is the master fault's throw
    (the fault with the largest slip; 0 without faults); :meth:`FaultSystem.throws_at` gives
    every fault's. The run lasts the larger of the master slip and ``|base_stretch| * width``
    at the wall speed; snapshot k holds k / (n_snapshots - 1) of both.

    Raises
    ------
    demseis.errors.SimulationError
        NaN, kinetic-energy blow-up, or an element leaving the box.
    """
    validate_material(material)
    if isinstance(fault, NormalFault):
        validate_fault(fault, asm.width_m)
    system = as_system(fault)
    validate_system(system, asm.width_m)
    validate_stretch(base_stretch)
    if not system.faults and base_stretch == 0.0:
        raise InputError("a FaultSystem without faults (structure 'none') needs base_stretch "
                         "!= 0: nothing would move")
    if not isinstance(n_snapshots, (int, np.integer)) or n_snapshots < 2:
        raise InputError(f"n_snapshots={n_snapshots!r} must be an integer >= 2")
    if erosion_level_m is not None and not math.isfinite(erosion_level_m):
        raise InputError(f"erosion_level_m={erosion_level_m!r} must be a finite elevation")
    if rng is None:
        rng = np.random.default_rng(0)
    elif isinstance(rng, (int, np.integer)):
        rng = np.random.default_rng(int(rng))
    W, H = asm.width_m, asm.height_m
    mirror = bool(system.faults) and all(f.dip_direction == "left" for f in system.faults)
    if mirror:
        system = system.mirrored(W)
    xy0 = asm.xy.copy()
    if mirror:
        xy0[:, 0] = W - xy0[:, 0]
    master = system.faults[system.master] if system.faults else None
    rmin, rmax = asm.radius_min_m, asm.radius_max_m
    motions = block_kinematics(system, W)
    rotating = [b for b, m in enumerate(motions) if m.rotates]

    cmat = None
    if layer_materials is not None:
        cmat, kn_max = _layer_cmat(asm, layer_materials)
        if kn_max > material.kn_n_m:
            material = dataclasses.replace(material, kn_n_m=kn_max)
    # dt from Eq. 5 with the smallest radius that can ever occur (sediment included)
    dt = time_step(min(rmin, float(asm.radius.min())), material.density_kg_m3,
                   material.kn_n_m)
    eng = Integrator(xy0, asm.radius, material, dt_s=dt)
    if cmat is not None:
        eng.set_element_material(cmat)

    dip_total = system.master_slip_m
    stretch_total = float(base_stretch) * W   # displacement of the base's right end (m)
    walls0, owner, anchor = basement_walls(system, motions, W, H, rmax,
                                           4 * rmax if stretch_total != 0.0 else None)
    eng.set_walls(walls0)
    corners = np.concatenate([m.displace([[m.x_left_m, 0.0], [m.x_right_m, 0.0]], dip_total)
                              for m in motions])
    corners[:, 0] += stretch_shift(np.concatenate([[m.x_left_m, m.x_right_m] for m in motions]),
                                   W, stretch_total)
    top = 3.0 * H + 10 * rmax
    eng.box = np.array([min(0.0, corners[:, 0].min()) - 4 * rmax,
                        max(W, corners[:, 0].max()) + 4 * rmax,
                        min(0.0, corners[:, 1].min()) - 4 * rmax, top])
    eng.vmax_limit = max(100.0, 20 * system.speed_m_s)
    if material.model == "bonded":
        eng.bond_initial_contacts()
    elif material.model == "brittle":
        eng.bond_initial_contacts(tol_frac=0.0, flag=2)  # touching pairs: no initial pull
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
    path = max(dip_total, abs(stretch_total))  # the longer of slip and stretch sets the pace
    steps_per_interval = max(int(math.ceil(path / n_interval / (system.speed_m_s * eng.dt))),
                             1) if path > 0 else 0
    total_steps = settle_steps + steps_per_interval * n_interval
    v_dip = dip_total / n_interval / (steps_per_interval * eng.dt) if steps_per_interval else 0.0
    v_end = (stretch_total / n_interval / (steps_per_interval * eng.dt)
             if steps_per_interval else 0.0)          # speed of the base's right end (m/s)
    done = 0

    def report():
        if progress is not None and total_steps > 0:
            progress(min(done / total_steps, 1.0))

    eng.run(settle_steps)
    done += settle_steps
    report()

    def erode() -> None:
        nonlocal ids, layer, deposited
        if erosion_level_m is None:
            return
        keep = eng.pos[:, 1] <= erosion_level_m
        if not keep.all():
            eng.remove_elements(keep)
            ids, layer, deposited = ids[keep], layer[keep], deposited[keep]

    def snap(k: int, applied_dip: float) -> Snapshot:
        erode()
        xy = eng.pos.copy()
        if mirror:
            xy[:, 0] = W - xy[:, 0]
        throw = float(master.throw_at_slip(applied_dip)) if master is not None else 0.0
        return Snapshot(index=k, step=eng.steps, throw_m=throw,
                        ids=ids.copy(), xy=xy, radius=eng.radius.copy(), layer=layer.copy(),
                        deposited=deposited.copy())

    def side_x(right: bool, applied_dip: float, applied_end: float) -> float:
        """x of the left or right side wall within the model height (inner-most point)."""
        b = len(motions) - 1 if right else 0
        m = motions[b]
        xw = W if right else 0.0
        shift = applied_end if right else 0.0   # the right wall follows the base's end
        if not m.rotates:
            return xw + applied_dip * m.velocity[0] + shift
        p = m.displace([[xw, 0.0], [xw, H]], applied_dip)[:, 0]
        return float(p.min() if right else p.max()) + shift

    def placed(w: int, dip: float, end: float) -> np.ndarray:
        return wall_ends(walls0[w], motions[owner[w]], anchor[w], W, dip, end)

    # walls whose ends do not translate together are re-placed every ``chunk`` steps: those of
    # rotating blocks and, on a stretching base, the pieces of the block tops
    moving = np.isin(owner, rotating)
    if stretch_total != 0.0:
        moving |= np.isnan(anchor)
    rot_walls = np.flatnonzero(moving)
    chunk = 50

    def run_part(nsteps: int, start_dip: float, start_end: float) -> None:
        """Run nsteps with the walls moving; ``rot_walls`` are re-placed every ``chunk``."""
        if rot_walls.size == 0:
            eng.run(nsteps)
            return
        left = nsteps
        at, at_end = start_dip, start_end
        while left > 0:
            k = min(chunk, left)
            nxt = at + k * eng.dt * v_dip
            nxt_end = at_end + k * eng.dt * v_end
            for w in rot_walls:
                now = placed(w, at, at_end)
                then = placed(w, nxt, nxt_end)
                eng.walls[w] = now.ravel()
                eng.wall_vel[w] = (then - now).mean(axis=0) / (k * eng.dt)
            eng._refresh_wall_candidates()
            eng.run(k)
            left -= k
            at, at_end = nxt, nxt_end

    snaps = [snap(0, 0.0)]
    applied = 0.0
    applied_end = 0.0
    for k in range(1, n_snapshots):
        grew = False
        q = steps_per_interval // 4
        for part, nsteps in enumerate((q, q, steps_per_interval - 2 * q)):
            eng.wall_vel[:] = 0.0
            for w in range(owner.size):
                vx, vy = motions[owner[w]].velocity
                if vx != 0.0 or vy != 0.0:
                    eng.wall_vel[w] = (v_dip * vx, v_dip * vy)
                if v_end != 0.0 and not math.isnan(anchor[w]):
                    eng.wall_vel[w, 0] += v_end * float(np.clip(anchor[w] / W, 0.0, 1.0))
            run_part(nsteps, applied, applied_end)
            done += nsteps
            applied += nsteps * eng.dt * v_dip
            applied_end += nsteps * eng.dt * v_end
            report()
            if part < 2:
                erode()
            if part < 2 and sedimentation:
                n_before = eng.n
                added = _deposit(eng, side_x(False, applied, applied_end),
                                 side_x(True, applied, applied_end), H,
                                 xy0, asm.radius, W, H, rng, relax=relax_deposits)
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
