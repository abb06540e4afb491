"""Integrity checks of a demseis store (``demseis validate PATH``).

Only shards whose done flag is set are checked: pending shards are work still to do, not
problems. A done shard must pass every chunk checksum (each damaged sample and array is named),
be complete (every chunk present), finite, hold labels within range and consistent parameters,
and its DEM run's particle snapshots (when stored) must be readable. ``validate`` only reads,
so it takes no writer lock and may run while a sweep writes (it checks the shards done so far).
"""

from __future__ import annotations

import sys
from collections.abc import Iterable, Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from tqdm import tqdm

from demseis.datasets._shardio import check_chunk_file
from demseis.datasets.index import INDEX_ARRAYS, indexed_rows, written_blocks
from demseis.datasets.integrity import read_done_flags, shard_damage
from demseis.datasets.layout import (SCHEMA_VERSION, StoreLayout, array_metas,
                                     check_store_metadata, domain_varies, metadata_problems,
                                     open_store, store_layout)
from demseis.datasets.particles import particle_group_name, read_particles
from demseis.datasets.records import fill_value_for, read_table_chunk, unpack
from demseis.errors import StoreError
from demseis.schema import SampleArray

_GRID_KEYS = ("x0_m", "top_m", "cell_m", "nz", "nx")


@dataclass
class ValidationReport:
    """Outcome of :func:`validate_store`.

    Attributes
    ----------
    path : the store checked.
    problems : one human-readable line per problem (empty when the store is fine).
    n_shards, n_done : shards in the store and shards marked done.
    n_samples_checked : samples of done shards that were read and checked.
    failures : the driver's ``failures`` attr (shard index -> error text).
    """

    path: str
    problems: list[str] = field(default_factory=list)
    n_shards: int = 0
    n_done: int = 0
    n_samples_checked: int = 0
    failures: dict[str, str] = field(default_factory=dict)

    @property
    def ok(self) -> bool:
        """True when no problem was found."""
        return not self.problems

    def summary(self) -> str:
        """One line: shards done / pending / failed, samples checked, problems."""
        pending = self.n_shards - self.n_done
        text = (
            f"{self.path}: {self.n_done}/{self.n_shards} shards done, {pending} pending"
            f" ({len(self.failures)} recorded failures), {self.n_samples_checked} samples checked"
        )
        n = len(self.problems)
        return text + (", ok" if self.ok else f", {n} problem{'' if n == 1 else 's'}")


def _check_array(spec: SampleArray, values: np.ndarray, shard: int, s0: int) -> list[str]:
    """Problems of one done shard's slice of the sample array ``spec`` declares (as the store
    describes it)."""
    name = spec.name
    out = []
    if values.dtype.kind == "f":
        bad = ~np.isfinite(values)
        if bad.any():
            samples = np.unique(np.nonzero(bad)[0]) + s0
            out.append(
                f"shard {shard}: {name} has {int(bad.sum())} NaN/inf values (missing or corrupt "
                f"data) in samples {_fmt(samples)}"
            )
        return out
    fill = fill_value_for(values.dtype)
    missing = (values == fill).all(axis=(1, 2))
    if missing.any():
        out.append(f"shard {shard}: {name} samples {_fmt(np.nonzero(missing)[0] + s0)} were never written")
    lo, hi = spec.valid_range or (None, None)
    if lo is not None:
        hi_v = np.iinfo(values.dtype).max if hi is None else hi
        bad = (values < lo) | (values > hi_v)
        bad[missing] = False
        if bad.any():
            samples = np.unique(np.nonzero(bad)[0]) + s0
            vals = np.unique(values[bad])
            out.append(
                f"shard {shard}: {name} has values {_fmt(vals)} outside [{lo}, {hi_v}] in samples "
                f"{_fmt(samples)}"
            )
    return out


def _fmt(values: np.ndarray, limit: int = 8) -> str:
    vals = [str(v) for v in np.asarray(values).tolist()[:limit]]
    more = len(values) - limit
    return ", ".join(vals) + (f" ... (+{more})" if more > 0 else "")


def _intact(group: Any, names: Iterable[str], label: str, k: int, sel: slice,
            damage: list[str], problems: list[str]) -> Iterator[tuple[str, np.ndarray]]:
    """``(name, values)`` of shard ``k`` of each array ``names`` of ``group`` whose checksums
    passed (``damage`` has no line for ``label + name``); an array that still cannot be read is
    appended to ``problems``."""
    for name in names:
        what = f"shard {k}: {label}{name}"
        if any(f"{what} " in line for line in damage):
            continue
        try:
            values = group[name][sel]
        except Exception as exc:  # noqa: BLE001 - truncated file, undecodable chunk
            problems.append(f"{what} is unreadable: {exc}")
            continue
        yield name, values


def _shard_params(path: Path, group: Any, layout: StoreLayout, metas: dict, k: int,
                  damage: list[str], problems: list[str],
                  records: dict[int, np.ndarray]) -> dict[str, np.ndarray]:
    """Every parameter of shard ``k`` whose checksum passed, name -> (S,) values; the shard's
    records are kept in ``records`` (for the index check)."""
    if not layout.table:  # a store assembled by hand: an array per parameter
        pgroup = group["params"] if layout.params else None
        sel = layout.shard_slice(k)
        return dict(_intact(pgroup, layout.params, "parameter ", k, sel, damage, problems))
    if not layout.params or any(line.startswith(f"shard {k}: parameters ") for line in damage):
        return {}
    try:
        rows = read_table_chunk(path, metas["params"], k, layout.samples_per_shard)[0]
        values = unpack(rows, list(layout.columns.values()))
    except (OSError, ValueError) as exc:
        problems.append(f"shard {k}: parameters are unreadable: {exc}")
        return {}
    records[k] = rows
    return values


def _index_problems(path: Path, layout: StoreLayout, metas: dict,
                    records: dict[int, np.ndarray]) -> list[str]:
    """The index of the parameter table against the table: a block that fails its checksum,
    or rows that differ from the chunk they claim to copy (``demseis migrate`` rebuilds it)."""
    if not layout.table or not all(n in metas for n in INDEX_ARRAYS):
        return []
    out = []
    for b in sorted(written_blocks(path, metas["params_index_files"])):
        for arr in INDEX_ARRAYS:
            problem = check_chunk_file(metas[arr].block_file(path, b))
            if problem:
                out.append(f"index block {b}: {arr} is damaged ({problem}); "
                           f"`demseis migrate {path}` rebuilds the index")
    shards = np.array(sorted(records), dtype=np.int64)
    held = indexed_rows(path, metas, shards, layout.samples_per_shard)
    wrong = [k for k, rows in held.items() if not np.array_equal(rows, records[k])]
    if wrong:
        out.append(f"the index holds other parameters than the table for shards {_fmt(wrong)}; "
                   f"`demseis migrate {path}` rebuilds the index")
    return out


def validate_store(path: str | Path, *, check_particles: bool = True,
                   progress: bool = False) -> ValidationReport:
    """Check a demseis store; return every problem found.

    Checks
    ------
    - root attrs: ``demseis`` (schema and package version), ``config``, ``grid`` (with keys
      x0_m, top_m, cell_m, nz, nx matching the sample shape);
    - every done shard: each sample array readable, no NaN/inf in float arrays, no never-written
      chunk, labels within their declared ``valid_range`` (:mod:`demseis.schema`); each parameter readable, no NaN (``inf`` only in
      parameters named ``*snr_db``), no missing integers; ``run_id`` (if stored) constant in
      the shard and different from every other shard's; ``snapshot`` (if stored) non-negative
      and, with particles stored, less than the run's number of snapshots;
    - the particles of each done shard's run, where stored: readable, consistent offsets.

    Parameters
    ----------
    path : store directory.
    check_particles : also read each done run's particle snapshots.
    progress : show a tqdm bar over the done shards on stderr.

    Raises
    ------
    StoreError
        The path is missing, foreign or of another schema version (the CLI exits 2).
    """
    check_store_metadata(Path(path))  # the root: StoreError (exit 2) when unreadable
    meta_problems = metadata_problems(path)
    if meta_problems:  # the data cannot be checked against metadata that cannot be read
        report = ValidationReport(path=str(path))
        report.problems.extend(meta_problems)
        report.problems.append("metadata damaged: `demseis generate` with the store's config "
                               "rewrites it")
        return report
    group = open_store(path, "r")  # read only: validate never writes, so it takes no lock
    attrs = dict(group.attrs)
    layout = store_layout(group)
    report = ValidationReport(path=str(path), n_shards=layout.n_shards)
    problems = report.problems
    report.failures = {str(k): str(v) for k, v in dict(attrs.get("failures", {})).items()}

    info = attrs.get("demseis", {})
    if info.get("schema_version") != SCHEMA_VERSION or "package_version" not in info:
        problems.append(f"root attr 'demseis' is incomplete: {info!r}")
    if not isinstance(attrs.get("config"), dict):
        problems.append("root attr 'config' (the resolved config) is missing")
    grid = attrs.get("grid")
    if not isinstance(grid, dict):
        problems.append("root attr 'grid' is missing")
    else:
        missing = [k for k in _GRID_KEYS if k not in grid]
        if missing:
            problems.append(f"root attr 'grid' lacks {missing}")
        elif grid.get("domain", "depth") == "time" or domain_varies(grid):
            if (grid.get("nt"), grid["nx"]) != layout.shape:
                problems.append(
                    f"time-domain grid nt, nx = ({grid.get('nt')}, {grid['nx']}) but samples are "
                    f"{layout.shape}"
                )
        elif (grid["nz"], grid["nx"]) != layout.shape:
            problems.append(
                f"grid nz, nx = ({grid['nz']}, {grid['nx']}) but samples are {layout.shape}"
            )

    done, damaged_flags = read_done_flags(path, layout.n_shards, group["shard_done"])
    for k in damaged_flags:
        problems.append(f"shard {k}: done flag is damaged (crc32c mismatch); the shard counts "
                        "as pending and a resumed sweep rewrites it")
    bad_flags = np.nonzero(done > 1)[0]
    if bad_flags.size:
        problems.append(f"shard_done holds values other than 0/1 at shards {_fmt(bad_flags)}")
    done_shards = np.nonzero(done == 1)[0]
    report.n_done = int(done_shards.size)
    for key in report.failures:
        if key.isdigit() and int(key) < layout.n_shards and done[int(key)] == 1:
            problems.append(f"shard {key} is done but still listed under 'failures'")

    s = layout.samples_per_shard
    metas = array_metas(Path(path)) if layout.table else {}
    records: dict[int, np.ndarray] = {}
    run_of_shard: dict[int, int] = {}
    for k in tqdm(done_shards.tolist(), desc="validate", unit="shard", disable=not progress,
                  file=sys.stderr):
        sel = layout.shard_slice(k)
        damage = shard_damage(path, k, group, layout, metas)  # names every damaged sample
        problems.extend(damage)
        for name, values in _intact(group, layout.arrays, "", k, sel, damage, problems):
            problems.extend(_check_array(layout.specs[name], values, k, sel.start))
        pvals = _shard_params(Path(path), group, layout, metas, k, damage, problems, records)
        for name, v in pvals.items():
            dtype = layout.params[name]
            if dtype.kind == "f":
                if np.isnan(v).any():
                    problems.append(f"shard {k}: parameter {name} has NaN (missing) values")
                inf_ok = name.endswith("snr_db")
                if np.isinf(v).any() and not (inf_ok and (v[np.isinf(v)] > 0).all()):
                    problems.append(f"shard {k}: parameter {name} has infinite values")
            elif (v == fill_value_for(dtype)).any():
                problems.append(f"shard {k}: parameter {name} has missing values")
        if "run_id" in pvals:
            ids = np.unique(pvals["run_id"])
            if ids.size != 1:
                problems.append(f"shard {k}: run_id is not constant ({_fmt(ids)})")
            else:
                run_of_shard[k] = int(ids[0])
        run_id = run_of_shard.get(k, k)
        if "snapshot" in pvals and (pvals["snapshot"] < 0).any():
            problems.append(f"shard {k}: parameter snapshot has negative values")
        if check_particles and not any("particles" in line for line in damage) and (
                Path(path) / particle_group_name(run_id) / "zarr.json").is_file():
            try:
                snaps = read_particles(path, run_id)
            except StoreError as exc:
                problems.append(f"shard {k}: {exc}")
            else:
                if "snapshot" in pvals and (pvals["snapshot"] >= len(snaps)).any():
                    problems.append(
                        f"shard {k}: parameter snapshot reaches {int(pvals['snapshot'].max())} but "
                        f"run {run_id} stores {len(snaps)} particle snapshots"
                    )
        report.n_samples_checked += s

    problems.extend(_index_problems(Path(path), layout, metas, records))
    seen: dict[int, int] = {}
    for k, rid in run_of_shard.items():
        if rid in seen:
            problems.append(f"shards {seen[rid]} and {k} share run_id {rid} (one shard = one run)")
        seen.setdefault(rid, k)
    return report
