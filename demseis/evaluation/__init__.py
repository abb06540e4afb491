"""demseis.evaluation: scoring fault predictions against a store, and a no-learning baseline.

Public API (see docs/scoring.md)::

    result = score(pred, truth, threshold=0.5, tolerance_px=0)   # precision, recall, f1, iou, AP
    prob = dip_fault_probability(section)                        # reference detector, no learning

Store reads go through :mod:`demseis.datasets.read`; this package never opens a store itself.
"""

from demseis.evaluation.baseline import (SemblanceBaseline, baseline_fault_probability,
                                         dip_fault_probability, semblance_fault_probability)
from demseis.evaluation.scoring import SampleCounts, ScoreResult, count_samples, score, summarise

__all__ = [
    "SampleCounts",
    "ScoreResult",
    "SemblanceBaseline",
    "baseline_fault_probability",
    "count_samples",
    "dip_fault_probability",
    "score",
    "semblance_fault_probability",
    "summarise",
]
