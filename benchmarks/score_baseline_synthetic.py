"""Quality of the baselines (semblance, dip) on synthetic Ricker sections by SNR; one JSON line.

Sections (96 x 96 samples): sparse random reflectivity convolved with a 25 Hz Ricker at 4 ms,
dipping 0.1 samples/trace, cut by a planar 70-degree normal fault with a 6-sample throw; truth is
the pixels within 1 px of the fault trace (demseis_dev.toys.faulted_section).
White noise is added at SNR = 20 log10(rms signal / rms noise). Reports micro precision,
recall, F1 at the default threshold 0.5, ODS F1 and AP at tolerance 0 and 2 px, over 16
sections per SNR, plus the chance AP (the fault pixel fraction).
Usage: ``python benchmarks/score_baseline_synthetic.py``.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # demseis_dev: the checkout's

import numpy as np

from demseis.evaluation.baseline import baseline_fault_probability
from demseis.evaluation.scoring import score


def faulted_section(seed: int, snr_db: float, nz: int = 96, nx: int = 96):
    from demseis_dev.toys import faulted_section as make

    sec, truth = make(nz=nz, nx=nx, seed=seed)
    if np.isfinite(snr_db):
        rng = np.random.default_rng(1000 + seed)
        rms = np.sqrt(np.mean(sec.astype(np.float64) ** 2))
        sec = sec + rng.normal(0, rms * 10 ** (-snr_db / 20), sec.shape).astype(np.float32)
    return sec, truth


def main() -> None:
    out = {"benchmark": "score_baseline_synthetic", "n_sections": 16, "rows": []}
    for snr in (np.inf, 20.0, 10.0, 5.0, 0.0):
        secs, truths = zip(*(faulted_section(s, snr) for s in range(16)))
        truth = np.stack(truths)
        for method in ("semblance", "dip"):
            prob = baseline_fault_probability(np.stack(secs), method)
            row = {"method": method, "snr_db": "inf" if np.isinf(snr) else snr}
            for tol in (0, 2):
                r = score(prob, truth, tolerance_px=tol)
                row[f"tol{tol}"] = {k: round(getattr(r, k), 3)
                                    for k in ("precision", "recall", "f1", "ods_f1", "ap",
                                              "chance_ap")}
            out["rows"].append(row)
    print(json.dumps(out))


if __name__ == "__main__":
    main()
