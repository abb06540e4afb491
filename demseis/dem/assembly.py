"""Building a settled, layered element assembly.

Two stages, so the expensive one can be reused:

1. :func:`settle_pack` makes a dense random packing of polydisperse disks in a box
   ``[0, width_m] x [0, ~height_m]`` by gravity settling between walls (left, right, bottom):
   disks are dropped from a loose row arrangement and settled frictionless, then friction is
   switched on and the pack settles again; disks with centres above ``height_m`` are cut.
   It depends only on geometry, radii range, material and seed, so it can be cached on disk
   (``cache_dir``) and reused by every run with the same geometry: each cache file holds a
   SHA-256 of its inputs and its arrays, checked on load (a damaged file is settled again, with
   a :class:`PackCacheWarning`), and is written atomically (safe for concurrent workers).
2. :func:`build_assembly` assigns layers by initial centre height (equal or given thicknesses)
   and returns an :class:`Assembly` ready for :func:`demseis.dem.simulate`.
"""

from __future__ import annotations

import hashlib
import json
import math
import os
import tempfile
import warnings
from dataclasses import asdict, dataclass, replace
from pathlib import Path

import numpy as np

from demseis.dem import detmath
from demseis.dem.integrator import Integrator, time_step, validate_material
from demseis.dem.types import Material
from demseis.errors import InputError

#: random dense 2D packing fraction used to size the number of disks before cutting
_PACKING_GUESS = 0.84
#: mass-proportional damping rate (1/s) used while settling a pack
_SETTLE_RATE = 0.5
#: mass-proportional damping rate (1/s) of the frictionless fall (terminal speed g / rate)
_FALL_RATE = 0.15
#: contact softening of the frictionless settling stage
_SETTLE_SOFTEN = 4.0
#: version of the settling recipe and of the cache file format (part of every cache key)
#: v2: radii drawn with detmath (CPU-independent); v3: checksummed cache files
_CACHE_VERSION = 3


class PackCacheWarning(UserWarning):
    """A settled-pack cache file was damaged (unreadable or its checksum wrong) and is rebuilt."""


@dataclass(frozen=True)
class Pack:
    """A settled packing: (n, 2) centres ``xy`` (m), (n,) ``radius`` (m), box size."""

    xy: np.ndarray
    radius: np.ndarray
    width_m: float
    height_m: float


@dataclass
class Assembly:
    """A settled, layered assembly ready for :func:`demseis.dem.simulate`.

    Attributes
    ----------
    xy : (n, 2) float64 centres (m); radius : (n,) float64 (m).
    layer : (n,) int16 layer index, 0 = deepest; ids : (n,) int64 element ids (0..n-1).
    width_m, height_m : the model box; n_layers : number of pre-kinematic layers.
    layer_top_m : (n_layers,) float64 top elevation of each layer (m).
    radius_min_m, radius_max_m : the radii range the pack was drawn from.
    """

    xy: np.ndarray
    radius: np.ndarray
    layer: np.ndarray
    ids: np.ndarray
    width_m: float
    height_m: float
    n_layers: int
    layer_top_m: np.ndarray
    radius_min_m: float
    radius_max_m: float

    @property
    def n(self) -> int:
        return int(self.radius.shape[0])


def draw_radii(n: int, radius_min_m: float, radius_max_m: float,
               rng: np.random.Generator) -> np.ndarray:
    """Draw ``n`` radii log-uniformly in [radius_min_m, radius_max_m] (m).

    Log-uniform (equal numbers per radius octave) gives, for 12.5-25 m in 5 km x 2.77 km, the
    paper's ~10,900 elements at a random dense packing fraction of ~0.84.
    """
    if radius_max_m == radius_min_m:
        return np.full(n, float(radius_min_m))
    u = rng.random(n)
    # not (r_max / r_min) ** u: np.power's result depends on the CPU (see detmath)
    log_ratio = float(detmath.log(radius_max_m / radius_min_m))
    return radius_min_m * detmath.exp(u * log_ratio)


def _check_geometry(width_m, height_m, radius_min_m, radius_max_m):
    for name, v in (("width_m", width_m), ("height_m", height_m),
                    ("radius_min_m", radius_min_m), ("radius_max_m", radius_max_m)):
        ok = isinstance(v, (int, float, np.floating, np.integer)) and not isinstance(v, bool)
        if not (ok and math.isfinite(v) and v > 0):
            raise InputError(f"{name}={v!r} must be a finite number > 0")
    if radius_max_m < radius_min_m:
        raise InputError(f"radius_max_m={radius_max_m} < radius_min_m={radius_min_m}")
    if width_m < 8 * radius_max_m or height_m < 4 * radius_max_m:
        raise InputError(f"box {width_m} x {height_m} m is too small for radius_max_m="
                         f"{radius_max_m} (need width >= 8 r_max, height >= 4 r_max)")
    n_est = _PACKING_GUESS * width_m * height_m / (math.pi * radius_min_m * radius_max_m)
    if n_est > 2_000_000:
        raise InputError(f"box {width_m} x {height_m} m with radii {radius_min_m}-"
                         f"{radius_max_m} m would need ~{n_est:.0f} elements (max 2,000,000)")


def loose_grid(radii: np.ndarray, x_lo: float, x_hi: float, y_lo: float,
               rng: np.random.Generator, gap: float) -> np.ndarray:
    """Place disks one per cell of a square grid (cell 2 r_max + gap) at random offsets.

    Rows of ``floor((x_hi - x_lo) / cell)`` cells are filled bottom-up from ``y_lo``; each disk
    sits at a random position inside its cell, so no two disks overlap and the start is
    disordered (a regular row start settles into crystalline rows).

    Returns
    -------
    (n, 2) float64 centres (m).
    """
    rmax = float(radii.max())
    cell = 2 * rmax + gap
    ncol = max(int((x_hi - x_lo) / cell), 1)
    cell_x = (x_hi - x_lo) / ncol
    n = radii.shape[0]
    k = np.arange(n)
    col = k % ncol
    row = k // ncol
    slack_x = np.maximum(cell_x - 2 * radii - gap, 0.0)
    slack_y = np.maximum(cell - 2 * radii - gap, 0.0)
    xy = np.empty((n, 2))
    xy[:, 0] = x_lo + col * cell_x + 0.5 * gap + radii + rng.random(n) * slack_x
    xy[:, 1] = y_lo + row * cell + 0.5 * gap + radii + rng.random(n) * slack_y
    return xy


def settle_pack(width_m: float, height_m: float, *, radius_min_m: float = 12.5,
                radius_max_m: float = 25.0, material: Material = Material(),
                rng: np.random.Generator | int = 0, cache_dir: str | os.PathLike | None = None,
                progress=None) -> Pack:
    """Dense random packing of disks in ``[0, width_m] x [0, height_m]`` by gravity settling.

    Parameters
    ----------
    width_m, height_m : box size (m); the pack's surface ends up near ``height_m``.
    radius_min_m, radius_max_m : radii range (m), drawn log-uniformly.
    material : contact stiffness, density, friction used for the settling.
    rng : Generator or int seed. With ``cache_dir`` an int seed is needed to name the cache
        entry (a Generator's current state is hashed otherwise).
    cache_dir : directory of ``.npz`` cache files (:func:`pack_cache_path`); a hit skips the
        settling entirely. Each file holds its inputs and a SHA-256 of them and its arrays,
        verified on load: a damaged file warns (:class:`PackCacheWarning`) and is settled again.
    progress : optional callable(fraction).

    Returns
    -------
    Pack

    Notes
    -----
    Stage 1 settles frictionless (mu = 0, also on the walls), which packs densely; stage 2
    switches friction on and lets the contacts load up. Stage 1 is mass-scaled and softened (it
    only has to reach a dense packing); stage 2 uses the true masses and stiffness. Both use
    mass-proportional damping (0.15 /s and 0.5 /s) for quick relaxation; the faulting run uses
    the material's own global damping.
    """
    _check_geometry(width_m, height_m, radius_min_m, radius_max_m)
    validate_material(material)
    if isinstance(rng, (int, np.integer)):
        seed_key = int(rng)
        rng = np.random.default_rng(int(rng))
    elif isinstance(rng, np.random.Generator):
        seed_key = json.dumps(rng.bit_generator.state, sort_keys=True, default=str)
    else:
        raise InputError(f"rng={rng!r} must be a numpy Generator or an int seed")
    path = key = None
    if cache_dir is not None:
        key = json.dumps({"w": float(width_m), "h": float(height_m),
                          "rmin": float(radius_min_m), "rmax": float(radius_max_m), "mat": asdict(material), "seed": seed_key,
                          "v": _CACHE_VERSION}, sort_keys=True)
        path = pack_cache_path(cache_dir, key)
        pack = _load_cached(path, key, width_m, height_m)
        if pack is not None:
            return pack
    mean_area = math.pi * (radius_max_m**2 - radius_min_m**2) / (
        2 * float(detmath.log(radius_max_m / radius_min_m))) if radius_max_m > radius_min_m else (
        math.pi * radius_min_m**2)
    n = int(math.ceil(1.10 * _PACKING_GUESS * width_m * height_m / mean_area))
    radii = draw_radii(n, radius_min_m, radius_max_m, rng)
    xy = loose_grid(radii, 0.0, width_m, 0.0, rng, gap=0.05 * radius_min_m)
    # Stage 1 (frictionless fall and compaction) is not a physical result, only a way to a
    # dense packing: it runs mass-scaled (every disk gets the largest disk's mass) and with a
    # softer contact (Kn / _SETTLE_SOFTEN), so its step is 2 * sqrt(_SETTLE_SOFTEN) larger.
    soft = replace(material, kn_n_m=material.kn_n_m / _SETTLE_SOFTEN)
    m_big = material.density_kg_m3 * math.pi * float(radii.max()) ** 2
    dt1 = 0.25 * math.sqrt(m_big / soft.kn_n_m)
    eng = Integrator(xy, radii, soft, dt_s=dt1, mass_kg=m_big, eta=_FALL_RATE * m_big,
                 friction=0.0, cohesion_n=0.0, wall_friction=0.0, skin_m=0.8 * radius_min_m)
    top = float(xy[:, 1].max()) + 10 * radius_max_m
    walls = np.array([[0.0, -radius_max_m, 0.0, top],
                      [width_m, -radius_max_m, width_m, top],
                      [-radius_max_m, 0.0, width_m + radius_max_m, 0.0]])
    eng.set_walls(walls)
    eng.box = np.array([-2 * radius_max_m, width_m + 2 * radius_max_m, -2 * radius_max_m, top])
    eng.vmax_limit = 400.0
    # free fall of the loose grid takes ~sqrt(2 h / g) at most; then compaction
    drop = float(xy[:, 1].max()) - height_m
    g = max(material.gravity_m_s2, 1e-6)
    t_fall = math.sqrt(2 * max(drop, radius_max_m) / g)
    eng.settle(int((4 * t_fall + 20 / _FALL_RATE) / dt1) + 2000, v_tol_m_s=0.05,
               min_steps=int(t_fall / dt1))
    if progress:
        progress(0.6)
    # Stage 2: the real masses, stiffness, friction and damping rate; contacts load up.
    mass = material.density_kg_m3 * math.pi * radii**2
    dt = time_step(float(radii.min()), material.density_kg_m3, material.kn_n_m)
    eng2 = Integrator(eng.pos, radii, material, dt_s=dt, eta=_SETTLE_RATE * mass)
    eng2.set_walls(walls)
    eng2.box = eng.box
    eng2.vmax_limit = 400.0
    eng2.settle(6000, v_tol_m_s=0.01, min_steps=1000)
    eng = eng2
    if progress:
        progress(1.0)
    keep = eng.pos[:, 1] <= height_m
    pack = Pack(eng.pos[keep].copy(), eng.radius[keep].copy(), float(width_m), float(height_m))
    if path is not None:
        _write_cached(path, key, pack)
    return pack


def pack_cache_path(cache_dir: str | os.PathLike, key: str) -> Path:
    """The cache file of the pack whose inputs are ``key`` (a canonical JSON string):
    ``cache_dir/pack_<first 20 hex digits of its SHA-256>.npz``."""
    return Path(cache_dir) / f"pack_{hashlib.sha256(key.encode()).hexdigest()[:20]}.npz"


def _pack_digest(key: str, xy: np.ndarray, radius: np.ndarray) -> str:
    """SHA-256 of a pack's inputs and arrays (little-endian float64 bytes)."""
    h = hashlib.sha256(key.encode())
    for a in (xy, radius):
        h.update(np.ascontiguousarray(a, dtype="<f8").tobytes())
    return h.hexdigest()


def _load_cached(path: Path, key: str, width_m: float, height_m: float) -> Pack | None:
    """The pack cached at ``path``, or None when there is none; a file that cannot be read, was
    made from other inputs or fails its checksum is reported (:class:`PackCacheWarning`) and
    treated as absent (it is settled again and replaced)."""
    if not path.exists():
        return None
    try:
        with np.load(path, allow_pickle=False) as z:
            xy, radius = z["xy"].copy(), z["radius"].copy()
            stored_key, stored_sum = str(z["key"]), str(z["sha256"])
        if stored_key != key:
            why = "made from other inputs"
        elif stored_sum != _pack_digest(key, xy, radius):
            why = "checksum mismatch"
        elif xy.ndim != 2 or xy.shape != (radius.shape[0], 2):
            why = f"arrays of shapes {xy.shape} and {radius.shape}"
        else:
            return Pack(xy, radius, float(width_m), float(height_m))
    except Exception as exc:  # noqa: BLE001 - any unreadable file (zip, npy, missing entry)
        why = f"unreadable: {type(exc).__name__}: {exc}"
    warnings.warn(f"settled-pack cache file {str(path)!r} is damaged ({why}); settling the "
                  "pack again", PackCacheWarning, stacklevel=3)
    return None


def _write_cached(path: Path, key: str, pack: Pack) -> None:
    """Write ``pack`` to ``path`` atomically: a unique temporary file in the same directory,
    then a rename, so readers see the old file or the whole new one, and workers settling the
    same pack at once each write identical arrays. A cache that cannot be written warns
    (:class:`PackCacheWarning`); the pack is still used."""
    tmp = None
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(prefix=f".{path.stem}.", suffix=".tmp", dir=path.parent)
        os.fchmod(fd, 0o644)   # mkstemp makes 0600; a shared cache is read by others
        with os.fdopen(fd, "wb") as f:
            np.savez(f, xy=pack.xy, radius=pack.radius, key=np.array(key),
                     sha256=np.array(_pack_digest(key, pack.xy, pack.radius)))
        os.replace(tmp, path)
    except OSError as exc:
        warnings.warn(f"settled-pack cache {str(path.parent)!r} cannot be written ({exc}); the "
                      "pack is settled again next time", PackCacheWarning, stacklevel=3)
        if tmp is not None:
            Path(tmp).unlink(missing_ok=True)
    except BaseException:   # an interrupt: leave no temporary file behind
        if tmp is not None:
            Path(tmp).unlink(missing_ok=True)
        raise


def build_assembly(width_m: float, height_m: float, *, radius_min_m: float = 12.5,
                   radius_max_m: float = 25.0, n_layers: int = 48,
                   layer_thickness_m=None, material: Material = Material(),
                   rng: np.random.Generator | int | None = None, pack: Pack | None = None,
                   cache_dir: str | os.PathLike | None = None) -> Assembly:
    """Settled, layered assembly of polydisperse disks filling ``[0, width_m] x [0, height_m]``.

    Parameters
    ----------
    width_m, height_m : model box (m).
    radius_min_m, radius_max_m : radii range (m), log-uniform.
    n_layers : number of pre-kinematic layers (>= 1).
    layer_thickness_m : (n_layers,) thicknesses bottom-to-top summing to ``height_m``
        (within 1e-6 relative); None = equal thicknesses.
    material : Material used for settling.
    rng : Generator or int seed (default seed 0).
    pack : a pre-settled :class:`Pack` of the same geometry (from :func:`settle_pack`); skips
        the settling.
    cache_dir : forwarded to :func:`settle_pack` (on-disk reuse of the settled pack).

    Returns
    -------
    Assembly
        Layers are assigned by initial centre height: layer k holds the elements whose centre
        lies between the bottom and top of layer k.
    """
    _check_geometry(width_m, height_m, radius_min_m, radius_max_m)
    if not isinstance(n_layers, (int, np.integer)) or n_layers < 1 or n_layers > 32000:
        raise InputError(f"n_layers={n_layers!r} must be an integer in [1, 32000]")
    if layer_thickness_m is None:
        thick = np.full(n_layers, height_m / n_layers)
    else:
        thick = np.asarray(layer_thickness_m, dtype=np.float64)
        if thick.shape != (n_layers,):
            raise InputError(f"layer_thickness_m has shape {thick.shape}; expected ({n_layers},)")
        if np.any(~np.isfinite(thick)) or np.any(thick <= 0):
            raise InputError("layer_thickness_m must be finite and > 0")
        if abs(thick.sum() - height_m) > 1e-6 * height_m:
            raise InputError(f"layer_thickness_m sums to {thick.sum():.3f} m; it must equal "
                             f"height_m={height_m}")
    if rng is None:
        rng = np.random.default_rng(0)
    if pack is None:
        pack = settle_pack(width_m, height_m, radius_min_m=radius_min_m,
                           radius_max_m=radius_max_m, material=material, rng=rng,
                           cache_dir=cache_dir)
    elif abs(pack.width_m - width_m) > 1e-9 or abs(pack.height_m - height_m) > 1e-9:
        raise InputError(f"pack is {pack.width_m} x {pack.height_m} m; the assembly asks for "
                         f"{width_m} x {height_m} m")
    tops = np.cumsum(thick)
    tops[-1] = max(tops[-1], height_m)
    layer = np.searchsorted(tops, pack.xy[:, 1], side="right")
    layer = np.clip(layer, 0, n_layers - 1).astype(np.int16)
    n = pack.radius.shape[0]
    return Assembly(xy=pack.xy.copy(), radius=pack.radius.copy(), layer=layer,
                    ids=np.arange(n, dtype=np.int64), width_m=float(width_m),
                    height_m=float(height_m), n_layers=int(n_layers), layer_top_m=tops,
                    radius_min_m=float(radius_min_m), radius_max_m=float(radius_max_m))
