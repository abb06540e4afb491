"""Slip: the displacement jump across a line of cells, and the crest cells that slip (step 2
of :mod:`demseis.labels.traces`).

Displacements are measured from each element's first appearance
(:func:`displacement_history`). Across a crest cell, the displacement is read k cells away on
both sides along the normal (Numba kernel ``jump_across``); the largest |u(+k) - u(-k)|
is the jump (:func:`displacement_jump`), and the crest cells whose jump, averaged along the
crest, reaches ``min_slip_m`` are traces (:func:`slipping_cells`).
"""

from __future__ import annotations

import numpy as np

from demseis.labels import _kernels
from demseis.labels.config import LabelConfig
from demseis.labels.direction import along_trace_mean, dip_of, local_direction
from demseis.labels.masks import remove_small_components


def displacement_history(snapshots) -> list[np.ndarray]:
    """Displacement (m, x right, y up) of every element since its first appearance.

    Parameters
    ----------
    snapshots : sequence of :class:`demseis.types.Snapshot` in time order, one id space.

    Returns
    -------
    list of (displacement (n_k, 2) float64, birth (n_k,) int64) aligned with each snapshot's
    elements; an element's reference position is where it first appears (``birth``: the
    position in ``snapshots`` of that snapshot; 0 for the original pack).
    """
    first_ids = np.empty(0, dtype=np.int64)
    first_xy = np.empty((0, 2), dtype=np.float64)
    first_k = np.empty(0, dtype=np.int64)
    out = []
    for k, s in enumerate(snapshots):
        ids = np.asarray(s.ids, dtype=np.int64)
        xy = np.asarray(s.xy, dtype=np.float64)
        pos = np.searchsorted(first_ids, ids)
        known = pos < first_ids.shape[0]
        known[known] = first_ids[pos[known]] == ids[known]
        ref = xy.copy()
        ref[known] = first_xy[pos[known]]
        birth = np.full(ids.shape[0], k, dtype=np.int64)
        birth[known] = first_k[pos[known]]
        out.append((xy - ref, birth))
        if (~known).any():
            all_ids = np.concatenate([first_ids, ids[~known]])
            all_xy = np.concatenate([first_xy, xy[~known]])
            all_k = np.concatenate([first_k, birth[~known]])
            order = np.argsort(all_ids, kind="stable")
            first_ids, first_xy, first_k = all_ids[order], all_xy[order], all_k[order]
    return out


def displacement_jump(cells: np.ndarray, t_r: np.ndarray, t_c: np.ndarray, disp_x_m: np.ndarray,
          disp_y_m: np.ndarray, rock: np.ndarray, k_max: int,
          cohort: np.ndarray | None = None, k_min: int = 2) -> np.ndarray:
    """(nz, nx, 3) |jump|, jump row / col components at ``cells`` (NaN elsewhere), for the
    offsets k = k_min..k_max cells along the normal.

    The normal points to the upper side (row decreasing; column increasing for a vertical
    trace), so the jump is u(upper side) - u(lower side).
    """
    rows, cols = np.nonzero(cells)
    n_r, n_c = t_c[rows, cols].copy(), -t_r[rows, cols].copy()
    flip = (n_r > 0) | ((n_r == 0) & (n_c < 0))
    n_r[flip] *= -1.0
    n_c[flip] *= -1.0
    u_row = np.ascontiguousarray(-np.asarray(disp_y_m, dtype=np.float64))
    u_col = np.ascontiguousarray(np.asarray(disp_x_m, dtype=np.float64))
    res = np.empty((rows.size, 3))
    coh = np.zeros(cells.shape, np.int64) if cohort is None else cohort.astype(np.int64)
    _kernels.jump_across(u_row, u_col, np.ascontiguousarray(rock), np.ascontiguousarray(coh),
                         rows.astype(np.int64),
                         cols.astype(np.int64), n_r, n_c, int(k_min), max(int(k_max), int(k_min)), res)
    out = np.full((*cells.shape, 3), np.nan)
    out[rows, cols] = res
    return out


def slipping_cells(crest: np.ndarray, disp_x_m: np.ndarray, disp_y_m: np.ndarray, rock: np.ndarray,
              cohort: np.ndarray | None, k_min: int, k_max: int, min_slip: float,
              cfg: LabelConfig, direction: tuple[np.ndarray, np.ndarray] | None = None
              ) -> tuple[np.ndarray, np.ndarray]:
    """Crest cells that slip (step 2 of the module docstring) and the slip of every crest cell.

    Returns (trace cells: slip >= ``min_slip``, dip >= ``min_dip_deg``, pieces of at least
    ``min_trace_cells``; slip (m) along the crest, the jump for k = k_min..k_max averaged
    along it over 5 x 5 cells, NaN off the crest or where not measurable).
    """
    if not crest.any():
        return np.zeros(crest.shape, dtype=bool), np.full(crest.shape, np.nan)
    t_r, t_c = local_direction(crest) if direction is None else direction
    jump = displacement_jump(crest, t_r, t_c, disp_x_m, disp_y_m, rock, k_max, cohort, k_min=k_min)
    slip = along_trace_mean(crest, np.nan_to_num(jump[..., 0], nan=0.0),
                             np.isfinite(jump[..., 0]))
    slip = np.where(crest, slip, np.nan)
    trace = crest & (slip >= min_slip)
    if cfg.min_dip_deg > 0:
        trace &= dip_of(t_r, t_c) >= cfg.min_dip_deg
    return remove_small_components(trace, cfg.min_trace_cells), slip
