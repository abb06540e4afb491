"""Scoring against a demseis store, grouped by sample parameters: predictions read from a file,
per-sample counts against the store's labels (:mod:`demseis.evaluation.scoring`), rows per
parameter value or bin, and their table."""

from __future__ import annotations

import os
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike, NDArray
from tqdm import tqdm

from demseis.datasets._nodes import zarr_lib
from demseis.errors import InputError, StoreError
from demseis.evaluation.scoring import SampleCounts, count_samples, summarise
from demseis.evaluation.segyfile import is_segy, read_segy_section

if TYPE_CHECKING:
    from demseis.datasets.read import TruthStore

#: a parameter with at most this many distinct values is grouped by value, otherwise binned
MAX_CATEGORIES = 12


def load_predictions(path: str) -> Any:
    """Open predictions of shape (N, H, W): a ``.npy`` file (memory-mapped; a 2-D (H, W) one
    is one section, N = 1), a Zarr array, or a SEG-Y file (``.sgy`` / ``.segy``, one section:
    N = 1, a trace per column, as ``demseis predict`` writes it).

    A Zarr group is accepted when it holds one array, or an array named ``pred``.
    """
    if not os.path.exists(path):
        raise InputError(f"predictions {path!r} do not exist")
    if is_segy(path):
        arr = read_segy_section(path)[None]
    elif str(path).endswith(".npy"):
        try:
            arr = np.load(path, mmap_mode="r", allow_pickle=False)
        except Exception as exc:
            if "Python objects" in str(exc) or "allow_pickle" in str(exc):
                # numpy's text suggests pickling; the fix is a numeric array, never a pickle
                raise InputError(f"predictions {path!r} hold Python objects (dtype object), not "
                                 "numbers: save a numeric (N, H, W) array, e.g. "
                                 "np.save(path, pred.astype(np.float32))") from None
            raise InputError(f"predictions {path!r}: cannot read as .npy ({exc})") from exc
        if arr.ndim == 2:
            arr = arr[None]
    else:
        zarr = zarr_lib()
        try:
            node = zarr.open(path, mode="r")
        except Exception as exc:
            raise InputError(f"predictions {path!r}: neither a .npy file nor a Zarr array "
                             f"({type(exc).__name__}: {exc})") from exc
        if isinstance(node, zarr.Group):
            keys = sorted(node.array_keys())
            if "pred" in keys:
                node = node["pred"]
            elif len(keys) == 1:
                node = node[keys[0]]
            else:
                raise InputError(f"predictions {path!r} is a Zarr group with arrays {keys}; "
                                 "give the array path itself or name it 'pred'")
        arr = node
    if len(arr.shape) != 3:
        raise InputError(f"predictions {path!r}: expected shape (N, H, W) or (H, W), got "
                         f"{arr.shape}")
    return arr


def _read(arr: Any, idx: NDArray[np.int64]) -> NDArray[Any]:
    """Rows ``idx`` (ascending) of a NumPy or Zarr (N, H, W) array, as one contiguous read
    when they are consecutive."""
    if idx.size and idx[-1] - idx[0] + 1 == idx.size:
        return np.asarray(arr[int(idx[0]) : int(idx[-1]) + 1])
    if isinstance(arr, np.ndarray):
        return np.asarray(arr[idx])
    return np.asarray(arr.get_orthogonal_selection((idx, slice(None), slice(None))))


def score_store_counts(pred: Any, store: TruthStore, *, indices: ArrayLike | None = None,
                       threshold: float = 0.5, tolerance_px: float = 0.0,
                       thresholds: int | ArrayLike = 99, block: int = 16,
                       progress: bool = False) -> tuple[SampleCounts, NDArray[np.int64]]:
    """Per-sample counts of ``pred`` against the store's ``fault`` labels.

    Parameters
    ----------
    pred : array-like (N_pred, H, W)
        NumPy or Zarr array of probabilities.
    store : TruthStore
    indices : array_like of int, shape (N_pred,), optional
        Store sample of each prediction row. Default: row i is store sample i, N_pred must equal
        the store's N, and samples of incomplete shards are skipped.
    block : int
        Samples read at a time.
    progress : bool
        Show a tqdm bar on stderr.

    Returns
    -------
    counts : SampleCounts
        One row per scored sample.
    sample_index : ndarray (M,), int64
        The store sample index of each row of ``counts``.
    """
    n_store, h, w = store.shape
    shape = tuple(int(s) for s in pred.shape)
    if shape[1:] != (h, w):
        raise InputError(f"predictions have sections of {shape[1]}x{shape[2]} pixels but the "
                         f"store's are {h}x{w}")
    if indices is None:
        if shape[0] != n_store:
            raise InputError(f"predictions hold {shape[0]} samples but the store holds "
                             f"{n_store}; pass the store index of each prediction (--indices)")
        rows = np.flatnonzero(store.valid)
        sample = rows.copy()
    else:
        sample = np.asarray(indices)
        if sample.ndim != 1 or sample.shape[0] != shape[0] \
                or not np.issubdtype(sample.dtype, np.integer):
            raise InputError(f"indices: expected {shape[0]} integer store indices (one per "
                             f"prediction), got shape {sample.shape} dtype {sample.dtype}")
        if sample.size and (sample.min() < 0 or sample.max() >= n_store):
            raise InputError(f"indices: values must lie in [0, {n_store}), got range "
                             f"[{sample.min()}, {sample.max()}]")
        if np.unique(sample).size != sample.size:
            raise InputError("indices: a store sample appears more than once")
        bad = ~store.valid[sample]
        if bad.any():
            raise StoreError(f"store sample {int(sample[bad][0])} belongs to a shard that is not "
                             f"complete ({int(bad.sum())} such predictions)")
        rows = np.arange(sample.size)
    if rows.size == 0:
        raise InputError("no samples to score")
    order = np.argsort(sample, kind="stable")
    rows, sample = rows[order], sample[order]
    bar = None
    if progress:
        bar = tqdm(total=int(rows.size), desc="score", unit="sample", file=None)
    parts = []
    for s in range(0, rows.size, block):
        r, smp = rows[s : s + block], sample[s : s + block]
        p = _read(pred, r)
        try:
            part = count_samples(p, _read(store.fault, smp), threshold, tolerance_px,
                                 thresholds=thresholds)
        except InputError as exc:
            raise InputError(f"predictions rows {int(r[0])}..{int(r[-1])}: {exc}") from exc
        parts.append(part)
        if bar is not None:
            bar.update(int(r.size))
    if bar is not None:
        bar.close()
    return SampleCounts.concat(parts), sample.astype(np.int64)


def _fmt_value(v: float) -> str:
    if np.isinf(v):
        return "inf" if v > 0 else "-inf"
    return f"{v:.6g}"


def group_rows(counts: SampleCounts, params: dict[str, NDArray[Any]], by: list[str], *,
               bins: int = 4, zero_division: float = 0.0) -> list[dict[str, Any]]:
    """Scores per group of a sample parameter.

    A parameter with at most :data:`MAX_CATEGORIES` distinct values that are all round (whole
    hundredths, or infinite: swept lists such as ``freq_hz = [20, 40, 60]`` or
    ``snr_db = [inf, 10]``) is grouped by value (``inf`` sorts last). Any other (values drawn
    from a distribution, such as ``dip_deg`` or ``throw_m`` per run) is split into ``bins``
    equal-width bins over its finite range, labelled ``[lo, hi)`` (the last bin closed);
    non-finite values then form their own group.

    Parameters
    ----------
    counts : SampleCounts
        One row per scored sample.
    params : dict[str, ndarray]
        Parameter values of the scored samples, each shape (M,).
    by : list of str
        Parameter names to group by.

    Returns
    -------
    list of dict
        Rows with keys ``by, group, lo, hi, n_samples, precision, recall, f1, iou, ap, ods_f1,
        tp, fp, fn, tp_truth``; the first row is the overall one (``by == "all"``).
    """
    if int(bins) != bins or bins < 1:
        raise InputError(f"bins: must be a positive integer, got {bins!r}")
    rows = [_row("all", "all", None, None, counts, zero_division)]
    for name in by:
        if name not in params:
            raise InputError(f"cannot group by {name!r}: the store has per-sample parameters "
                             f"{sorted(params)}")
        v = np.asarray(params[name], dtype=np.float64)
        uniq = np.unique(v)  # NaN last, inf before NaN
        fin = uniq[np.isfinite(uniq)]
        round_ = bool(np.all(np.abs(fin - np.round(fin, 2)) <= 1e-6 * np.maximum(1, np.abs(fin))))
        if uniq.size <= MAX_CATEGORIES and round_:
            for u in uniq:
                mask = np.isnan(v) if np.isnan(u) else (v == u)
                rows.append(_row(name, _fmt_value(u), float(u), float(u), counts.take(mask),
                                 zero_division))
            continue
        finite = v[np.isfinite(v)]
        edges = np.linspace(finite.min(), finite.max(), int(bins) + 1)
        which = np.clip(np.searchsorted(edges, v, side="right") - 1, 0, int(bins) - 1)
        for b in range(int(bins)):
            mask = np.isfinite(v) & (which == b)
            if not mask.any():
                continue
            close = "]" if b == bins - 1 else ")"
            label = f"[{edges[b]:.3g}, {edges[b + 1]:.3g}{close}"
            rows.append(_row(name, label, float(edges[b]), float(edges[b + 1]),
                             counts.take(mask), zero_division))
        if (~np.isfinite(v)).any():
            mask = ~np.isfinite(v)
            rows.append(_row(name, "non-finite", None, None, counts.take(mask), zero_division))
    return rows


def _row(by: str, group: str, lo: float | None, hi: float | None, c: SampleCounts,
         zero_division: float) -> dict[str, Any]:
    r = summarise(c, zero_division)
    return {"by": by, "group": group, "lo": lo, "hi": hi, "n_samples": r.n_samples,
            "precision": r.precision, "recall": r.recall, "f1": r.f1, "iou": r.iou,
            "ap": r.ap, "ods_f1": r.ods_f1, "chance_ap": r.chance_ap, "tp": r.tp, "fp": r.fp,
            "fn": r.fn,
            "tp_truth": r.tp_truth}


TABLE_COLUMNS = ("by", "group", "n_samples", "precision", "recall", "f1", "iou", "ap", "ods_f1",
                 "chance_ap")


def format_table(rows: list[dict[str, Any]], columns: tuple[str, ...] = TABLE_COLUMNS) -> str:
    """Plain aligned text table of group rows (floats with 3 decimals)."""
    def cell(v: Any) -> str:
        if isinstance(v, float):
            return "nan" if np.isnan(v) else f"{v:.3f}"
        return str(v)

    body = [[cell(r[c]) for c in columns] for r in rows]
    widths = [max(len(c), *(len(b[i]) for b in body)) for i, c in enumerate(columns)]
    lines = ["  ".join(c.ljust(wd) if i < 2 else c.rjust(wd)
                       for i, (c, wd) in enumerate(zip(columns, widths)))]
    lines.append("  ".join("-" * wd for wd in widths))
    prev = None
    for r, b in zip(rows, body):
        if prev is not None and r["by"] != prev:
            lines.append("")
        prev = r["by"]
        lines.append("  ".join(x.ljust(wd) if i < 2 else x.rjust(wd)
                               for i, (x, wd) in enumerate(zip(b, widths))))
    return "\n".join(lines)


