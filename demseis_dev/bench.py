"""Speed benchmarks of the stages, each returning one JSON-ready dict; run from a checkout as
``python -m demseis_dev.bench dem|seismic|labels|loader`` (one JSON line each).

- ``dem`` (:func:`dem_benchmark`): DEM kernel throughput. The frictional model (default
  :class:`Material`) on a settled pack with fixed walls at the pack's left, right and bottom,
  gravity and global viscous damping; reports element-steps per second (elements x steps / wall
  seconds).
- ``seismic`` (:func:`seismic_benchmark`): the whole per-snapshot seismic render of a faulted toy
  pack.
- ``labels`` (:func:`labels_benchmark`): strain history and label maps on a seed-scale-sized
  synthetic model (no DEM needed).
- ``loader`` (:func:`loader_benchmark`): DataLoader throughput of
  :class:`~demseis.datasets.FaultSegDataset` against a NumPy memmap of the same data.

Loader benchmark details: Builds a temporary store of
band-limited synthetic sections (so that compression sees realistic data, not white noise or
zeros) with fault masks, and the same arrays as raw ``.npy`` memmaps, then times full epochs of
random ``crop x crop`` windows through ``torch.utils.data.DataLoader``:

- zarr: ``FaultSegDataset(inputs=("seismic",), targets=("fault",), crop=crop)`` with a
  :class:`ShardAwareSampler`;
- memmap (the limit): a minimal dataset cropping the same windows out of ``np.load(mmap_mode="r")``
  arrays in random order.

Both use the same batch size, workers and collation; workers are persistent and a first epoch
(reported apart, ``*_first_epoch_*``: worker start, page cache and, for the store, the first
check of each chunk's crc32c in each worker) warms them before ``repeats`` timed epochs, whose
median is reported. Epochs of the two loaders alternate, so that the load of a shared machine
hits both alike.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import statistics
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from demseis.datasets import create_store, finalize_store, write_shard
from demseis.datasets.dataset import FaultSegDataset, ShardAwareSampler, crop_offsets
from demseis.dem.assembly import Pack, settle_pack
from demseis.dem.integrator import Integrator
from demseis.dem.types import Material
from demseis.errors import InputError, import_torch
from demseis.labels import LabelConfig, displacement_history, label_maps, strain_history
from demseis.seismic.forward import synthetic_sections
from demseis.seismic.properties import (PropertyModel, draw_layer_properties, element_properties,
                                        fill_background, property_grids, smooth)
from demseis.seismic.raster import rasterise
from demseis.types import Grid, Snapshot, load_snapshots
from demseis_dev.toys import disk_pack, faulted_sequence, kinematic_fault

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


def dem_benchmark(xy: np.ndarray, radius: np.ndarray, n_steps: int = 2000,
                  material: Material = BENCH_MATERIAL, warmup_steps: int = 20) -> dict:
    """Time ``n_steps`` frictional-model steps on the pack; returns a JSON-able dict.

    The kernels are compiled (or loaded from Numba's cache) and warmed by ``warmup_steps``
    steps first; the timed part is the stepping loop only.
    """
    if n_steps < 1:
        raise InputError(f"--steps {n_steps}: must be >= 1")
    eng = Integrator(xy, radius, material)
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


# --------------------------------------------------------------------------------------------
# seismic


def median_ms(fn, repeats: int) -> tuple[float, float]:
    """Median wall-clock and process-CPU milliseconds of ``fn()`` over ``repeats`` calls."""
    wall, cpu = [], []
    for _ in range(repeats):
        t0, c0 = time.perf_counter(), time.process_time()
        fn()
        wall.append(time.perf_counter() - t0)
        cpu.append(time.process_time() - c0)
    return float(np.median(wall) * 1e3), float(np.median(cpu) * 1e3)


def seismic_benchmark(nx: int = 512, nz: int = 288, cell_m: float = 10.0, repeats: int = 7,
                      freqs_hz: tuple[float, ...] = (20.0, 40.0, 60.0), seed: int = 0,
                      npz: str | None = None) -> dict:
    """Time the render of one faulted toy snapshot (``nx`` x ``nz`` cells of ``cell_m``).

    The snapshot is the last (throw 450 m) of :func:`demseis_dev.toys.faulted_sequence`
    over ``nx cell_m`` x ``nz cell_m`` m (about 11,800 disks at 512 x 288). Timed, as medians
    of ``repeats`` runs after one warm-up (Numba compiled and cached): element properties,
    rasterisation, background fill, smoothing of both grids, the convolution for one frequency
    and for all of ``freqs_hz``, and the whole render (properties -> grids -> sections) for one
    frequency and for all. ``ms_per_section_*`` divides the whole render by the number of
    frequencies. Runs single-threaded Numba code (as in the dask workers).
    """
    rng = np.random.default_rng(seed)
    width, height = nx * cell_m, nz * cell_m
    if npz is None:
        snap = faulted_sequence(width, height, rng=rng)[-1]
        source = "kinematic toy sequence, last snapshot"
    else:
        snap = load_snapshots(npz)[-1]
        source = f"{npz}, last snapshot"
    grid = Grid.covering(width, height, cell_m)
    model = PropertyModel().validate()
    lp = draw_layer_properties(int(snap.layer.max()) + 1, model, rng)
    f1 = (freqs_hz[0],)

    def props():
        return element_properties(snap.ids, snap.layer, lp, model, seed)

    vp_e, rho_e = props()
    values = np.column_stack([vp_e, rho_e])

    def rast():
        return rasterise(snap.xy, snap.radius, values, grid)

    mean, count = rast()

    def background():
        return fill_background(mean.copy(), count, snap.xy, values, snap.layer.astype(np.int64),
                               grid, model.background)

    filled = background()

    def smoothing():
        return smooth(filled[:, :, 0], model), smooth(filled[:, :, 1], model)

    vp_g, rho_g = smoothing()

    def render(freqs):
        ve, re = element_properties(snap.ids, snap.layer, lp, model, seed)
        vg, rg = property_grids(snap.xy, snap.radius, ve, re, snap.layer, grid, model)
        return synthetic_sections(vg, rg, cell_m, freqs)

    render(freqs_hz)  # warm-up: Numba compilation / cache load
    nf = len(freqs_hz)
    comp = {
        "element_properties": median_ms(props, repeats),
        "rasterise": median_ms(rast, repeats),
        "background": median_ms(background, repeats),
        "smooth_vp_rho": median_ms(smoothing, repeats),
        "convolution_1f": median_ms(lambda: synthetic_sections(vp_g, rho_g, cell_m, f1),
                                     repeats),
        f"convolution_{nf}f": median_ms(
            lambda: synthetic_sections(vp_g, rho_g, cell_m, freqs_hz), repeats),
    }
    full1 = median_ms(lambda: render(f1), repeats)
    fulln = median_ms(lambda: render(freqs_hz), repeats)
    return {
        "benchmark": "seismic_render",
        "nz": grid.nz,
        "nx": grid.nx,
        "cell_m": cell_m,
        "snapshot": source,
        "n_elements": int(snap.ids.shape[0]),
        "freqs_hz": list(freqs_hz),
        "repeats": repeats,
        "loadavg_1min": round(os.getloadavg()[0], 2),
        "ms_snapshot_1f": round(full1[0], 2),
        f"ms_snapshot_{nf}f": round(fulln[0], 2),
        "ms_per_section_1f": round(full1[0], 2),
        f"ms_per_section_{nf}f": round(fulln[0] / nf, 2),
        "cpu_ms_snapshot_1f": round(full1[1], 2),
        f"cpu_ms_snapshot_{nf}f": round(fulln[1], 2),
        "components_ms": {k: round(v[0], 2) for k, v in comp.items()},
        "components_cpu_ms": {k: round(v[1], 2) for k, v in comp.items()},
    }


# --------------------------------------------------------------------------------------------
# labels


def _snapshots(n_snapshots: int, seed: int):
    xy, r = disk_pack(5000.0, 2770.0, np.random.default_rng(seed), packing_fraction=0.88)
    n = xy.shape[0]
    layer = np.minimum(xy[:, 1] // (2770.0 / 48), 47).astype(np.int16)
    snaps = []
    for k in range(n_snapshots):
        slip = 450.0 / np.sin(np.radians(45.0)) * k / max(n_snapshots - 1, 1)
        cur = kinematic_fault(xy, x_m=2500.0, dip_deg=45.0, slip_m=0.6 * slip,
                              zone_width_m=200.0)
        cur = kinematic_fault(cur, x_m=2500.0, dip_deg=45.0, slip_m=0.4 * slip)
        snaps.append(Snapshot(k, 100 * k, 450.0 * k / max(n_snapshots - 1, 1),
                              np.arange(n, dtype=np.int64), cur, r, layer, np.zeros(n, bool)))
    return snaps


def labels_benchmark(n_snapshots: int = 6, repeats: int = 5, seed: int = 0) -> dict:
    """Median wall times of :func:`strain_history` and of :func:`label_maps` per snapshot.

    Returns a dict ready for one JSON line.
    """
    snaps = _snapshots(n_snapshots, seed)
    cfg = LabelConfig()
    grid = Grid.covering(5000.0, 2770.0, 10.0)
    hist = strain_history(snaps[:2], cfg)  # JIT warm-up
    label_maps(snaps[1], hist[1], grid, cfg, displacement=displacement_history(snaps[:2])[1])
    t_hist, t_maps = [], []
    for _ in range(repeats):
        t0 = time.perf_counter()
        hist = strain_history(snaps, cfg)
        t_hist.append(time.perf_counter() - t0)
        t0 = time.perf_counter()
        for s, h, d in zip(snaps, hist, displacement_history(snaps)):
            label_maps(s, h, grid, cfg, displacement=d)
        t_maps.append((time.perf_counter() - t0) / len(snaps))
    return {
        "benchmark": "labels",
        "n_elements": int(snaps[0].n),
        "n_snapshots": n_snapshots,
        "grid": list(grid.shape),
        "strain_history_s_median": round(float(np.median(t_hist)), 4),
        "label_maps_s_per_snapshot_median": round(float(np.median(t_maps)), 4),
        "repeats": repeats,
    }


# --------------------------------------------------------------------------------------------
# loader


def synthetic_shard(rng: np.random.Generator, s: int, h: int, w: int) -> dict[str, np.ndarray]:
    """``s`` band-limited sections (h, w) with a dipping fault offsetting them, and labels.

    Reflectivity: sparse spikes per row band, laterally continuous, convolved along depth with
    a 30-sample-period Ricker-like pulse; a fault plane with random dip shifts the hanging wall.
    """
    z = np.arange(h)
    refl = rng.normal(size=(s, h)) * (rng.random((s, h)) < 0.15)
    t = np.arange(-16, 17) / 8.0
    wavelet = (1 - 2 * (np.pi * 0.5 * t) ** 2) * np.exp(-((np.pi * 0.5 * t) ** 2))
    trace = np.stack([np.convolve(r, wavelet, mode="same") for r in refl])  # (s, h)
    seismic = np.empty((s, h, w), np.float32)
    fault = np.zeros((s, h, w), np.uint8)
    x = np.arange(w)
    for i in range(s):
        x0 = rng.uniform(0.3, 0.7) * w
        slope = np.tan(np.deg2rad(rng.uniform(30, 70)))
        throw = int(rng.integers(5, 30))
        fx = x0 + z / slope  # fault x at each depth
        hanging = x[None, :] > fx[:, None]
        seismic[i] = trace[i][:, None] * (1 + 0.1 * rng.normal(size=(1, w)))
        seismic[i][hanging] = np.roll(trace[i], throw)[:, None].repeat(w, 1)[hanging]
        fault[i] = np.abs(x[None, :] - fx[:, None]) < 1.5
    seismic += 0.05 * rng.normal(size=seismic.shape).astype(np.float32)
    return {"seismic": seismic, "fault": fault}


class MemmapCrops:
    """Minimal memmap dataset with the same crops and item format as :class:`FaultSegDataset`."""

    def __init__(self, seismic_npy: str, fault_npy: str, crop: int, seed: int = 0) -> None:
        self.files = (seismic_npy, fault_npy)
        self.crop = crop
        self.seed = seed
        self._arrays = None
        self.n, self.h, self.w = np.load(seismic_npy, mmap_mode="r").shape

    def __getstate__(self):
        return {**self.__dict__, "_arrays": None}

    def __len__(self) -> int:
        return self.n

    def __getitem__(self, i: int):
        import torch  # heavy: loaded only by the loader benchmark's workers

        if self._arrays is None:
            self._arrays = [np.load(f, mmap_mode="r") for f in self.files]
        r, c = crop_offsets(self.seed, 0, np.array([i]), self.h - self.crop + 1,
                            self.w - self.crop + 1)  # the same windows as FaultSegDataset
        r0, c0 = int(r[0]), int(c[0])
        win = (int(i), slice(r0, r0 + self.crop), slice(c0, c0 + self.crop))
        x = np.array(self._arrays[0][win], dtype=np.float32)[None]
        y = np.array(self._arrays[1][win])  # uint8, like FaultSegDataset's default
        return torch.from_numpy(x), torch.from_numpy(y)


def _epoch_rate(loader, n_items: int) -> float:
    t0 = time.perf_counter()
    seen = 0
    for x, _y in loader:
        seen += x.shape[0]
    rate = seen / (time.perf_counter() - t0)
    assert seen == n_items
    return rate


def _interleaved_rates(loaders: dict, n_items: int,
                       repeats: int) -> tuple[dict[str, list[float]], dict[str, float]]:
    """Epoch rates of each loader, alternating loaders epoch by epoch so that changes in the
    machine's load hit all of them alike, after one first epoch each, timed apart (worker
    start, page cache, first-touch pages and, for the store, each chunk's first checksum)."""
    first = {name: _epoch_rate(loader, n_items) for name, loader in loaders.items()}
    rates: dict[str, list[float]] = {name: [] for name in loaders}
    for _ in range(repeats):
        for name, loader in loaders.items():
            rates[name].append(_epoch_rate(loader, n_items))
    return rates, first


def loader_benchmark(
    *,
    n_shards: int = 24,
    samples_per_shard: int = 32,
    shape: tuple[int, int] = (277, 500),
    crop: int = 256,
    batch_size: int = 32,
    repeats: int = 3,
    workers: tuple[int, ...] = (0, 2),
    workdir: str | None = None,
    seed: int = 0,
    progress: bool = False,
) -> dict:
    """Build the data, time both loaders, return the result dict (one JSON line's worth)."""
    torch = import_torch("python -m demseis_dev.bench loader")  # heavy: only this benchmark needs it
    from torch.utils.data import DataLoader, RandomSampler

    torch.set_num_threads(1)
    tmp = Path(tempfile.mkdtemp(prefix="demseis_bench_", dir=workdir))
    try:
        h, w = shape
        n = n_shards * samples_per_shard
        store = tmp / "bench.zarr"
        create_store(store, n_shards=n_shards, samples_per_shard=samples_per_shard, shape=shape,
                     arrays=["seismic", "fault"], params={"run_id": "int32"},
                     attrs={"config": {"benchmark": "loader"},
                            "grid": {"x0_m": 0.0, "top_m": 0.0, "cell_m": 10.0, "nz": h, "nx": w}})
        seis_mm = np.lib.format.open_memmap(tmp / "seismic.npy", "w+", np.float32, (n, h, w))
        fault_mm = np.lib.format.open_memmap(tmp / "fault.npy", "w+", np.uint8, (n, h, w))
        rng = np.random.default_rng(seed)
        t0 = time.perf_counter()
        for k in range(n_shards):
            d = synthetic_shard(rng, samples_per_shard, h, w)
            write_shard(store, k, d, {"run_id": np.full(samples_per_shard, k)})
            sl = slice(k * samples_per_shard, (k + 1) * samples_per_shard)
            seis_mm[sl], fault_mm[sl] = d["seismic"], d["fault"]
        write_s = time.perf_counter() - t0
        finalize_store(store)
        seis_mm.flush()
        fault_mm.flush()
        del seis_mm, fault_mm
        store_bytes = sum(f.stat().st_size for f in store.rglob("*") if f.is_file())

        result: dict = {
            "benchmark": "loader",
            "n_samples": n,
            "shape": [h, w],
            "crop": [crop, crop],
            "batch_size": batch_size,
            "samples_per_shard": samples_per_shard,
            "repeats": repeats,
            "store_mb": round(store_bytes / 2**20, 1),
            "raw_mb": round(n * h * w * 5 / 2**20, 1),
            "write_samples_per_s": round(n / write_s, 1),
        }
        ds = FaultSegDataset(store, ("seismic",), ("fault",), crop=crop, seed=seed)
        mm = MemmapCrops(str(tmp / "seismic.npy"), str(tmp / "fault.npy"), crop, seed)
        for nw in workers:
            kw = dict(batch_size=batch_size, num_workers=nw, persistent_workers=nw > 0)
            zl = DataLoader(ds, sampler=ShardAwareSampler(ds, seed=seed), **kw)
            order = torch.Generator().manual_seed(seed)
            ml = DataLoader(mm, sampler=RandomSampler(mm, generator=order), **kw)
            rates, first = _interleaved_rates({"zarr": zl, "memmap": ml}, n, repeats)
            z_rates, m_rates = rates["zarr"], rates["memmap"]
            del zl, ml
            z_med, m_med = statistics.median(z_rates), statistics.median(m_rates)
            result[f"zarr_samples_per_s_w{nw}"] = round(z_med, 1)
            result[f"memmap_samples_per_s_w{nw}"] = round(m_med, 1)
            result[f"zarr_over_memmap_w{nw}"] = round(z_med / m_med, 3)
            result[f"zarr_runs_w{nw}"] = [round(r, 1) for r in z_rates]
            result[f"memmap_runs_w{nw}"] = [round(r, 1) for r in m_rates]
            result[f"zarr_first_epoch_samples_per_s_w{nw}"] = round(first["zarr"], 1)
            result[f"memmap_first_epoch_samples_per_s_w{nw}"] = round(first["memmap"], 1)
            if progress:
                print(f"workers={nw}: zarr {z_med:.0f}/s, memmap {m_med:.0f}/s", file=sys.stderr)
        return result
    finally:
        shutil.rmtree(tmp, ignore_errors=True)

def _parser() -> argparse.ArgumentParser:
    """The command line: ``python -m demseis_dev.bench dem|seismic|labels|loader``."""
    ap = argparse.ArgumentParser(prog="python -m demseis_dev.bench",
                                 description="Speed benchmarks printing one JSON line each.")
    bench = ap.add_subparsers(dest="target", metavar="TARGET", required=True)
    p = bench.add_parser("dem", help="DEM kernel throughput (element-steps per second)")
    p.add_argument("--pack", default=None,
                   help=".npz with arrays x, y, radius (m); default: the seed-scale pack "
                        "(5 km x 2.77 km), settled once and cached")
    p.add_argument("--steps", type=int, default=2000, help="timed steps (default 2000)")
    p.set_defaults(func=cmd_dem)

    p = bench.add_parser(
        "seismic",
        help="ms per rendered snapshot/section at 512x288 (1 and 3 frequencies)",
        description="Time the whole per-snapshot seismic render (element properties, "
                    "rasterisation, background, smoothing, time-domain Ricker convolution back "
                    "to depth) of a faulted toy disk pack; prints one JSON line.",
    )
    p.add_argument("--nx", type=int, default=512, help="grid columns (default 512)")
    p.add_argument("--nz", type=int, default=288, help="grid rows (default 288)")
    p.add_argument("--repeats", type=int, default=7, help="timed repeats, median (default 7)")
    p.add_argument("--npz", help="render the last snapshot of this .npz (demseis.types."
                                 "save_snapshots, e.g. saved from a DEM run) instead of the "
                                 "kinematic toy pack")
    p.set_defaults(func=cmd_seismic)

    p = bench.add_parser("labels", help="strain history and label maps on ~11k elements")
    p.add_argument("--snapshots", type=int, default=6, help="number of snapshots (>= 2)")
    p.add_argument("--repeats", type=int, default=5, help="timed repeats (median reported)")
    p.set_defaults(func=cmd_labels)

    p = bench.add_parser("loader", help="DataLoader throughput vs NumPy memmap (256x256 crops)")
    p.add_argument("--shards", type=int, default=48, help="shards in the temporary store")
    p.add_argument("--samples-per-shard", type=int, default=32)
    p.add_argument("--shape", type=int, nargs=2, default=(277, 500), metavar=("H", "W"))
    p.add_argument("--crop", type=int, default=256)
    p.add_argument("--batch-size", type=int, default=32)
    p.add_argument("--repeats", type=int, default=5)
    p.add_argument("--workers", type=int, nargs="+", default=(0, 2))
    p.add_argument("--dir", default=None, help="where to build the temporary store")
    p.set_defaults(func=cmd_loader)
    return ap


def cmd_dem(args: argparse.Namespace) -> int:
    if args.steps < 1:
        raise InputError(f"--steps {args.steps}: must be >= 1")
    if args.pack:
        xy, r = load_pack(args.pack)
    else:
        print("demseis: settling the seed-scale pack (cached after the first time)...",
              file=sys.stderr)
        pack = seed_pack()
        xy, r = pack.xy, pack.radius
    print(json.dumps(dem_benchmark(xy, r, n_steps=args.steps)))
    return 0


def cmd_seismic(args: argparse.Namespace) -> int:
    for name in ("nx", "nz", "repeats"):
        if getattr(args, name) < 1:
            raise InputError(f"--{name} must be >= 1, got {getattr(args, name)}")
    if args.npz is not None and not os.path.isfile(args.npz):
        raise InputError(f"--npz {args.npz!r} is not a file")
    print(json.dumps(seismic_benchmark(nx=args.nx, nz=args.nz, repeats=args.repeats,
                                       npz=args.npz)))
    return 0


def cmd_labels(args: argparse.Namespace) -> int:
    if args.snapshots < 2 or args.repeats < 1:
        raise InputError(f"--snapshots must be >= 2 and --repeats >= 1; got {args.snapshots}, "
                         f"{args.repeats}")
    print(json.dumps(labels_benchmark(n_snapshots=args.snapshots, repeats=args.repeats)))
    return 0


def cmd_loader(args: argparse.Namespace) -> int:
    result = loader_benchmark(
        n_shards=args.shards,
        samples_per_shard=args.samples_per_shard,
        shape=tuple(args.shape),
        crop=args.crop,
        batch_size=args.batch_size,
        repeats=args.repeats,
        workers=tuple(args.workers),
        workdir=args.dir,
        progress=sys.stderr.isatty(),
    )
    print(json.dumps(result))
    return 0


def main(argv: list[str] | None = None) -> int:
    """Run one benchmark; a bad argument is one line on stderr and exit status 2."""
    args = _parser().parse_args(argv)
    try:
        return args.func(args)
    except InputError as exc:
        print(f"python -m demseis_dev.bench: error: {exc}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    raise SystemExit(main())
