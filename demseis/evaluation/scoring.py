"""Benchmark scoring of fault predictions: precision, recall, F1 and IoU.

This module holds the metrics on arrays; :mod:`demseis.evaluation.grouping` scores a store's
samples and groups them by parameter, :mod:`demseis.evaluation.store_scoring` is the whole
store- or mask-level scoring that ``demseis score`` runs.

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

from dataclasses import dataclass, field, fields
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy import ndimage

from demseis.errors import InputError

__all__ = [
    "SampleCounts",
    "ScoreResult",
    "count_samples",
    "default_thresholds",
    "disk_footprint",
    "within_tolerance",
    "metrics_from_counts",
    "score",
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
