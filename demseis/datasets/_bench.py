"""DataLoader throughput of :class:`FaultSegDataset` against a NumPy memmap of the same data.

Used by ``benchmarks/loader.py`` and ``demseis bench loader``. Builds a temporary store of
band-limited synthetic sections (so that compression sees realistic data, not white noise or
zeros) with fault masks, and the same arrays as raw ``.npy`` memmaps, then times full epochs of
random ``crop x crop`` windows through ``torch.utils.data.DataLoader``:

- zarr: ``FaultSegDataset(inputs=("seismic",), targets=("fault",), crop=crop)`` with a
  :class:`ShardAwareSampler`;
- memmap (the limit): a minimal dataset cropping the same windows out of ``np.load(mmap_mode="r")``
  arrays in random order.

Both use the same batch size, workers and collation; workers are persistent and one untimed
epoch warms them (and the page cache) before ``repeats`` timed epochs, whose median is reported.
Epochs of the two loaders alternate, so that the load of a shared machine hits both alike.
"""

from __future__ import annotations

import shutil
import statistics
import tempfile
import time
from pathlib import Path

import numpy as np

from demseis.datasets.dataset import FaultSegDataset, ShardAwareSampler, crop_offsets
from demseis.datasets.store import create_store, finalize_store, write_shard


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
        import torch

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


def _interleaved_rates(loaders: dict, n_items: int, repeats: int) -> dict[str, list[float]]:
    """Epoch rates of each loader, alternating loaders epoch by epoch so that changes in the
    machine's load hit all of them alike; one untimed warm-up epoch each first."""
    for loader in loaders.values():  # warm-up: worker start, page cache, first-touch pages
        for _ in loader:
            pass
    rates: dict[str, list[float]] = {name: [] for name in loaders}
    for _ in range(repeats):
        for name, loader in loaders.items():
            rates[name].append(_epoch_rate(loader, n_items))
    return rates


def run_loader_benchmark(
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
    import torch
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
            ml = DataLoader(mm, sampler=RandomSampler(mm, generator=torch.Generator().manual_seed(seed)),
                            **kw)
            rates = _interleaved_rates({"zarr": zl, "memmap": ml}, n, repeats)
            z_rates, m_rates = rates["zarr"], rates["memmap"]
            del zl, ml
            z_med, m_med = statistics.median(z_rates), statistics.median(m_rates)
            result[f"zarr_samples_per_s_w{nw}"] = round(z_med, 1)
            result[f"memmap_samples_per_s_w{nw}"] = round(m_med, 1)
            result[f"zarr_over_memmap_w{nw}"] = round(z_med / m_med, 3)
            result[f"zarr_runs_w{nw}"] = [round(r, 1) for r in z_rates]
            result[f"memmap_runs_w{nw}"] = [round(r, 1) for r in m_rates]
            if progress:
                import sys

                print(f"workers={nw}: zarr {z_med:.0f}/s, memmap {m_med:.0f}/s", file=sys.stderr)
        return result
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
