"""Continuum strain from element-centre displacements.

Per element, a least-squares deformation gradient F is fitted to the relative positions of its
neighbours (chosen in the reference state, by distance or k-nearest):

    F = argmin sum_j |dx_j - F dX_j|^2 = (sum_j dx_j dX_j^T) (sum_j dX_j dX_j^T)^-1,

with dX_j = X_j - X_i (reference) and dx_j = x_j - x_i (current). The right Cauchy-Green tensor
C = F^T F has eigenvalues lambda1 >= lambda2, the quadratic elongations of the principal axes
(lambda = (1 + e)^2). The maximum shear strain (Ramsay & Huber) is

    gamma_max = (lambda1 - lambda2) / (2 sqrt(lambda1 lambda2)),

which is 0 for any rigid motion. For simple shear by gamma it is gamma * sqrt(1 + gamma^2 / 4)
(lambda1 lambda2 = 1, lambda1 + lambda2 = 2 + gamma^2), for pure shear F = diag(k, 1/k) it is
(k^2 - k^-2) / 2. Volumetric strain is det(F) - 1, the relative change of area.

Because the elements are rigid this is a kinematic descriptor of the assembly, not a strain of
the grains themselves.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from demseis.errors import InputError
from demseis.labels import _kernels
from demseis.labels.config import NEIGHBOUR_METHODS, LabelConfig

#: eigmin / eigmax of sum dX dX^T below which the neighbour cloud counts as collinear.
COLLINEAR_TOL = 1e-3


@dataclass(frozen=True)
class StrainResult:
    """Per-element finite strain.

    Attributes
    ----------
    gamma_max : (n,) float64 maximum shear strain; NaN where not ``valid``.
    volumetric : (n,) float64 det(F) - 1; NaN where not ``valid``.
    valid : (n,) bool; False where the element has fewer than ``min_neighbours`` neighbours,
        a (nearly) collinear neighbour cloud, or an inverted fit (det F <= 0).
    n_neighbours : (n,) int64 neighbour count in the reference state.
    deformation_gradient : (n, 2, 2) float64 F (x, y components); NaN where not ``valid``.
    """

    gamma_max: np.ndarray
    volumetric: np.ndarray
    valid: np.ndarray
    n_neighbours: np.ndarray
    deformation_gradient: np.ndarray

    def __getitem__(self, key: str) -> np.ndarray:
        """Dictionary-style access, ``res["gamma_max"]``."""
        return getattr(self, key)


def neighbour_lists(
    xy: np.ndarray,
    radii: np.ndarray,
    *,
    method: str = "radius",
    radius_factor: float = 1.5,
    k: int = 10,
) -> tuple[np.ndarray, np.ndarray]:
    """Neighbour lists (CSR) of element centres.

    Parameters
    ----------
    xy : (n, 2) centres (m).
    radii : (n,) radii (m).
    method : ``"radius"``: j neighbours i when ``|x_j - x_i| <= radius_factor * (r_i + r_j)``;
        ``"knn"``: the ``k`` nearest other centres.
    radius_factor, k : see ``method``.

    Returns
    -------
    offsets : (n + 1,) int64; index : (m,) int64.
        Neighbours of i: ``index[offsets[i]:offsets[i+1]]``.
    """
    xy, radii = _check_xy_radii(xy, radii, "xy")
    x = np.ascontiguousarray(xy[:, 0])
    y = np.ascontiguousarray(xy[:, 1])
    if method == "radius":
        if not (0.0 < float(radius_factor) <= 5.0):
            raise InputError(f"radius_factor = {radius_factor!r}; allowed: (0, 5]")
        return _kernels.radius_neighbours(x, y, radii, float(radius_factor))
    if method == "knn":
        n = xy.shape[0]
        if isinstance(k, bool) or not isinstance(k, (int, np.integer)) or k < 1:
            raise InputError(f"k = {k!r}; allowed: an integer >= 1")
        kk = int(min(k, max(n - 1, 0)))
        if kk == 0:
            return np.zeros(n + 1, dtype=np.int64), np.empty(0, dtype=np.int64)
        return _kernels.knn_neighbours(x, y, kk)
    raise InputError(f"method = {method!r}; allowed: {' | '.join(map(repr, NEIGHBOUR_METHODS))}")


def element_strain(
    reference_xy: np.ndarray,
    current_xy: np.ndarray,
    radii: np.ndarray,
    *,
    method: str = "radius",
    radius_factor: float = 1.5,
    k: int = 10,
    min_neighbours: int = 3,
) -> StrainResult:
    """Finite strain of every element from its neighbours' displacements.

    Parameters
    ----------
    reference_xy : (n, 2) element centres in the reference state (m).
    current_xy : (n, 2) centres of the same elements, same order, in the current state (m).
    radii : (n,) element radii (m), > 0 (used by the ``"radius"`` neighbour search).
    method : ``"radius"`` or ``"knn"``, how neighbours are chosen in the reference state
        (see :func:`neighbour_lists`).
    radius_factor : for ``"radius"``: neighbours within ``radius_factor * (r_i + r_j)``.
    k : for ``"knn"``: number of nearest neighbours.
    min_neighbours : elements with fewer neighbours are flagged invalid.

    Returns
    -------
    StrainResult
        ``gamma_max``, ``volumetric`` (det F - 1), ``valid``, ``n_neighbours`` and
        ``deformation_gradient``; see the module docstring for the equations.

    Raises
    ------
    demseis.errors.InputError
        On mismatched shapes, non-finite positions or non-positive radii.
    """
    ref, radii = _check_xy_radii(reference_xy, radii, "reference_xy")
    cur = np.asarray(current_xy, dtype=np.float64)
    if cur.shape != ref.shape:
        raise InputError(
            f"current_xy has shape {cur.shape}; expected {ref.shape} like reference_xy"
        )
    if not np.all(np.isfinite(cur)):
        raise InputError("current_xy contains non-finite values")
    if isinstance(min_neighbours, bool) or not isinstance(min_neighbours, (int, np.integer)) \
            or min_neighbours < 2:
        raise InputError(f"min_neighbours = {min_neighbours!r}; allowed: an integer >= 2")
    offsets, index = neighbour_lists(ref, radii, method=method, radius_factor=radius_factor, k=k)
    return _strain_from_lists(ref, cur, offsets, index, int(min_neighbours))


def _strain_from_lists(ref, cur, offsets, index, min_neighbours) -> StrainResult:
    n = ref.shape[0]
    f = np.empty((n, 2, 2), dtype=np.float64)
    gamma = np.empty(n, dtype=np.float64)
    vol = np.empty(n, dtype=np.float64)
    nn = np.empty(n, dtype=np.int64)
    valid = np.empty(n, dtype=np.bool_)
    _kernels.finite_strain(
        np.ascontiguousarray(ref[:, 0]), np.ascontiguousarray(ref[:, 1]),
        np.ascontiguousarray(cur[:, 0]), np.ascontiguousarray(cur[:, 1]),
        offsets, index, min_neighbours, COLLINEAR_TOL, f, gamma, vol, nn, valid,
    )
    return StrainResult(gamma_max=gamma, volumetric=vol, valid=valid, n_neighbours=nn,
                        deformation_gradient=f)


def _check_xy_radii(xy, radii, name) -> tuple[np.ndarray, np.ndarray]:
    xy = np.asarray(xy, dtype=np.float64)
    radii = np.asarray(radii, dtype=np.float64)
    if xy.ndim != 2 or xy.shape[1] != 2:
        raise InputError(f"{name} must have shape (n, 2); got {xy.shape}")
    if radii.shape != (xy.shape[0],):
        raise InputError(f"radii must have shape ({xy.shape[0]},) like {name}; got {radii.shape}")
    if not np.all(np.isfinite(xy)):
        raise InputError(f"{name} contains non-finite values")
    if xy.shape[0] and not (np.all(np.isfinite(radii)) and radii.min() > 0):
        raise InputError("radii must be finite and > 0")
    return xy, radii


@dataclass(frozen=True)
class StrainState:
    """Strain of the elements of one snapshot, aligned with ``snapshot.ids``.

    Attributes
    ----------
    index : the snapshot's index.
    ids : (n,) int64 element ids (the snapshot's own order).
    total : (n,) float64 gamma_max of the finite strain from each element's first appearance
        (snapshot 0 for the original elements) to this snapshot; 0 in the snapshot where an
        element first appears; NaN where the fit is invalid.
    total_volumetric : (n,) float64 det F - 1 of the same finite strain; NaN where invalid.
    incremental : (n,) float64 gamma_max between the previous snapshot and this one (0 for
        elements new in this snapshot and in snapshot 0; NaN where invalid).
    cumulative : (n,) float64 sum of the incremental gamma_max over all snapshots so far in
        which the element existed; invalid increments add nothing.
    valid : (n,) bool, True where ``total`` is a valid fit.
    """

    index: int
    ids: np.ndarray
    total: np.ndarray
    total_volumetric: np.ndarray
    incremental: np.ndarray
    cumulative: np.ndarray
    valid: np.ndarray

    def measure(self, name: str) -> np.ndarray:
        """``"total"`` or ``"cumulative"`` gamma_max (what ``LabelConfig.strain_measure`` names)."""
        if name == "total":
            return self.total
        if name == "cumulative":
            return self.cumulative
        raise InputError(f"strain measure {name!r}; allowed: 'total' | 'cumulative'")


def strain_history(
    snapshots: Sequence,
    config: LabelConfig | None = None,
) -> list[StrainState]:
    """Total, incremental and cumulative gamma_max of every element of every snapshot.

    Parameters
    ----------
    snapshots : sequence of :class:`demseis.types.Snapshot`, in time order, sharing one
        id space. Elements may appear (deposition) in later snapshots; an element's reference
        is its first appearance.
    config : neighbour method/size and ``min_neighbours`` (default :class:`LabelConfig`).

    Returns
    -------
    list of StrainState, one per snapshot, arrays aligned with that snapshot's elements.

    Notes
    -----
    Total strain at snapshot k of an element that first appeared at snapshot t is fitted with
    the neighbours it had at t among the elements present at both t and k (positions at t as
    reference), so every cohort of deposited elements is strained against a consistent state.
    Incremental strain from k-1 to k uses the elements present in both, positions at k-1 as
    reference; the cumulative strain is the running sum of the incremental strains, starting
    at 0 when an element first appears.
    """
    cfg = (config or LabelConfig()).validate()
    snaps = list(snapshots)
    if not snaps:
        raise InputError("strain_history needs at least one snapshot; got none")
    for s_i, s in enumerate(snaps):
        _check_snapshot(s, s_i)
    kw = dict(method=cfg.neighbour_method, radius_factor=cfg.neighbour_radius_factor,
              k=cfg.neighbour_k)
    out: list[StrainState] = []
    # neighbour lists of each snapshot's full element set, reused while no element is lost
    cache: dict[int, tuple[np.ndarray, np.ndarray]] = {}

    def lists_of(t: int, in_ref: np.ndarray, full: bool):
        ref = snaps[t]
        if full:
            if t not in cache:
                cache[t] = neighbour_lists(ref.xy, ref.radius, **kw)
            return cache[t]
        return neighbour_lists(ref.xy[in_ref], ref.radius[in_ref], **kw)

    def fit(t: int, cur_snap) -> tuple[np.ndarray, np.ndarray, StrainResult]:
        ref = snaps[t]
        in_ref, in_cur, full = _match(np.asarray(ref.ids), np.asarray(cur_snap.ids))
        offsets, index = lists_of(t, in_ref, full)
        res = _strain_from_lists(np.ascontiguousarray(ref.xy[in_ref], dtype=np.float64),
                                 np.ascontiguousarray(cur_snap.xy[in_cur], dtype=np.float64),
                                 offsets, index, cfg.min_neighbours)
        return in_ref, in_cur, res

    seen_ids = np.empty(0, dtype=np.int64)  # sorted ids seen so far
    seen_birth = np.empty(0, dtype=np.int64)  # their first snapshot position
    prev_cum: np.ndarray | None = None
    for k_pos, snap in enumerate(snaps):
        ids = np.asarray(snap.ids, dtype=np.int64)
        n = ids.shape[0]
        pos = np.searchsorted(seen_ids, ids)
        known = pos < seen_ids.shape[0]
        known[known] = seen_ids[pos[known]] == ids[known]
        birth = np.full(n, k_pos, dtype=np.int64)
        birth[known] = seen_birth[pos[known]]
        if (~known).any():
            all_ids = np.concatenate([seen_ids, ids[~known]])
            all_birth = np.concatenate([seen_birth, birth[~known]])
            order = np.argsort(all_ids, kind="stable")
            seen_ids, seen_birth = all_ids[order], all_birth[order]
        total = np.zeros(n)
        total_vol = np.zeros(n)
        valid = np.ones(n, dtype=bool)
        # one fit per cohort of first appearance
        for t in np.unique(birth):
            if t == k_pos:
                continue  # born now: zero strain against itself
            _, in_cur, res = fit(int(t), snap)
            sel = birth[in_cur] == t
            tgt = in_cur[sel]
            total[tgt] = res.gamma_max[sel]
            total_vol[tgt] = res.volumetric[sel]
            valid[tgt] = res.valid[sel]
        incr = np.zeros(n)
        cum = np.zeros(n)
        if k_pos > 0:
            in_prev, in_cur, res = fit(k_pos - 1, snap)
            incr[in_cur] = res.gamma_max
            add = np.where(res.valid, res.gamma_max, 0.0)
            cum[in_cur] = prev_cum[in_prev] + add
        out.append(StrainState(index=int(snap.index), ids=ids.copy(), total=total,
                               total_volumetric=total_vol, incremental=incr, cumulative=cum,
                               valid=valid))
        prev_cum = cum
    return out


def _match(ref_ids: np.ndarray, cur_ids: np.ndarray) -> tuple[np.ndarray, np.ndarray, bool]:
    """Positions of the common ids: ``ref_ids[in_ref] == cur_ids[in_cur]``, in reference order.

    ``full`` is True when every reference id is present in ``cur_ids`` (then in_ref = arange).
    """
    order = np.argsort(cur_ids, kind="stable")
    sorted_cur = cur_ids[order]
    pos = np.searchsorted(sorted_cur, ref_ids)
    pos_c = np.minimum(pos, max(sorted_cur.shape[0] - 1, 0))
    found = (pos < sorted_cur.shape[0]) & (sorted_cur[pos_c] == ref_ids) if sorted_cur.size \
        else np.zeros(ref_ids.shape[0], dtype=bool)
    in_ref = np.nonzero(found)[0]
    in_cur = order[pos_c[found]]
    return in_ref, in_cur, bool(found.all())


def _check_snapshot(s, pos: int) -> None:
    try:
        ids = np.asarray(s.ids)
        xy = np.asarray(s.xy)
        radius = np.asarray(s.radius)
    except AttributeError as exc:
        raise InputError(f"snapshots[{pos}] is not a Snapshot ({type(s).__name__})") from exc
    n = ids.shape[0]
    if ids.ndim != 1 or xy.shape != (n, 2) or radius.shape != (n,):
        raise InputError(
            f"snapshots[{pos}]: expected ids (n,), xy (n, 2), radius (n,); got "
            f"{ids.shape}, {xy.shape}, {radius.shape}"
        )
    if np.unique(ids).shape[0] != n:
        raise InputError(f"snapshots[{pos}]: element ids are not unique")
    if not np.all(np.isfinite(xy)):
        raise InputError(f"snapshots[{pos}]: xy contains non-finite values")
