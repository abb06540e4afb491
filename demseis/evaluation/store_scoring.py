"""The whole store- or mask-level scoring: what ``demseis.score`` and ``demseis score`` do
(:class:`StoreScore`: the overall scores, the rows per parameter, the CSV and JSON files)."""

from __future__ import annotations

import csv
import json
import os
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from demseis.datasets.read import open_truth
from demseis.errors import InputError
from demseis.evaluation.fieldio import as_masks, read_masks, resize_sections
from demseis.evaluation.grouping import (format_table, group_rows, load_predictions,
                                         score_store_counts)
from demseis.evaluation.scoring import (SampleCounts, ScoreResult, count_samples, summarise,
                                        validate_pred)

__all__ = ["CSV_COLUMNS", "StoreScore", "json_safe", "score_mask", "score_store"]

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
    threshold, tolerance_px, thresholds : see :func:`demseis.evaluation.scoring.score`.
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
    threshold, tolerance_px, thresholds : see :func:`demseis.evaluation.scoring.score`.
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
