"""Speed of scoring and of the semblance baseline; prints one JSON line.

Scores 64 random (256, 256) sections at tolerance 0 and 2 px with the 99-threshold sweep, and
runs both baselines on 8 sections, each repeated; medians of the repeats, after a warm-up call
(Numba compile). Usage: ``python benchmarks/score_speed.py``.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # demseis_dev: the checkout's

import numpy as np

from demseis.evaluation.baseline import dip_fault_probability, semblance_fault_probability
from demseis.evaluation.scoring import score
from demseis_dev.bench import median_ms


def _seconds(fn, repeats: int) -> float:
    """Median wall-clock seconds of ``fn()`` over ``repeats`` calls."""
    return median_ms(fn, repeats)[0] / 1e3


def main() -> None:
    rng = np.random.default_rng(0)
    n, h, w = 64, 256, 256
    truth = rng.random((n, h, w)) < 0.02
    pred = np.clip(rng.random((n, h, w)) * 0.6 + 0.4 * truth, 0, 1).astype(np.float32)
    sections = rng.normal(size=(8, h, w)).astype(np.float32)
    semblance_fault_probability(sections[:1, :16, :16])  # compile
    t0 = _seconds(lambda: score(pred, truth), 3)
    t2 = _seconds(lambda: score(pred, truth, tolerance_px=2), 3)
    tb = _seconds(lambda: semblance_fault_probability(sections), 3)
    td = _seconds(lambda: dip_fault_probability(sections), 3)
    print(json.dumps({
        "benchmark": "score_speed", "section_shape": [h, w],
        "score_tol0_ms_per_section": round(1e3 * t0 / n, 3),
        "score_tol2_ms_per_section": round(1e3 * t2 / n, 3),
        "baseline_semblance_ms_per_section": round(1e3 * tb / len(sections), 2),
        "baseline_dip_ms_per_section": round(1e3 * td / len(sections), 2),
        "repeats": 3, "statistic": "median",
    }))


if __name__ == "__main__":
    main()
