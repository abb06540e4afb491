"""How far the reflectors step at the faults of a training store and of hand-picked field
sections, measured the same way on both: the seismic itself, not the labels' slip.

At every fault pixel (row t, trace j; field masks thinned to lines, as the field benchmark
scores them) the traces ``j - side`` and ``j + side`` are aligned over rows ``t +- window``
(:func:`demseis.evaluation.realism.best_lag`, up to ``--max-lag`` samples); a pixel counts
only where neither trace holds a fault label in the window. The same at random pixels
farther than that from any label (300 per store sample, 2000 per field section) gives the
lags the section shows where nobody picked a fault (dipping beds, noise). One JSON line per source: the
pixels, the shares of fault pixels and of background pixels with ``|lag|`` of at least 1, 2
and 3 samples, and the median fault lag.

    PYTHONPATH=$PWD python benchmarks/fault_lags.py --store S.zarr [--samples 60]
    PYTHONPATH=$PWD python benchmarks/fault_lags.py --field-dir DIR   # seismic_K.* / mask_K.*
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np
import zarr
from scipy.ndimage import binary_dilation

from demseis.evaluation.realism import best_lag

sys.path.insert(0, str(Path(__file__).resolve().parent))

from _field_common import field_dir_pairs, read_pair  # noqa: E402  (benchmarks/ is on sys.path)


def section_lags(section: np.ndarray, fault: np.ndarray, rng: np.random.Generator, *,
                 side: int = 3, window: int = 12, max_lag: int = 8, step: int = 1,
                 background: int = 300) -> tuple[np.ndarray, np.ndarray]:
    """(|lag| at fault pixels, |lag| at background pixels) of one section (module docstring)."""
    s = np.asarray(section, dtype=np.float64)
    f = np.asarray(fault) > 0
    h, w = s.shape

    def lag_at(t: int, j: int) -> int | None:
        lo, hi = t - window, t + window + 1
        if j - side < 0 or j + side >= w or lo < 0 or hi > h:
            return None
        if f[lo:hi, j - side].any() or f[lo:hi, j + side].any():
            return None
        a, b = s[lo:hi, j - side], s[lo:hi, j + side]
        if not (np.any(a) and np.any(b)):
            return None
        return abs(best_lag(a, b, max_lag))

    at_fault = [lag_at(t, j) for t, j in list(zip(*np.nonzero(f)))[::step]]
    far = ~binary_dilation(f, np.ones((2 * window + 1, 2 * side + 3), bool)) if f.any() \
        else np.ones(f.shape, bool)
    rows, cols = np.nonzero(far)
    pick = rng.choice(rows.size, min(background, rows.size), replace=False) if rows.size else []
    at_bg = [lag_at(int(rows[k]), int(cols[k])) for k in pick]
    return (np.array([v for v in at_fault if v is not None], dtype=float),
            np.array([v for v in at_bg if v is not None], dtype=float))


def summary(name: str, fault_lags: list[np.ndarray], bg_lags: list[np.ndarray]) -> dict:
    """The JSON line of one source from its sections' lags."""
    f = np.concatenate(fault_lags) if fault_lags else np.zeros(0)
    b = np.concatenate(bg_lags) if bg_lags else np.zeros(0)

    def shares(a: np.ndarray) -> list[float | None]:
        return [round(float(np.mean(a >= k)), 3) if a.size else None for k in (1, 2, 3)]

    return {"benchmark": "fault_lags", "source": name, "fault_pixels": int(f.size),
            "fault_lag_at_least_1_2_3": shares(f), "median_fault_lag":
            float(np.median(f)) if f.size else None, "background_pixels": int(b.size),
            "background_lag_at_least_1_2_3": shares(b)}


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--store", action="append", default=[], help="a demseis store")
    ap.add_argument("--field-dir", action="append", default=[],
                    help="seismic_<key>.* / mask_<key>.* pairs (.npy, .png, .sgy)")
    ap.add_argument("--samples", type=int, default=60, help="store samples read (evenly)")
    ap.add_argument("--side", type=int, default=3, help="traces either side of the pixel")
    ap.add_argument("--window", type=int, default=12, help="rows either side aligned")
    ap.add_argument("--max-lag", type=int, default=8, help="largest lag searched, samples")
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args(argv)
    opts = dict(side=args.side, window=args.window, max_lag=args.max_lag)
    for path in args.store:
        rng = np.random.default_rng(args.seed)
        root = zarr.open_group(path, mode="r")
        n = root["seismic"].shape[0]
        fl, bl = [], []
        for i in np.unique(np.linspace(0, n - 1, min(args.samples, n)).round().astype(int)):
            fault = np.asarray(root["fault"][i])
            if fault.any():
                a, b = section_lags(np.asarray(root["seismic"][i]), fault, rng, **opts)
                fl.append(a)
                bl.append(b)
        print(json.dumps(summary(Path(path).name, fl, bl)))
    for d in args.field_dir:
        rng = np.random.default_rng(args.seed)
        fl, bl = [], []
        for _key, sec, mask in field_dir_pairs(d):
            s, m = read_pair(sec, mask, thin_lines=True)
            a, b = section_lags(s, m, rng, background=2000, **opts)
            fl.append(a)
            bl.append(b)
        print(json.dumps(summary(Path(d).expanduser().name, fl, bl)))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
