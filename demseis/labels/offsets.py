"""Reflector offsets the section shows: the jump of the rock's reference elevation across traces.

A reflector is a surface of constant reference elevation ``y0`` (where the rock was before
deformation, :attr:`demseis.generator.engines.State.reference`). Inside rock that moved
together ``y0`` varies smoothly from trace to trace; across a slip surface it jumps by the
throw. So the offset a section shows between traces ``j`` and ``j + 1`` at a row is the jump of
``y0`` beyond the row's local trend, in output samples:

    jump(j)   = y0[:, j + 1 + h] - y0[:, j - h]          (a window of ``width = 2 h + 1`` pairs)
    trend(j)  = median of the per-pair jumps of ``trend_pairs`` pairs beyond the window on
                each side, times the window's pair count
    offset(j) = |jump(j) - trend(j)| * samples_per_m

``samples_per_m`` is ``2 / (vp dt)`` on a two-way-time axis (``vp`` the interval velocity of the
cell) and ``1 / cell`` in depth. A fault zone a few traces wide offsets the reflectors over
several pairs, hence the window. A pixel's offset is the largest offset of the pairs within one
trace of it (:func:`pixel_offsets`), so a label drawn a trace off its slip surface still reads
the offset.

The picked fault target (:mod:`demseis.labels.picks`) takes this as the throw of its pixels
when ``[labels] throw_from = "offset"``: a fault is drawn only where the reflectors are offset
by at least ``min_throw_samples``, measured on the section's own grid instead of from the
mechanical slip (which a fault zone spreads over drag and many strands).
"""

from __future__ import annotations

import numpy as np
from scipy.ndimage import binary_closing, binary_dilation, label

from demseis.labels.picks import PICKED


def pair_jumps(y0_m: np.ndarray, width: int = 3, trend_pairs: int = 4) -> np.ndarray:
    """Signed jump of ``y0_m`` (m) across each pair of neighbouring traces beyond the row's
    trend (see the module docstring), (rows, ntr - 1); NaN where the window touches a pixel
    without rock. Positive: the rock right of the pair came from higher up (that side moved
    down relative to the left).

    Parameters
    ----------
    y0_m : (rows, ntr) reference elevation (m) of the rock at each pixel; NaN where there is
        no rock.
    width : odd number of neighbouring trace pairs the jump is taken over, >= 1.
    trend_pairs : pairs on each side beyond the window whose median jump is the trend.
    """
    y = np.asarray(y0_m, dtype=np.float64)
    if y.ndim != 2 or y.shape[1] < 2:
        raise ValueError(f"y0_m must be (rows, traces >= 2), got shape {y.shape}")
    if width < 1 or width % 2 != 1:
        raise ValueError(f"width must be an odd number >= 1, got {width}")
    d = np.diff(y, axis=1)
    nrow, npair = d.shape
    h = width // 2
    out = np.full((nrow, npair), np.nan)
    for j in range(npair):
        lo, hi = max(0, j - h), min(npair, j + h + 1)
        jump = d[:, lo:hi].sum(axis=1)
        side = np.concatenate([d[:, max(0, lo - trend_pairs):lo], d[:, hi:hi + trend_pairs]],
                              axis=1)
        # a row without rock beside the window has no trend to remove
        trend = _row_nanmedian(side) if side.shape[1] else np.zeros(nrow)
        out[:, j] = jump - trend * (hi - lo)
    return out


def pair_offsets(y0_m: np.ndarray, samples_per_m: np.ndarray | float, width: int = 3,
                 trend_pairs: int = 4) -> np.ndarray:
    """Offsets between neighbouring traces, in output samples: ``|pair_jumps|`` times the
    mean ``samples_per_m`` (scalar or (rows, ntr)) of the pair's two pixels; (rows, ntr - 1),
    NaN where there is no rock (see :func:`pair_jumps`)."""
    y = np.asarray(y0_m, dtype=np.float64)
    return jumps_to_samples(pair_jumps(y, width, trend_pairs), samples_per_m, y.shape)


def jumps_to_samples(jumps_m: np.ndarray, samples_per_m: np.ndarray | float,
                     shape: tuple[int, int]) -> np.ndarray:
    """``|jumps_m|`` (rows, npair) in output samples: times the mean ``samples_per_m`` (scalar
    or per pixel, of ``shape`` = (rows, npair + 1)) of each pair's two pixels."""
    sc = np.broadcast_to(np.asarray(samples_per_m, dtype=np.float64), shape)
    return np.abs(jumps_m) * 0.5 * (sc[:, 1:] + sc[:, :-1])


def _row_nanmedian(a: np.ndarray) -> np.ndarray:
    """Median of each row over its finite values; 0 for a row without any."""
    a = np.sort(np.where(np.isfinite(a), a, np.inf), axis=1)
    n = np.isfinite(a).sum(axis=1)
    rows = np.arange(a.shape[0])
    lo = a[rows, np.maximum((n - 1) // 2, 0)]
    hi = a[rows, np.maximum(n // 2, 0)]
    return np.where(n > 0, 0.5 * (lo + hi), 0.0)


def pixel_offsets(y0_m: np.ndarray, samples_per_m: np.ndarray | float, width: int = 3,
                  trend_pairs: int = 4) -> np.ndarray:
    """(rows, ntr) offset of each pixel: the largest :func:`pair_offsets` of the pairs within
    one trace of it (pairs (j-2, j-1) to (j+1, j+2)); 0 where none is defined (no rock)."""
    return window_max(pair_offsets(y0_m, samples_per_m, width, trend_pairs))


def window_max(pair: np.ndarray) -> np.ndarray:
    """(rows, npair + 1) per pixel: the largest of the pair values (rows, npair) within one
    trace of it (pairs (j-2, j-1) to (j+1, j+2)); NaN read as 0."""
    p = np.nan_to_num(np.asarray(pair, dtype=np.float64), nan=0.0)
    rows, npair = p.shape
    padded = np.zeros((rows, npair + 4))
    padded[:, 2:-2] = p
    # pixel j touches pairs j-1 and j; one trace either side adds pairs j-2 and j+1
    return np.max(np.stack([padded[:, k:k + npair + 1] for k in range(4)]), axis=0)


def offset_faults(maps: dict[str, np.ndarray], jump_m: np.ndarray, samples_per_m: np.ndarray,
                  m_per_trace: float, m_per_row: np.ndarray, *, min_samples: float,
                  min_rows: int, keep_away_px: int = 2) -> dict[str, np.ndarray]:
    """``maps`` with the visible offsets that no fault label explains added as faults.

    A pixel is on an offset ridge where its pair's offset (``|jump_m| * samples_per_m``) is
    at least ``min_samples`` and no smaller than its row neighbours'. Ridge pixels within
    ``keep_away_px`` of a labelled fault are left to that fault. The rest are linked into
    8-connected pieces (gaps of one row bridged); a piece spanning at least ``min_rows`` rows
    becomes a new fault instance (``fault_id`` after the existing ones, by decreasing size)
    with ``fault = 1``, its dip from a line fitted to its pixels (through ``m_per_trace`` and
    the per-pixel ``m_per_row``), its throw the mean |jump| (m), ``slip_m = throw / sin(dip)``,
    and ``sense`` normal where the side it dips towards moved down, else reverse.

    Parameters
    ----------
    maps : label maps on the output grid (``fault``, ``fault_id``, ``slip_m``, ``dip_deg``,
        ``sense`` at least), (H, W) each; not modified (the returned dict holds new arrays
        for those five and ``maps``' own arrays for the others).
    jump_m : (H, W) signed :func:`pair_jumps` of the pair (j, j + 1) at column j (the last
        column 0), on the output grid.
    samples_per_m, m_per_row : (H, W) output samples per metre of throw and metres of depth
        per row.
    """
    jump = np.nan_to_num(np.asarray(jump_m, dtype=np.float64), nan=0.0)
    off = np.abs(jump) * samples_per_m
    left = np.pad(off, ((0, 0), (1, 0)))[:, :-1]
    right = np.pad(off, ((0, 0), (0, 1)))[:, 1:]
    ridge = (off >= min_samples) & (off >= left) & (off >= right)
    fault = np.asarray(maps["fault"]) > 0
    if keep_away_px > 0 and fault.any():
        near = binary_dilation(fault, np.ones((2 * keep_away_px + 1,) * 2, dtype=bool))
        ridge &= ~near
    out = {k: (np.array(v, copy=True) if k in PICKED else v) for k, v in maps.items()}
    if not ridge.any():
        return out
    linked = binary_closing(ridge, np.ones((3, 1), dtype=bool)) | ridge
    lab, n = label(linked, np.ones((3, 3), dtype=bool))
    pieces = []
    for k in range(1, n + 1):
        rr, cc = np.nonzero((lab == k) & ridge)
        if rr.size and rr.max() - rr.min() + 1 >= min_rows:
            pieces.append((rr, cc))
    pieces.sort(key=lambda p: -p[0].size)
    next_id = int(np.asarray(maps["fault_id"]).max()) + 1
    z = np.cumsum(np.concatenate([[0.0], np.median(m_per_row, axis=1)]))[:-1]  # row depths (m)
    for rr, cc in pieces:
        zz, xx = z[rr], cc * m_per_trace
        slope = np.polyfit(zz, xx, 1)[0] if np.ptp(zz) > 0 else 0.0     # dx/dz
        dip = float(np.degrees(np.arctan2(1.0, abs(slope))))
        throw = float(np.mean(np.abs(jump[rr, cc])))
        down_right = float(np.mean(jump[rr, cc])) > 0
        normal = (slope >= 0) == down_right
        out["fault"][rr, cc] = 1
        out["fault_id"][rr, cc] = next_id
        out["slip_m"][rr, cc] = throw / max(np.sin(np.radians(dip)), 1e-6)
        out["dip_deg"][rr, cc] = dip
        out["sense"][rr, cc] = 1 if normal else 2
        next_id += 1
    return out


#: ``fault_uncertain`` classes (:func:`offset_disagreement`)
LABEL_NOT_SHOWN = 1
OFFSET_NOT_LABELLED = 2


def offset_ridge(pair: np.ndarray, min_samples: float) -> np.ndarray:
    """(rows, npair + 1) bool: the pixel of each pair (column j for the pair (j, j + 1)) whose
    offset (``pair``, output samples, NaN read as 0) is at least ``min_samples`` and no
    smaller than its row neighbours', the centre of a step rather than the fringe a window
    spreads it over (as :func:`offset_faults` finds steps)."""
    off = np.pad(np.nan_to_num(np.asarray(pair, dtype=np.float64), nan=0.0), ((0, 0), (0, 1)))
    left = np.pad(off, ((0, 0), (1, 0)))[:, :-1]
    right = np.pad(off, ((0, 0), (0, 1)))[:, 1:]
    return (off >= min_samples) & (off >= left) & (off >= right)


def offset_disagreement(fault: np.ndarray, pair: np.ndarray, *, min_samples: float,
                        near_px: int = 2) -> np.ndarray:
    """Where a fault label and the reflectors' visible offsets disagree, (H, W) uint8.

    - ``LABEL_NOT_SHOWN`` (1): a labelled pixel with no pixel within ``near_px`` of it whose
      offset (:func:`window_max` of ``pair``: the pairs within one trace) is at least
      ``min_samples``: the label marks slip that the section does not show as a step of the
      reflectors;
    - ``OFFSET_NOT_LABELLED`` (2): the centre of a step of at least ``min_samples``
      (:func:`offset_ridge`) with no labelled pixel within ``near_px``: a step the section
      shows that no label marks;
    - 0 elsewhere: the label and the section agree (a labelled step, or neither).

    ``near_px`` is a square neighbourhood (Chebyshev distance), as the scoring tolerance.

    Parameters
    ----------
    fault : (H, W) fault label (non-zero on a fault).
    pair : (H, W - 1) offset between the traces j and j + 1 in output samples
        (:func:`jumps_to_samples` of the jumps; NaN or 0 where there is no rock).
    """
    lab = np.asarray(fault) > 0
    p = np.asarray(pair, dtype=np.float64)
    if p.shape != (lab.shape[0], lab.shape[1] - 1):
        raise ValueError(f"pair has shape {p.shape}; a fault label of shape {lab.shape} needs "
                         f"({lab.shape[0]}, {lab.shape[1] - 1})")
    shown = window_max(p) >= float(min_samples)
    steps = offset_ridge(p, float(min_samples))
    out = np.zeros(lab.shape, dtype=np.uint8)
    if near_px > 0:
        square = np.ones((2 * near_px + 1,) * 2, dtype=bool)
        near_shown = binary_dilation(shown, square)
        near_lab = binary_dilation(lab, square)
    else:
        near_shown, near_lab = shown, lab
    out[lab & ~near_shown] = LABEL_NOT_SHOWN
    out[steps & ~near_lab] = OFFSET_NOT_LABELLED
    return out


__all__ = ["LABEL_NOT_SHOWN", "OFFSET_NOT_LABELLED", "jumps_to_samples", "offset_disagreement",
           "offset_faults", "offset_ridge", "pair_jumps", "pair_offsets", "pixel_offsets",
           "window_max"]
