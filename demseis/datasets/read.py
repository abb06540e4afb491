"""Read-only views of a demseis store for evaluation and export.

Every read of a store outside the training loader goes through here (or through
:mod:`demseis.datasets.layout`): the samples of completed shards (:func:`done_samples`), the label
view that scoring needs (:func:`open_truth`), the per-sample parameters (:func:`read_params`), one
seismic section with its grid (:func:`read_section`) and its SEG-Y export (:func:`export_segy`).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from demseis.datasets.checked import CheckedArray
from demseis.datasets.layout import domain_varies, open_store, store_layout
from demseis.datasets.status import shard_status
from demseis.datasets.table import DoneParams, FullParams, read_done_params
from demseis.errors import InputError, StoreError
from demseis.seismic.segy import write_segy


def done_samples(root: Any, n: int, path: str | Path, *,
                 require_any: bool = True) -> NDArray[np.bool_]:
    """(n,) bool: the samples of completed shards (``shard_done == 1``).

    Parameters
    ----------
    root : zarr.Group
        The open store.
    n : int
        Number of samples of the array the mask is for.
    path : str or Path
        The store path, for messages.
    require_any : bool
        Raise when no shard is complete (scoring and the baseline need samples).

    Raises
    ------
    StoreError
        The samples do not split into the shards, or (``require_any``) no shard is complete.
    """
    valid = np.ones(n, bool)
    if "shard_done" in set(root.array_keys()):
        done = shard_status(path) == 1  # a damaged flag reads as not done
        if done.size == 0 or n % done.size:
            raise StoreError(f"store {str(path)!r}: {n} samples do not split into "
                             f"{done.size} shards")
        valid = np.repeat(done, n // done.size)
    if require_any and not valid.any():
        raise StoreError(f"store {str(path)!r} is empty: no shard is complete "
                         "(shard_done is 0 everywhere); finish the sweep first")
    return valid


def read_params(path: str | Path, *, decode: bool = False) -> FullParams:
    """Per-sample parameters of a store: name -> (N,) array (fill values outside the done
    samples; categorical ones as names with ``decode``), each read when first asked for, from
    the done shards only (:mod:`demseis.datasets.table`)."""
    return FullParams(read_done_params(path, ()), decode=decode)


@dataclass(frozen=True)
class TruthStore:
    """The parts of a demseis store that scoring reads.

    Attributes
    ----------
    path : str
    fault : CheckedArray, shape (N, H, W), uint8
    valid : ndarray, shape (N,), bool
        Samples of completed shards.
    params : FullParams
        Per-sample parameters from ``params/``, each shape (N,) (read when first asked for;
        ``params.take(samples)`` reads them at a few samples).
    """

    path: str
    fault: Any
    valid: NDArray[np.bool_]
    params: FullParams

    @property
    def shape(self) -> tuple[int, int, int]:
        """(N, H, W) of the label array."""
        return tuple(int(s) for s in self.fault.shape)  # type: ignore[return-value]


def open_truth(path: str | Path, array: str = "fault") -> TruthStore:
    """Open a demseis store read-only for scoring; :class:`StoreError` naming what is wrong.

    Checks the label array ``array`` (N, H, W), ``params/`` and ``shard_done`` (only samples of
    completed shards are scored).
    """
    root = open_store(path, "r")
    names = set(root.array_keys())
    if array not in names:
        raise StoreError(f"store {str(path)!r} has no {array!r} label array; it holds "
                         f"{sorted(names) or 'no arrays'}")
    fault = root[array]
    if fault.ndim != 3:
        raise StoreError(f"store {str(path)!r}: {array!r} must have shape (N, H, W), "
                         f"got {fault.shape}")
    n = int(fault.shape[0])
    if n == 0:
        raise StoreError(f"store {str(path)!r} is empty: {array!r} holds 0 samples")
    valid = done_samples(root, n, path)
    return TruthStore(path=str(path), fault=CheckedArray(fault, path, array), valid=valid,
                      params=read_params(path))


def open_sections(path: str | Path, array: str = "seismic") -> tuple[Any, NDArray[np.bool_]]:
    """The (N, H, W) array ``array`` of a store and the mask of its completed samples."""
    root = open_store(path, "r")
    if array not in set(root.array_keys()):
        raise StoreError(f"store {str(path)!r} has no {array!r} array; it holds "
                         f"{sorted(root.array_keys())}")
    arr = root[array]
    if arr.ndim != 3 or 0 in arr.shape:
        raise StoreError(f"store {str(path)!r}: {array!r} must be a non-empty (N, H, W) "
                         f"array, got shape {arr.shape}")
    return CheckedArray(arr, path, array), done_samples(root, int(arr.shape[0]), path)


def read_section(store: str | Path, sample: int) -> tuple[np.ndarray, dict]:
    """Section ``sample`` (nz, nx) float32 and the store's ``grid`` attribute."""
    path = Path(store)
    group = open_store(path, "r")
    if "seismic" not in group:
        raise StoreError(f"store {str(path)!r} has no 'seismic' array")
    grid = group.attrs.get("grid")
    need = ("x0_m", "top_m", "cell_m", "nz", "nx")
    if not isinstance(grid, dict) or any(k not in grid for k in need):
        raise StoreError(f"store {str(path)!r} lacks the root attribute 'grid' with keys {need}")
    arr = CheckedArray(group["seismic"], path, "seismic")
    n = arr.shape[0]
    if isinstance(sample, bool) or not isinstance(sample, (int, np.integer)) \
            or not 0 <= sample < n:
        raise InputError(f"--sample {sample!r} is out of range: the store has samples 0..{n - 1}")
    section = np.asarray(arr[int(sample)], dtype=np.float32)
    if section.shape != (int(grid["nz"]), int(grid["nx"])) and grid.get("domain") != "time" \
            and not domain_varies(grid):      # rows: depth cells or time samples
        raise StoreError(f"seismic sample shape {section.shape} does not match the store grid "
                         f"(nz={grid['nz']}, nx={grid['nx']})")
    if not np.all(np.isfinite(section)):
        raise StoreError(f"sample {sample} of array 'seismic' in {str(path)!r} was never "
                         "written (its shard is missing or unfinished): it holds NaN")
    return section, dict(grid)


def rows_text(grid: Mapping[str, Any]) -> str:
    """What the rows of a store's samples are, from its ``grid`` attribute: depth cells, time
    samples of one interval, or each run's own (``grid["sampling"]``)."""
    if domain_varies(grid):
        return "depth cells or time samples (each run its own domain)"
    if grid.get("domain") == "time":
        return ("time samples (each run its own dt_s)" if "dt_s" in (grid.get("sampling") or {})
                else f"time samples of {float(grid.get('dt_s', math.nan)) * 1e3:g} ms")
    return f"depth cells of {grid.get('cell_m')} m"


def export_segy(store: str | Path, sample: int, out: str | Path, overwrite: bool = False) -> Path:
    """Write section ``sample`` of a demseis store to the SEG-Y file ``out``.

    The headers are those of :func:`demseis.seismic.segy.write_segy`.
    """
    section, grid = read_section(store, sample)
    domain = grid.get("domain", "depth")
    dt_s = grid.get("dt_s")
    if grid.get("sampling"):  # each sample its own sampling, in the parameter table
        own = read_params(store).take(np.array([int(sample)]))
        grid = {**grid, "dx_m": float(own["trace_spacing_m"][0])}
        if domain_varies(grid):                      # each run its own domain (dt_s 0: depth)
            domain = "time" if float(own["dt_s"][0]) > 0 else "depth"
        if domain == "time":
            dt_s = float(own["dt_s"][0])
    if domain == "time" and (dt_s is None or not math.isfinite(float(dt_s))):
        raise StoreError("store grid says domain 'time' but has no valid 'dt_s'")
    dx = grid.get("dx_m")
    return write_segy(section, out, x0_m=float(grid["x0_m"]), cell_m=float(grid["cell_m"]),
                      trace_spacing_m=None if dx is None else float(dx),
                      top_m=float(grid["top_m"]), domain=domain, dt_s=dt_s, overwrite=overwrite,
                      note=f"store {Path(store).name} sample {sample}")


def _fmt(v: object) -> str:
    f = float(v)  # type: ignore[arg-type]
    return "inf" if math.isinf(f) else f"{f:g}"


def store_summary(path: str | Path, table: DoneParams | None = None) -> list[str]:
    """Lines describing a store: samples, its sample arrays (with their role, units and
    description as the store declares them), parameter ranges over done
    samples, config and failed runs (what ``demseis info`` prints). ``table``: the store's
    :func:`~demseis.datasets.table.read_done_params` (all parameters), if read already."""
    root = open_store(path)
    attrs = dict(root.attrs)
    cfg = attrs.get("config", {})
    lines = [f"store: {path}", f"demseis schema: {attrs.get('demseis', {})}"]
    n, h, w = root["seismic"].shape
    n_shards = int(root["shard_done"].shape[0]) if "shard_done" in root else 1
    per_shard = n // max(n_shards, 1)
    table = read_done_params(path) if table is None else table
    if table.records is not None:        # the table's done shards: the flags read once
        n_done = int(table.shards.size)
    else:                                # a store assembled by hand, read through zarr
        n_done = int(done_samples(root, int(n), path, require_any=False).sum()) // max(per_shard, 1)
    lines.append(f"samples: {n} in {n_shards} shards of {per_shard}; done shards: {n_done}")
    grid = attrs.get("grid", {})
    lines.append(f"grid: {h} x {w}: {rows_text(grid)}, {grid.get('cell_m')} m model cells")
    lines.append("sample arrays (role, units: description):")
    for name, spec in store_layout(root).specs.items():
        a = root[name]
        lines.append(f"  {name:10s} {str(a.dtype):8s} shape {tuple(a.shape)} chunks "
                     f"{tuple(a.chunks)}  {spec.role}, {spec.units}: {spec.description}")
    lines.append("parameters (over done samples):")
    for name, vals in table.values.items():
        if vals.size == 0:
            continue
        names = table.categories.get(name)
        if names:                        # names with their sample counts, e.g. imaging 1d (6), psf (6)
            codes_used, counts = np.unique(vals.astype(np.int64), return_counts=True)
            shown = ", ".join(f"{names[int(c)]} ({int(k)})" for c, k in zip(codes_used, counts))
            lines.append(f"  {name:22s} {shown}")
            continue
        uniq = np.unique(vals)
        if uniq.size <= 6:
            shown = ", ".join(_fmt(v) for v in uniq)
        else:
            shown = f"{_fmt(vals.min())} .. {_fmt(vals.max())} ({uniq.size} distinct)"
        lines.append(f"  {name:22s} {shown}")
    if "has_fault" in table.values and table.samples.size:
        none = int((table.values["has_fault"] == 0).sum())
        lines.append(f"samples without a fault: {none} of {int(table.samples.size)} done "
                     f"(select faulted ones with where={{'has_fault': 1}})")
    if cfg:
        sw = cfg.get("sweep", {})
        model = cfg.get("model", {})
        lines.append(f"config: name={cfg.get('name')} seed={sw.get('seed')} n_runs={sw.get('n_runs')} "
                     f"model={model.get('width_m')}x{model.get('height_m')} m "
                     f"snapshots={model.get('n_snapshots')}")
    failed = attrs.get("failures") or {}
    if failed:
        lines.append(f"failed runs: {len(failed)}")
        for k, v in sorted(failed.items(), key=lambda kv: int(kv[0])):
            lines.append(f"  run {k}: {v}")
    return lines
