"""Benchmark scoring of fault predictions: precision, recall, F1 and IoU.

Definitions (all pooled over every pixel given: a *micro* average)
-----------------------------------------------------------------
A pixel is *predicted* a fault when ``pred >= threshold``. With ``tolerance_px = r``:

- a predicted fault pixel is *matched* when a labelled fault pixel of the same sample lies within
  Euclidean distance ``r`` of it (``distance_transform_edt(~truth) <= r``);
- a labelled fault pixel is *matched* when a predicted fault pixel lies within ``r`` of it
  (``distance_transform_edt(~predicted) <= r``).

Then, with ``n_pred`` predicted and ``n_truth`` labelled fault pixels::

    tp = matched predicted pixels          fp = n_pred - tp
    tp_truth = matched labelled pixels     fn = n_truth - tp_truth
    precision = tp / n_pred                recall = tp_truth / n_truth
    F1  = 2 P R / (P + R)                  IoU = F1 / (2 - F1) = P R / (P + R - P R)

This is the boundary-matching rule of the BSDS benchmark (without its one-to-one assignment).
With ``r = 0`` both matchings are the plain intersection, ``tp == tp_truth``, and the formulas
reduce exactly to scikit-learn's ``precision_score``, ``recall_score``, ``f1_score`` and
``jaccard_score`` (IoU = TP / (TP + FP + FN)) on the flattened masks.

Zero denominators follow scikit-learn's ``zero_division`` argument (default 0.0): with no
predicted pixels precision is ``zero_division``; with no labelled pixels recall is
``zero_division``; with neither, all four scores are ``zero_division``; with exactly one of them
empty F1 and IoU are 0 (as scikit-learn gives).

Threshold sweeps
----------------
For ``thresholds`` t_1 < ... < t_K (default 0.01, 0.02, ..., 0.99) the same counts are formed at
every threshold in one pass: precision counts come from a histogram of the predictions at pixels
within ``r`` of a label; recall counts from a histogram of the running maximum of the prediction
over a disk of radius ``r`` (``maximum_filter``) at labelled pixels, which is the same matching
rule as the distance transform at every threshold at once.

- ``ods_f1``: the best dataset-pooled F1 over the thresholds, at ``ods_threshold``;
- ``ois_f1``: the mean over samples of each sample's best F1 over the thresholds, taken over the
  samples that contain labelled fault pixels (others have no recall);
- ``ap``: average precision, ``sum_k (R_k - R_{k-1}) P_k`` over the thresholds from high to low
  (scikit-learn's step definition; precision is taken as 1 where nothing is predicted). It equals
  ``sklearn.metrics.average_precision_score`` when every distinct prediction value is one of the
  thresholds, and otherwise differs by the threshold discretisation (below 0.01 on continuous
  random scores with the default 99 thresholds, see the tests);
- ``chance_ap``: the fraction of pixels within ``r`` of a labelled pixel, which is the precision
  (and so the average precision) that random scores get: the level a detector must beat.
"""

from __future__ import annotations

import csv
import json
import os
from dataclasses import dataclass, field, fields
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy import ndimage
from tqdm import tqdm

from demseis.datasets.read import open_truth
from demseis.errors import InputError, StoreError
from demseis.evaluation.fieldio import as_masks, read_masks, resize_sections
from demseis.evaluation.segyfile import is_segy, read_segy_section

if TYPE_CHECKING:
    from demseis.datasets.read import TruthStore

__all__ = [
    "SampleCounts",
    "ScoreResult",
    "count_samples",
    "default_thresholds",
    "disk_footprint",
    "within_tolerance",
    "metrics_from_counts",
    "score",
    "score_mask",
    "score_store",
    "StoreScore",
    "summarise",
]


def default_thresholds(n: int = 99) -> NDArray[np.float64]:
    """``n`` evenly spaced thresholds strictly inside (0, 1): ``k / (n + 1)``, k = 1..n."""
    if int(n) != n or n < 1:
        raise InputError(f"thresholds: number of thresholds must be a positive integer, got {n!r}")
    return np.arange(1, int(n) + 1, dtype=np.float64) / (int(n) + 1)


def disk_footprint(radius_px: float) -> NDArray[np.bool_]:
    """Boolean disk of offsets (dy, dx) with ``dy**2 + dx**2 <= radius_px**2``.

    Shape (2k+1, 2k+1) with k = floor(radius_px).
    """
    k = int(np.floor(radius_px))
    dy, dx = np.mgrid[-k : k + 1, -k : k + 1]
    return (dy * dy + dx * dx) <= radius_px * radius_px


def within_tolerance(mask: NDArray[np.bool_], tol: float) -> NDArray[np.bool_]:
    """Pixels within Euclidean distance ``tol`` of a True pixel of the 2-D ``mask`` (the
    matching rule above: ``distance_transform_edt(~mask) <= tol``; all False for an empty mask)."""
    if not mask.any():
        return np.zeros_like(mask)
    return ndimage.distance_transform_edt(~mask) <= tol


@dataclass(frozen=True)
class SampleCounts:
    """Per-sample pixel counts, the sufficient statistics of every score.

    Attributes
    ----------
    n_pred, n_truth, tp, tp_truth : ndarray, shape (N,), int64
        Predicted, labelled, matched-predicted and matched-labelled fault pixels at ``threshold``.
    n_near_truth, n_pixels : ndarray, shape (N,), int64
        Pixels within ``tolerance_px`` of a labelled pixel, and all pixels: their ratio is the
        precision (and average precision) of random scores, the chance level.
    curve_n_pred, curve_tp, curve_tp_truth : ndarray, shape (N, K), int64
        The same counts at each of the K ``thresholds``.
    thresholds : ndarray, shape (K,), float64
        Ascending thresholds of the sweep.
    threshold, tolerance_px : float
        The operating threshold and the matching distance in pixels.
    """

    n_pred: NDArray[np.int64]
    n_truth: NDArray[np.int64]
    tp: NDArray[np.int64]
    tp_truth: NDArray[np.int64]
    n_near_truth: NDArray[np.int64]
    n_pixels: NDArray[np.int64]
    curve_n_pred: NDArray[np.int64]
    curve_tp: NDArray[np.int64]
    curve_tp_truth: NDArray[np.int64]
    thresholds: NDArray[np.float64]
    threshold: float
    tolerance_px: float

    @property
    def n_samples(self) -> int:
        """Number of samples N."""
        return int(self.n_pred.shape[0])

    def take(self, index: ArrayLike) -> SampleCounts:
        """Counts of the samples selected by ``index`` (integer indices or a boolean mask)."""
        idx = np.asarray(index)
        kw = {f.name: getattr(self, f.name) for f in fields(self)}
        for name in _PER_SAMPLE_FIELDS:
            kw[name] = kw[name][idx]
        return SampleCounts(**kw)

    @staticmethod
    def concat(parts: list[SampleCounts]) -> SampleCounts:
        """Join counts of consecutive sample blocks scored with the same settings."""
        if not parts:
            raise InputError("no samples to score")
        first = parts[0]
        kw: dict[str, Any] = {"thresholds": first.thresholds, "threshold": first.threshold,
                              "tolerance_px": first.tolerance_px}
        for name in _PER_SAMPLE_FIELDS:
            kw[name] = np.concatenate([getattr(p, name) for p in parts], axis=0)
        return SampleCounts(**kw)


_PER_SAMPLE_FIELDS = ("n_pred", "n_truth", "tp", "tp_truth", "n_near_truth", "n_pixels",
                      "curve_n_pred", "curve_tp", "curve_tp_truth")


@dataclass(frozen=True)
class Metrics:
    """Precision, recall, F1 and IoU (scalars or arrays of one shape)."""

    precision: Any
    recall: Any
    f1: Any
    iou: Any


def metrics_from_counts(tp: ArrayLike, n_pred: ArrayLike, tp_truth: ArrayLike,
                        n_truth: ArrayLike, zero_division: float = 0.0) -> Metrics:
    """Precision, recall, F1, IoU from (possibly tolerance-matched) counts, elementwise.

    See the module docstring for the formulas and the ``zero_division`` rule.
    """
    tp = np.asarray(tp, dtype=np.float64)
    n_pred = np.asarray(n_pred, dtype=np.float64)
    tp_truth = np.asarray(tp_truth, dtype=np.float64)
    n_truth = np.asarray(n_truth, dtype=np.float64)
    zd = float(zero_division)
    with np.errstate(divide="ignore", invalid="ignore"):
        precision = np.where(n_pred > 0, tp / np.where(n_pred > 0, n_pred, 1.0), zd)
        recall = np.where(n_truth > 0, tp_truth / np.where(n_truth > 0, n_truth, 1.0), zd)
        both = (n_pred > 0) & (n_truth > 0)
        psum = precision + recall
        f1 = np.where(both & (psum > 0), 2.0 * precision * recall / np.where(psum > 0, psum, 1.0),
                      0.0)
        neither = (n_pred == 0) & (n_truth == 0)
        f1 = np.where(neither, zd, f1)
        iou = np.where(neither, zd, f1 / (2.0 - np.where(neither, 0.0, f1)))
    if precision.ndim == 0:
        return Metrics(float(precision), float(recall), float(f1), float(iou))
    return Metrics(precision, recall, f1, iou)


@dataclass(frozen=True)
class ScoreResult:
    """Scores of predictions against labels; see :func:`score`.

    Scalars are pooled over all pixels (micro average); ``per_sample`` holds arrays of shape (N,)
    named ``precision, recall, f1, iou, tp, fp, fn, tp_truth, n_pred, n_truth``.
    ``precision_curve``, ``recall_curve``, ``f1_curve`` have shape (K,) over ``thresholds``.
    """

    precision: float
    recall: float
    f1: float
    iou: float
    tp: int
    fp: int
    fn: int
    tp_truth: int
    n_samples: int
    threshold: float
    tolerance_px: float
    ods_f1: float
    ods_threshold: float
    ois_f1: float
    ap: float
    chance_ap: float
    thresholds: NDArray[np.float64] = field(repr=False)
    precision_curve: NDArray[np.float64] = field(repr=False)
    recall_curve: NDArray[np.float64] = field(repr=False)
    f1_curve: NDArray[np.float64] = field(repr=False)
    per_sample: dict[str, NDArray[Any]] = field(repr=False)

    def summary(self) -> dict[str, float | int]:
        """The scalar scores as a plain dict (JSON-ready)."""
        keys = ("n_samples", "threshold", "tolerance_px", "precision", "recall", "f1", "iou",
                "tp", "fp", "fn", "tp_truth", "ods_f1", "ods_threshold", "ois_f1", "ap",
                "chance_ap")
        return {k: _py(getattr(self, k)) for k in keys}


def _py(v: Any) -> Any:
    if isinstance(v, np.generic):
        return v.item()
    return v


def _as_stack(a: ArrayLike, name: str) -> NDArray[Any]:
    arr = np.asarray(a)
    if arr.ndim == 2:
        arr = arr[None]
    if arr.ndim != 3:
        raise InputError(f"{name}: expected an array of shape (N, H, W) or (H, W), "
                         f"got shape {arr.shape}")
    if arr.size == 0:
        raise InputError(f"{name}: array is empty (shape {arr.shape}); nothing to score")
    return arr


def validate_pred(pred: ArrayLike, name: str = "pred") -> NDArray[np.floating]:
    """Check predictions: finite, in [0, 1]; return a float (N, H, W) array.

    Float32 and float64 input keep their dtype (comparisons with thresholds are made in that
    dtype, as ``pred >= threshold`` does in NumPy); other types become float32.
    """
    arr = _as_stack(pred, name)
    if arr.dtype == bool:
        return arr.astype(np.float32)
    if not (np.issubdtype(arr.dtype, np.number)):
        raise InputError(f"{name}: expected numeric or boolean values, got dtype {arr.dtype}")
    if arr.dtype not in (np.float32, np.float64):
        arr = arr.astype(np.float32)
    bad = ~np.isfinite(arr)
    if bad.any():
        first = int(np.argwhere(bad.reshape(bad.shape[0], -1).any(axis=1))[0, 0])
        raise InputError(f"{name}: {int(bad.sum())} NaN or infinite values "
                         f"(first in sample {first}); predictions must be finite")
    lo, hi = float(arr.min()), float(arr.max())
    if lo < 0.0 or hi > 1.0:
        raise InputError(f"{name}: values must be probabilities in [0, 1] or binary 0/1, "
                         f"got range [{lo:g}, {hi:g}]; apply a sigmoid to logits first")
    return arr


def validate_truth(truth: ArrayLike, name: str = "truth") -> NDArray[np.bool_]:
    """Check labels are binary 0/1 (or boolean); return a boolean (N, H, W) array."""
    arr = _as_stack(truth, name)
    if arr.dtype == bool:
        return arr
    if not np.issubdtype(arr.dtype, np.number):
        raise InputError(f"{name}: expected a binary 0/1 mask, got dtype {arr.dtype}")
    if np.issubdtype(arr.dtype, np.floating) and not np.isfinite(arr).all():
        raise InputError(f"{name}: contains NaN or infinite values; labels must be binary 0/1")
    ok = (arr == 0) | (arr == 1)
    if not ok.all():
        vals = np.unique(arr[~ok])[:5]
        raise InputError(f"{name}: labels must be binary 0/1, found values {vals.tolist()}")
    return arr.astype(bool)


def _check_settings(threshold: float, tolerance_px: float,
                    thresholds: int | ArrayLike) -> tuple[float, float, NDArray[np.float64]]:
    threshold = float(threshold)
    if not (0.0 < threshold <= 1.0):
        raise InputError(f"threshold: must lie in (0, 1], got {threshold!r}")
    tolerance_px = float(tolerance_px)
    if not np.isfinite(tolerance_px) or tolerance_px < 0:
        raise InputError(f"tolerance_px: must be a finite distance >= 0 pixels, "
                         f"got {tolerance_px!r}")
    if np.ndim(thresholds) == 0:
        thr = default_thresholds(thresholds)  # type: ignore[arg-type]
    else:
        thr = np.asarray(thresholds, dtype=np.float64)
        if thr.ndim != 1 or thr.size == 0 or not np.all(np.diff(thr) > 0) \
                or thr[0] <= 0 or thr[-1] > 1:
            raise InputError("thresholds: must be a strictly increasing 1-D array in (0, 1], "
                             f"got {np.asarray(thresholds)!r}")
    return threshold, tolerance_px, thr


def _count_ge(values: NDArray[np.float32], thr: NDArray[np.float64]) -> NDArray[np.int64]:
    """For each threshold t_k, the number of ``values >= t_k``; shape (K,)."""
    # searchsorted(side="right") = number of thresholds <= v, i.e. v >= t_j for j < idx
    idx = np.searchsorted(thr.astype(values.dtype), values, side="right")
    hist = np.bincount(idx, minlength=thr.size + 1)
    ge = np.cumsum(hist[::-1])[::-1]  # ge[j] = #(idx >= j)
    return ge[1:].astype(np.int64)


def count_samples(pred: ArrayLike, truth: ArrayLike, threshold: float = 0.5,
                  tolerance_px: float = 0.0, *,
                  thresholds: int | ArrayLike = 99) -> SampleCounts:
    """Per-sample matched / predicted / labelled pixel counts at ``threshold`` and a sweep.

    Parameters
    ----------
    pred : array_like, shape (N, H, W) or (H, W)
        Fault probabilities in [0, 1] or a binary mask. Must be finite.
    truth : array_like, same shape as ``pred``
        Binary fault labels (0/1 or bool).
    threshold : float
        Operating threshold in (0, 1]; a pixel is predicted a fault when ``pred >= threshold``.
    tolerance_px : float
        Matching distance in pixels (Euclidean), >= 0.
    thresholds : int or array_like
        Number of evenly spaced sweep thresholds, or the ascending thresholds themselves.

    Returns
    -------
    SampleCounts
    """
    p = validate_pred(pred)
    t = validate_truth(truth)
    if p.shape != t.shape:
        raise InputError(f"pred has shape {p.shape} but truth has shape {t.shape}; they must "
                         "match sample for sample and pixel for pixel")
    threshold, tol, thr = _check_settings(threshold, tolerance_px, thresholds)
    n, k = p.shape[0], thr.size
    out = {name: np.zeros(n, np.int64) for name in ("n_pred", "n_truth", "tp", "tp_truth",
                                                     "n_near_truth", "n_pixels")}
    curves = {name: np.zeros((n, k), np.int64) for name in ("curve_n_pred", "curve_tp",
                                                              "curve_tp_truth")}
    foot = disk_footprint(tol) if tol > 0 else None
    for i in range(n):
        pi, ti = p[i], t[i]
        pos = pi >= pi.dtype.type(threshold)
        if tol == 0:
            near_truth = ti
            near_pred = pos
            reach = pi  # the prediction seen from a labelled pixel
        else:
            near_truth = within_tolerance(ti, tol)
            near_pred = within_tolerance(pos, tol)
            reach = ndimage.maximum_filter(pi, footprint=foot, mode="constant", cval=0.0)
        out["n_pred"][i] = int(pos.sum())
        out["n_truth"][i] = int(ti.sum())
        out["tp"][i] = int((pos & near_truth).sum())
        out["tp_truth"][i] = int((ti & near_pred).sum())
        out["n_near_truth"][i] = int(near_truth.sum())
        out["n_pixels"][i] = int(ti.size)
        curves["curve_n_pred"][i] = _count_ge(pi.ravel(), thr)
        curves["curve_tp"][i] = _count_ge(pi[near_truth], thr)
        curves["curve_tp_truth"][i] = _count_ge(reach[ti], thr)
    return SampleCounts(**out, **curves, thresholds=thr, threshold=threshold, tolerance_px=tol)


def _average_precision(precision: NDArray[np.float64], recall: NDArray[np.float64],
                       n_pred: NDArray[np.int64]) -> float:
    """sum (R_k - R_{k-1}) P_k over thresholds from high to low; P = 1 where nothing predicted."""
    p = np.where(n_pred > 0, precision, 1.0)[::-1]
    r = recall[::-1]
    dr = np.diff(np.concatenate([[0.0], r]))
    return float(np.sum(dr * p))


def summarise(counts: SampleCounts, zero_division: float = 0.0) -> ScoreResult:
    """Pool per-sample counts into a :class:`ScoreResult` (micro average plus sweep summaries)."""
    if counts.n_samples == 0:
        raise InputError("no samples to score")
    c = counts
    tp, n_pred = int(c.tp.sum()), int(c.n_pred.sum())
    tp_truth, n_truth = int(c.tp_truth.sum()), int(c.n_truth.sum())
    m = metrics_from_counts(tp, n_pred, tp_truth, n_truth, zero_division)
    ms = metrics_from_counts(c.tp, c.n_pred, c.tp_truth, c.n_truth, zero_division)
    cn, ctp, ctt = c.curve_n_pred.sum(0), c.curve_tp.sum(0), c.curve_tp_truth.sum(0)
    mc = metrics_from_counts(ctp, cn, ctt, n_truth, zero_division)
    best = int(np.argmax(mc.f1))
    per_f1 = metrics_from_counts(c.curve_tp, c.curve_n_pred, c.curve_tp_truth,
                                 c.n_truth[:, None], zero_division).f1
    labelled = c.n_truth > 0
    ois = float(per_f1[labelled].max(axis=1).mean()) if labelled.any() else float("nan")
    ap = _average_precision(mc.precision, mc.recall, cn) if n_truth > 0 else float("nan")
    per_sample = {
        "precision": ms.precision, "recall": ms.recall, "f1": ms.f1, "iou": ms.iou,
        "tp": c.tp.copy(), "fp": c.n_pred - c.tp, "fn": c.n_truth - c.tp_truth,
        "tp_truth": c.tp_truth.copy(), "n_pred": c.n_pred.copy(), "n_truth": c.n_truth.copy(),
    }
    return ScoreResult(
        precision=m.precision, recall=m.recall, f1=m.f1, iou=m.iou,
        tp=tp, fp=n_pred - tp, fn=n_truth - tp_truth, tp_truth=tp_truth,
        n_samples=c.n_samples, threshold=c.threshold, tolerance_px=c.tolerance_px,
        ods_f1=float(mc.f1[best]), ods_threshold=float(c.thresholds[best]), ois_f1=ois, ap=ap,
        chance_ap=float(c.n_near_truth.sum() / c.n_pixels.sum()),
        thresholds=c.thresholds, precision_curve=mc.precision, recall_curve=mc.recall,
        f1_curve=mc.f1, per_sample=per_sample,
    )


def score(pred: ArrayLike, truth: ArrayLike, threshold: float = 0.5, tolerance_px: float = 0.0,
          *, thresholds: int | ArrayLike = 99, zero_division: float = 0.0) -> ScoreResult:
    """Score fault predictions against binary labels, pooled over all pixels.

    Parameters
    ----------
    pred : array_like, shape (N, H, W) or (H, W)
        Fault probabilities in [0, 1] or a binary mask; NaN or infinite values are an error.
    truth : array_like, same shape as ``pred``
        Binary fault labels (0/1 or bool).
    threshold : float, default 0.5
        A pixel is predicted a fault when ``pred >= threshold``.
    tolerance_px : float, default 0
        Matching distance in pixels. 0 is plain pixel overlap; r > 0 counts a predicted pixel
        as correct when a labelled pixel lies within distance r, and a labelled pixel as found
        when a predicted pixel lies within r (distance transforms).
    thresholds : int or array_like, default 99
        Sweep for ODS / OIS / AP: a count of evenly spaced thresholds in (0, 1), or the
        ascending thresholds themselves.
    zero_division : float, default 0.0
        Value of a score whose denominator is zero (scikit-learn's ``zero_division``).

    Returns
    -------
    ScoreResult
        Micro-averaged precision, recall, f1, iou; counts tp, fp, fn, tp_truth; sweep summaries
        ods_f1, ods_threshold, ois_f1, ap; and ``per_sample`` arrays.

    Raises
    ------
    demseis.errors.InputError
        Shapes differ, an array is empty, predictions are not finite or outside [0, 1], labels
        are not binary, or a setting is out of range.

    Examples
    --------
    >>> import numpy as np
    >>> truth = np.zeros((8, 8), np.uint8); truth[:, 4] = 1
    >>> pred = np.zeros((8, 8)); pred[:, 5] = 0.9      # one pixel to the right
    >>> score(pred, truth).f1, score(pred, truth, tolerance_px=1).f1
    (0.0, 1.0)
    """
    return summarise(count_samples(pred, truth, threshold, tolerance_px, thresholds=thresholds),
                     zero_division)


# --------------------------------------------------------------------------------------------
# Scoring against a demseis store, grouped by sample parameters
# --------------------------------------------------------------------------------------------

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
        import zarr  # lazy: ~0.25 s to import, and only Zarr predictions need it

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


# --------------------------------------------------------------------------------------------
# The whole store-level scoring: what ``demseis.score`` and ``demseis score`` do
# --------------------------------------------------------------------------------------------

#: columns of the ``<prefix>.csv`` file :meth:`StoreScore.write` writes
CSV_COLUMNS = ("by", "group", "lo", "hi", "n_samples", "precision", "recall", "f1", "iou", "ap",
               "ods_f1", "chance_ap", "tp", "fp", "fn", "tp_truth")


def json_safe(v: Any) -> Any:
    """``v`` with NumPy scalars as Python ones and non-finite floats as null / "inf" / "-inf"."""
    if isinstance(v, dict):
        return {k: json_safe(x) for k, x in v.items()}
    if isinstance(v, (list, tuple)):
        return [json_safe(x) for x in v]
    if isinstance(v, np.generic):
        v = v.item()
    if isinstance(v, float) and not np.isfinite(v):
        return None if np.isnan(v) else ("inf" if v > 0 else "-inf")
    return v


@dataclass
class StoreScore:
    """Scores of predictions against a store's fault labels (see :func:`score_store`).

    Attributes
    ----------
    overall : ScoreResult
        Pooled over every scored sample (``overall.per_sample`` has one row per sample).
    rows : list of dict
        One row per group (the first is ``by == "all"``), see :func:`group_rows`.
    sample_index : ndarray (M,), int64
        The store index of each scored sample.
    params : dict[str, ndarray]
        The store's per-sample parameters of the scored samples, each (M,).
    counts : SampleCounts
    """

    overall: ScoreResult
    rows: list[dict[str, Any]]
    sample_index: NDArray[np.int64]
    params: dict[str, NDArray[Any]]
    counts: SampleCounts

    def table(self) -> str:
        """The aligned text table of ``rows``."""
        return format_table(self.rows)

    def summary_line(self) -> str:
        """ODS / OIS / AP and the chance level in one line."""
        o = self.overall
        return (f"ODS F1 {o.ods_f1:.3f} at threshold {o.ods_threshold:.2f}   "
                f"OIS F1 {o.ois_f1:.3f}   AP {o.ap:.3f}   "
                f"chance AP (random scores) {o.chance_ap:.4f}")

    def per_sample_rows(self) -> list[dict[str, Any]]:
        """One JSON-safe dict per scored sample: its store index, parameters and scores."""
        ps = self.overall.per_sample
        names = sorted(self.params)
        out = []
        for j in range(self.counts.n_samples):
            row: dict[str, Any] = {"sample": int(self.sample_index[j])}
            row.update({k: self.params[k][j] for k in names})
            row.update({k: ps[k][j] for k in ("precision", "recall", "f1", "iou", "tp", "fp",
                                              "fn", "tp_truth", "n_pred", "n_truth")})
            out.append(json_safe(row))
        return out

    def write(self, prefix: str, *, per_sample: bool = False,
              meta: dict[str, Any] | None = None) -> list[str]:
        """Write ``<prefix>.csv`` and ``<prefix>.json`` (and ``<prefix>.samples.csv`` with
        ``per_sample``); returns the paths. ``meta`` goes into the JSON report."""
        os.makedirs(os.path.dirname(os.path.abspath(prefix)), exist_ok=True)
        with open(prefix + ".csv", "w", newline="") as fh:
            w = csv.DictWriter(fh, fieldnames=list(CSV_COLUMNS))
            w.writeheader()
            for r in self.rows:
                w.writerow({k: ("" if r[k] is None else r[k]) for k in CSV_COLUMNS})
        report: dict[str, Any] = {**(meta or {}), "overall": self.overall.summary(),
                                  "groups": self.rows}
        written = [prefix + ".csv", prefix + ".json"]
        if per_sample:
            sample_rows = self.per_sample_rows()
            with open(prefix + ".samples.csv", "w", newline="") as fh:
                w = csv.DictWriter(fh, fieldnames=list(sample_rows[0]))
                w.writeheader()
                w.writerows(sample_rows)
            report["per_sample"] = sample_rows
            written.append(prefix + ".samples.csv")
        with open(prefix + ".json", "w") as fh:
            json.dump(json_safe(report), fh, indent=1)
        return written


def score_store(pred: Any, store: Any, *, indices: ArrayLike | None = None,
                threshold: float = 0.5, tolerance_px: float = 0.0, by: tuple[str, ...] = (),
                bins: int = 4, thresholds: int | ArrayLike = 99,
                progress: bool = False) -> StoreScore:
    """Score fault predictions against the ``fault`` labels of a demseis store.

    Parameters
    ----------
    pred : array-like (N_pred, H, W) or str
        Probabilities in [0, 1], or the path of a ``.npy`` file / Zarr array of them.
    store : str, Path or object with a ``path`` attribute (e.g. :class:`demseis.Store`)
    indices : array_like of int, shape (N_pred,), optional
        Store sample of each prediction row (default: row i is sample i, all samples).
    threshold, tolerance_px, thresholds : see :func:`score`.
    by : names of per-sample parameters to group by (e.g. ``("freq_hz", "snr_db")``).
    bins : bins of parameters with many distinct values.

    Returns
    -------
    StoreScore
    """
    truth = open_truth(str(getattr(store, "path", store)))
    for name in by:
        if name not in truth.params:
            raise InputError(f"--by {name!r}: the store has per-sample parameters "
                             f"{sorted(truth.params)}")
    if isinstance(pred, (str, bytes)) or hasattr(pred, "__fspath__"):
        pred = load_predictions(str(pred))
    elif not hasattr(pred, "shape"):
        pred = np.asarray(pred)
    counts, sample = score_store_counts(pred, truth, indices=indices, threshold=threshold,
                                        tolerance_px=tolerance_px, thresholds=thresholds,
                                        progress=progress)
    params = truth.params.take(sample)  # without building (N,) columns of a huge store
    return StoreScore(overall=summarise(counts), rows=group_rows(counts, params, list(by), bins=bins),
                      sample_index=sample, params=params, counts=counts)


def score_mask(pred: Any, mask: Any, *, threshold: float = 0.5, tolerance_px: float = 0.0,
               thresholds: int | ArrayLike = 99, resize: bool = False,
               progress: bool = False) -> StoreScore:
    """Score fault predictions against a hand-picked mask, as :func:`score_store` scores them
    against a store (the same counts, sweep and report, without per-sample parameters).

    Parameters
    ----------
    pred : array-like (H, W) or (N, H, W), or a path
        Probabilities in [0, 1]: an array, or a ``.npy``, Zarr or SEG-Y file
        (:func:`load_predictions`).
    mask : array-like (H, W) or (N, H, W), or a path
        The picked faults: nonzero on a fault. A path is read by
        :func:`demseis.evaluation.fieldio.read_masks` (``.npy``, ``.png`` or SEG-Y; its rules
        say which pixels of a PNG are faults).
    threshold, tolerance_px, thresholds : see :func:`score`.
    resize : resample the predictions onto the mask's grid
        (:func:`demseis.evaluation.fieldio.resize_sections`, bilinear) when their (H, W)
        differ; without it a different shape is an error naming both. The number of sections
        N must match either way. ``tolerance_px`` is then in mask pixels.
    progress : accepted for the same call as :func:`score_store`; a mask is scored at once.

    Returns
    -------
    StoreScore
        One row per section; ``rows`` holds only the overall group, ``params`` is empty.
    """
    del progress  # a few sections: no bar
    if isinstance(mask, (str, bytes)) or hasattr(mask, "__fspath__"):
        truth = read_masks(os.fsdecode(mask))
    else:
        truth = as_masks(mask)
    if isinstance(pred, (str, bytes)) or hasattr(pred, "__fspath__"):
        pred = load_predictions(os.fsdecode(pred))
    p = np.asarray(pred)
    if p.ndim == 2:
        p = p[None]
    if p.ndim != 3 or p.size == 0:
        raise InputError(f"predictions: expected shape (H, W) or (N, H, W), got {p.shape}")
    if p.shape[0] != truth.shape[0] or (p.shape[1:] != truth.shape[1:] and not resize):
        hint = "" if p.shape[0] != truth.shape[0] else \
            "; pass --resize (resize=True) to resample the predictions onto the mask's grid"
        raise InputError(f"predictions have shape {_shape(p)} but the mask has shape "
                         f"{_shape(truth)}{hint}")
    if p.shape[1:] != truth.shape[1:]:
        validate_pred(p, "predictions")  # before resampling: a logit is named as it is
        p = resize_sections(p, truth.shape[1:])
    counts = count_samples(p, truth, threshold, tolerance_px, thresholds=thresholds)
    return StoreScore(overall=summarise(counts), rows=group_rows(counts, {}, []),
                      sample_index=np.arange(counts.n_samples, dtype=np.int64), params={},
                      counts=counts)


def _shape(a: NDArray[Any]) -> tuple[int, ...]:
    """(H, W) for one section, (N, H, W) for several: the shape as the user gave it."""
    return tuple(int(s) for s in (a.shape[1:] if a.shape[0] == 1 else a.shape))
