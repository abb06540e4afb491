"""Helpers shared by the evaluation tests: small stores to score, train on and run baselines on,
and a small 3-D SEG-Y cube."""

from __future__ import annotations

import numpy as np


def make_store(path, n_shards=3, per_shard=4, h=24, w=20, seed=0, done=None, with_fault=True,
               seismic=None):
    """A small store with the layout of docs/store.md: fault labels are vertical lines."""
    import zarr

    from demseis.datasets import SCHEMA_VERSION

    rng = np.random.default_rng(seed)
    n = n_shards * per_shard
    root = zarr.open_group(str(path), mode="w")
    root.attrs["demseis"] = {"schema_version": SCHEMA_VERSION}
    root.attrs["grid"] = {"x0_m": 0.0, "top_m": 0.0, "cell_m": 10.0, "nz": h, "nx": w}
    root.attrs["config"] = {}
    fault = np.zeros((n, h, w), np.uint8)
    for i in range(n):
        fault[i, :, int(rng.integers(3, w - 3))] = 1
    if with_fault:
        root.create_array("fault", data=fault, chunks=(1, h, w))
    sei = rng.normal(size=(n, h, w)).astype(np.float32) if seismic is None else seismic
    root.create_array("seismic", data=sei.astype(np.float32), chunks=(1, h, w))
    params = root.create_group("params")
    params.create_array("run_id", data=np.repeat(np.arange(n // 2), 2).astype(np.int64))
    params.create_array("snapshot", data=np.tile([0, 1], n // 2).astype(np.int64))
    params.create_array("freq_hz", data=np.tile([20.0, 40.0, 60.0], n // 3 + 1)[:n])
    params.create_array("snr_db", data=np.tile([np.inf, 10.0], n // 2))
    params.create_array("dip_deg", data=np.linspace(50.0, 80.0, n))
    params.create_array("throw_m", data=np.linspace(10.0, 100.0, n))
    flags = np.ones(n_shards, np.uint8) if done is None else np.asarray(done, np.uint8)
    root.create_array("shard_done", data=flags, chunks=(1,))
    return fault


def toy_store(path, n_shards=5, per_shard=4, h=32, w=32, fault_fn=None, seismic_fn=None):
    """Faulted sections written with demseis.datasets; ``fault_fn`` / ``seismic_fn`` (arrays of
    one shard in, out) make a store with other labels or other seismic of the same samples."""
    from demseis import datasets
    from demseis_dev.toys import faulted_section

    datasets.create_store(path, n_shards=n_shards, samples_per_shard=per_shard, shape=(h, w),
                          arrays=["seismic", "fault"],
                          params={"run_id": "int32", "freq_hz": "float32",
                                  "snr_db": "float32", "dip_deg": "float32"},
                          attrs={"config": {}, "grid": {"x0_m": 0.0, "top_m": 0.0,
                                                        "cell_m": 10.0, "nz": h, "nx": w}})
    for k in range(n_shards):
        dip = 55.0 + 5 * k
        secs, labs = zip(*(faulted_section(nz=h, nx=w, dip_deg=dip, seed=10 * k + j,
                                           noise=0.3 * (j % 2)) for j in range(per_shard)))
        secs, labs = np.stack(secs), np.stack(labs)
        if fault_fn is not None:
            labs = fault_fn(labs)
        if seismic_fn is not None:
            secs = seismic_fn(secs)
        datasets.write_shard(path, k, {"seismic": secs, "fault": labs},
                             {"run_id": k, "freq_hz": np.array([20.0, 20.0, 40.0, 40.0]),
                              "snr_db": np.array([np.inf, 10.0, np.inf, 10.0]),
                              "dip_deg": dip})


def write_cube(path, cube, ilines, xlines, *, sorting_inline=True):
    """A 3-D SEG-Y file of ``cube`` (inlines, crosslines, samples) at 4 ms, IBM float (format
    1, as field cubes are), with inline/crossline numbers and coordinates in the headers."""
    import segyio

    spec = segyio.spec()
    spec.ilines, spec.xlines = list(ilines), list(xlines)
    spec.samples = list(range(0, 4 * cube.shape[2], 4))
    spec.format = 1
    spec.sorting = (segyio.TraceSortingFormat.INLINE_SORTING if sorting_inline
                    else segyio.TraceSortingFormat.CROSSLINE_SORTING)
    with segyio.create(str(path), spec) as f:
        k = 0
        pairs = ([(i, j) for i in range(len(ilines)) for j in range(len(xlines))] if sorting_inline
                 else [(i, j) for j in range(len(xlines)) for i in range(len(ilines))])
        for i, j in pairs:
            f.header[k] = {segyio.su.iline: ilines[i], segyio.su.xline: xlines[j],
                           segyio.su.cdpx: 1000 + 25 * j, segyio.su.cdpy: 5000 + 25 * i,
                           segyio.su.offset: 1}
            f.trace[k] = cube[i, j].astype(np.float32)
            k += 1
        f.bin.update(tsort=spec.sorting)
