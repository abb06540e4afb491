"""Throughput benchmark of the DEM kernels (``demseis bench dem``).

The benchmark runs the frictional model (default :class:`Material`) on a settled pack with
fixed walls at the pack's left, right and bottom, gravity and global viscous damping, and
reports element-steps per second (elements x steps / wall seconds).
"""

from __future__ import annotations

import os
import time
from pathlib import Path

import numpy as np

from demseis.dem.assembly import Pack, settle_pack
from demseis.dem.engine import Engine
from demseis.dem.types import Material
from demseis.errors import InputError

SEED_WIDTH_M = 5000.0
SEED_HEIGHT_M = 2770.0


def default_cache_dir() -> Path:
    """Cache directory for settled packs: ``$DEMSEIS_CACHE`` or ``~/.cache/demseis``."""
    return Path(os.environ.get("DEMSEIS_CACHE", Path.home() / ".cache" / "demseis"))


def seed_pack(cache_dir: str | os.PathLike | None = None, seed: int = 0) -> Pack:
    """The settled seed-scale pack (5 km x 2.77 km, radii 12.5-25 m), cached on disk."""
    return settle_pack(SEED_WIDTH_M, SEED_HEIGHT_M, rng=seed,
                       cache_dir=cache_dir if cache_dir is not None else default_cache_dir())


def load_pack(path: str | os.PathLike) -> tuple[np.ndarray, np.ndarray]:
    """Read a pack file: an ``.npz`` with arrays ``x``, ``y``, ``radius`` (metres).

    Returns
    -------
    xy : (n, 2) float64; radius : (n,) float64.
    """
    p = Path(path)
    if not p.is_file():
        raise InputError(f"--pack {path}: no such file")
    try:
        with np.load(p) as z:
            missing = [k for k in ("x", "y", "radius") if k not in z]
            if missing:
                raise InputError(f"--pack {path}: missing arrays {missing} (need x, y, radius)")
            x, y, r = (np.asarray(z[k], dtype=np.float64).ravel() for k in ("x", "y", "radius"))
    except InputError:
        raise
    except Exception as exc:  # not an npz
        raise InputError(f"--pack {path}: not a readable .npz file ({exc})") from exc
    if not (x.size == y.size == r.size) or x.size == 0:
        raise InputError(f"--pack {path}: x, y, radius must be non-empty and of equal length "
                         f"(got {x.size}, {y.size}, {r.size})")
    if not (np.all(np.isfinite(x)) and np.all(np.isfinite(y)) and np.all(r > 0)):
        raise InputError(f"--pack {path}: x, y must be finite and radius > 0")
    return np.c_[x, y], r


def pack_walls(xy: np.ndarray, radius: np.ndarray) -> np.ndarray:
    """Walls (left, right, bottom) touching the pack's extreme disks, as (3, 4) segments."""
    xlo = float(np.min(xy[:, 0] - radius))
    xhi = float(np.max(xy[:, 0] + radius))
    ylo = float(np.min(xy[:, 1] - radius))
    top = float(np.max(xy[:, 1] + radius)) + 10 * float(radius.max())
    return np.array([[xlo, ylo, xlo, top], [xhi, ylo, xhi, top], [xlo, ylo, xhi, ylo]])


#: the benchmark's contact model: frictional, no cohesion (what LAMMPS gran/hooke/history has)
BENCH_MATERIAL = Material(cohesion_n=0.0)


def run_bench(xy: np.ndarray, radius: np.ndarray, n_steps: int = 2000,
              material: Material = BENCH_MATERIAL, warmup_steps: int = 20) -> dict:
    """Time ``n_steps`` frictional-model steps on the pack; returns a JSON-able dict.

    The kernels are compiled (or loaded from Numba's cache) and warmed by ``warmup_steps``
    steps first; the timed part is the stepping loop only.
    """
    if n_steps < 1:
        raise InputError(f"--steps {n_steps}: must be >= 1")
    eng = Engine(xy, radius, material)
    eng.set_walls(pack_walls(xy, radius))
    eng.run(warmup_steps)
    t0 = time.perf_counter()
    c0 = time.process_time()
    eng.run(n_steps)
    wall = time.perf_counter() - t0
    cpu = time.process_time() - c0
    n = eng.n
    return {"benchmark": "dem", "n_elements": n, "steps": int(n_steps), "dt_s": eng.dt,
            "wall_s": wall, "cpu_s": cpu,
            "element_steps_per_s": n * n_steps / wall,
            "element_steps_per_cpu_s": n * n_steps / cpu if cpu > 0 else None,
            "neighbour_rebuilds": eng.n_rebuilds,
            "numba_threads": int(os.environ.get("NUMBA_NUM_THREADS", "0") or 0)}
