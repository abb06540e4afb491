"""Deterministic shard contents for the datasets tests (also used by killed child processes)."""

from __future__ import annotations

import hashlib
from pathlib import Path

import numpy as np

from demseis.datasets import create_store, write_shard
from demseis.schema import SAMPLE_ARRAYS, sample_array
from demseis.types import Snapshot

PARAMS = {"run_id": "int32", "snapshot": "int16", "freq_hz": "float32", "snr_db": "float32",
          "noise_kind": "int8"}
ARRAYS = ("seismic", "fault", "damage", "strain", "layer")


def grid_attrs(shape: tuple[int, int]) -> dict:
    return {"x0_m": 0.0, "top_m": 0.0, "cell_m": 10.0, "nz": shape[0], "nx": shape[1]}


def shard_data(k: int, s: int, shape: tuple[int, int], arrays=ARRAYS, params=PARAMS,
               n_snapshots: int = 3, seed: int = 0):
    """(arrays, params, particles) of shard ``k``: random but a pure function of its inputs."""
    rng = np.random.default_rng([seed, k])
    h, w = shape
    data = {}
    for name in arrays:
        if name in ("seismic", "strain", "impedance"):
            data[name] = rng.normal(size=(s, h, w)).astype(np.float32)
        elif name == "fault":
            data[name] = rng.integers(0, 2, (s, h, w), dtype=np.uint8)
        elif name == "damage":
            data[name] = rng.integers(0, 3, (s, h, w), dtype=np.uint8)
        elif name == "layer":
            data[name] = rng.integers(0, 60, (s, h, w), dtype=np.int16)
    snap = np.arange(s) % n_snapshots
    pvals = {
        "run_id": np.full(s, k),
        "snapshot": snap,
        "freq_hz": np.array([20.0, 40.0, 60.0])[np.arange(s) % 3],
        "snr_db": np.where(np.arange(s) % 2 == 0, np.inf, 10.0),
        "noise_kind": np.arange(s) % 2,
    }
    pvals = {n: pvals[n] for n in params}
    particles = []
    n0 = int(rng.integers(3, 12))
    for i in range(n_snapshots):
        n = n0 + i  # deposited elements appear later
        particles.append(Snapshot(
            index=i, step=100 * i, throw_m=10.0 * i,
            ids=np.arange(n, dtype=np.int64),
            xy=rng.uniform(0, 1000, (n, 2)),
            radius=rng.uniform(12.5, 25, n),
            layer=rng.integers(0, 48, n).astype(np.int16),
            deposited=np.arange(n) >= n0,
        ))
    return data, pvals, particles


def make_store(path: Path, n_shards: int = 4, s: int = 6, shape=(24, 32), write=None,
               arrays=ARRAYS, params=PARAMS, seed: int = 0, overwrite: bool = False):
    """Create a store and write the shards in ``write`` (default all)."""
    create_store(path, n_shards=n_shards, samples_per_shard=s, shape=shape, arrays=list(arrays),
                 params=params, attrs={"config": {"seed": seed}, "grid": grid_attrs(shape)},
                 overwrite=overwrite)
    for k in range(n_shards) if write is None else write:
        d, p, parts = shard_data(k, s, shape, arrays, params, seed=seed)
        write_shard(path, k, d, p, parts)
    return path


#: (samples per shard, sample shape, parameters) of the stores of :func:`every_array_shard`
EVERY_S, EVERY_SHAPE = 5, (8, 12)
EVERY_PARAM_DTYPES = {"a_i8": "int8", "b_i16": "int16", "c_i32": "int32", "d_i64": "int64",
                      "e_u8": "uint8", "f_u16": "uint16", "g_f32": "float32", "h_f64": "float64"}


def every_array_dtypes() -> dict[str, np.dtype]:
    """Name -> dtype of every sample array the schema declares, in store order."""
    return {name: spec.np_dtype for name, spec in SAMPLE_ARRAYS.items()}


def every_array_shard(k: int, variant: int = 0) -> tuple[dict, dict, list[Snapshot]]:
    """(arrays, params, particles) of shard ``k`` of a store of every sample array and every
    parameter dtype (:data:`EVERY_PARAM_DTYPES`): random values, labels that fill an inner
    chunk with one value (0: a constant chunk that is not the fill value), -0.0 and extremes."""
    s, shape = EVERY_S, EVERY_SHAPE
    rng = np.random.default_rng([k, variant])
    arrays = {}
    for name, dtype in every_array_dtypes().items():
        if dtype.kind == "f":
            a = rng.normal(size=(s, *shape)).astype(dtype)
            a[1] = -0.0  # a float chunk of negative zeros
            a[2] = 0.0
        elif sample_array(name).valid_range[1] is not None:  # a bounded label: 0 or 1
            a = rng.integers(0, 2, (s, *shape), dtype=dtype)
            a[0] = 0  # a constant chunk that is not the fill value 255
        else:
            a = rng.integers(0, 3000, (s, *shape)).astype(dtype)
            a[3] = np.iinfo(dtype).max
        arrays[name] = a
    params = {}
    for name, dtype in EVERY_PARAM_DTYPES.items():
        dt = np.dtype(dtype)
        if dt.kind == "f":
            params[name] = np.array([0.0, -0.0, np.inf, -1.5e30, 3.25])[:s].astype(dt)
        else:
            lo = np.iinfo(dt).min + 1 if dt.kind == "i" else 0  # the fill value is reserved
            hi = np.iinfo(dt).max if dt.kind == "i" else np.iinfo(dt).max - 1
            params[name] = np.array([lo, hi, 0, 1, hi - 7])[:s].astype(dt)
    params["d_i64"] = np.full(s, k + 10 * variant, dtype=np.int64)  # constant chunk
    snaps = []
    for i in range(3):
        m = 0 if i == 0 else 4 + i + variant  # snapshot 0 has no element
        snaps.append(Snapshot(index=i, step=50 * i, throw_m=2.5 * i,
                              ids=np.arange(m, dtype=np.int64), xy=rng.uniform(0, 9, (m, 2)),
                              radius=rng.uniform(1, 2, m),
                              layer=rng.integers(0, 9, m).astype(np.int16),
                              deposited=np.zeros(m, dtype=bool)))  # all False: fill value 0
    return arrays, params, snaps


def digest(path: Path) -> dict[str, str]:
    """sha256 of every file of a store, by relative path (byte-identity of two stores)."""
    return {str(f.relative_to(path)): hashlib.sha256(f.read_bytes()).hexdigest()
            for f in sorted(path.rglob("*")) if f.is_file()}


def mini_config(domain: str = "depth"):
    """A sweep of one minute DEM run (a few seconds once Numba's cache is warm); 30 m of throw passes
    the relaxation-time check of demseis.generator.engines.physics at 5 m/s (20 m did not)."""
    from demseis.generator.config.settings import load_config, parse_config

    raw = load_config(preset="tiny").to_dict()
    raw["sweep"].update(n_runs=1, n_layers=2, throw_m=30.0, dip_deg=60.0, snr_db=[10.0],
                        noise_kind="band")
    raw["model"].update(n_snapshots=2, width_m=300.0, height_m=200.0)
    raw["output"] = {**raw.get("output", {}), "domain": domain, "impedance": True}
    return parse_config(raw)


def set_param(path: Path, name: str, index, value) -> None:
    """Write ``value`` into parameter ``name`` at sample(s) ``index`` through zarr (the
    record's bytes in the ``params`` table), as damage a test injects."""
    import zarr

    from demseis.datasets import read_layout
    from demseis.datasets.records import record_dtype

    layout = read_layout(path)
    table = zarr.open_group(path, mode="r+", use_consolidated=False)["params"]
    rows = np.asarray(table[:]).copy()
    rec = rows.view(record_dtype(list(layout.columns.values()))).reshape(-1)
    rec[name][index] = value
    table[:] = rows


def zarr_params(path: Path) -> dict[str, np.ndarray]:
    """Every parameter of every sample (N,) read through zarr, not demseis's readers: the
    ``params`` table's bytes viewed as the record its attributes declare (the fill bytes of a
    shard never written read as zeros)."""
    import zarr

    table = zarr.open_group(path, mode="r", use_consolidated=False)["params"]
    cols = table.attrs["demseis"]["columns"]
    rec = np.asarray(table[:]).view(np.dtype([(c["name"], c["dtype"]) for c in cols])).reshape(-1)
    return {c["name"]: rec[c["name"]].astype(np.dtype(c["dtype"]).newbyteorder("=")) for c in cols}


def drop_param(path: Path, name: str) -> None:
    """Rewrite the store's parameter table without parameter ``name`` (a store written before
    that parameter existed), its index emptied and the consolidated metadata dropped."""
    import json
    import shutil

    import zarr

    from demseis.datasets import read_layout
    from demseis.datasets._nodes import create_arrays, put_files, zarr_files
    from demseis.datasets.create import _table_specs
    from demseis.datasets.records import record_dtype

    layout = read_layout(path)
    cols = [c for c in layout.columns.values() if c.name != name]
    table = zarr.open_group(path, mode="r", use_consolidated=False)["params"]
    old = np.asarray(table[:]).view(record_dtype(list(layout.columns.values()))).reshape(-1)
    new = np.zeros(old.shape[0], record_dtype(cols))
    for c in cols:
        new[c.name] = old[c.name]
    for arr in ("params", "params_index", "params_index_files"):
        shutil.rmtree(path / arr)
    files = zarr_files(lambda st: create_arrays(st, _table_specs(layout, cols)))
    put_files(path, {k: v for k, v in files.items() if k != "zarr.json"})
    meta = json.loads((path / "zarr.json").read_text())
    meta.pop("consolidated_metadata", None)
    (path / "zarr.json").write_text(json.dumps(meta))
    zarr.open_group(path, mode="r+", use_consolidated=False)["params"][:] = (
        new.view(np.uint8).reshape(old.shape[0], -1))
