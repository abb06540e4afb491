"""Fault instances: the trace cells linked into faults (step 3 of :mod:`demseis.labels.traces`).

A trace network is cut at its junctions; the branches that continue each other across a
junction, or face each other across a short gap, are one fault (:func:`trace_instances`).
Strands, the other slip surfaces of a wide shear zone, take the id of the fault whose zone
they lie in (:func:`strand_instances`). Ids are 1.. by decreasing size.
"""

from __future__ import annotations

import numpy as np
from scipy import ndimage
from scipy.spatial import cKDTree

from demseis.labels.centreline import crossing_number
from demseis.labels.masks import EIGHT


#: largest gap (cells) across which two facing trace ends are joined into one fault
LINK_GAP_CELLS = 10.0

#: a strand lying mostly within this distance (cells) of a trace belongs to that fault's zone
STRAND_ZONE_CELLS = 15.0


def trace_instances(skel: np.ndarray, link_angle_deg: float = 35.0,
                    gap_cells: float = 8.0) -> np.ndarray:
    """Fault ids of a one-cell-wide trace network (0 off the trace, 1.. by size).

    Branches are the 8-connected pieces left when the junction cells (crossing number >= 3)
    and their neighbours are removed. At each junction, pairs of branches that continue each
    other (their directions away from the junction within ``link_angle_deg`` of opposite) are
    joined, the straightest pair first; every other branch is a fault of its own. Two branch
    ends at most ``gap_cells`` apart that face each other (each end's direction within
    ``link_angle_deg`` of the line joining them) are one fault across the gap. Junction
    cells take the id of the nearest branch cell.
    """
    s = np.asarray(skel, dtype=bool)
    out = np.zeros(s.shape, dtype=np.int32)
    if not s.any():
        return out
    # a crossing drawn as a 2 x 2 block has crossing number 2 everywhere: 4+ neighbours too
    nbrs = ndimage.convolve(s.astype(np.int32), np.ones((3, 3), np.int32), mode="constant") - 1
    junction = ((crossing_number(s) >= 3) | (nbrs >= 4)) & s
    zone = ndimage.binary_dilation(junction, structure=EIGHT) & s
    body = s & ~zone
    blab, nb = ndimage.label(body, structure=EIGHT)
    if nb == 0:
        lab, _ = ndimage.label(s, structure=EIGHT)
        return _by_size(lab)
    parent = np.arange(nb + 1)

    def find(a: int) -> int:
        while parent[a] != a:
            parent[a] = parent[parent[a]]
            a = parent[a]
        return a

    cos_max = -np.cos(np.radians(link_angle_deg))
    zlab, nz_ = ndimage.label(zone, structure=EIGHT)
    br_r, br_c = np.nonzero(blab)
    br_l = blab[br_r, br_c]
    reach = 8.0
    tree = cKDTree(np.column_stack([br_r, br_c]).astype(np.float64))

    def within(pr: float, pc: float) -> np.ndarray:
        """Branch cells within ``reach`` of (pr, pc), in the order of np.nonzero."""
        cand = np.array(sorted(tree.query_ball_point((pr, pc), reach + 1e-6)), dtype=np.int64)
        if cand.size == 0:
            return cand
        return cand[(br_r[cand] - pr) ** 2 + (br_c[cand] - pc) ** 2 <= reach * reach]

    for z, sl in enumerate(ndimage.find_objects(zlab), start=1):
        if sl is None:
            continue
        zr, zc = np.nonzero(zlab[sl] == z)
        cr, cc = zr.mean() + sl[0].start, zc.mean() + sl[1].start
        r0, r1 = max(sl[0].start - 1, 0), min(sl[0].stop + 1, s.shape[0])
        c0, c1 = max(sl[1].start - 1, 0), min(sl[1].stop + 1, s.shape[1])
        near = (zlab[r0:r1, c0:c1] == z)
        ring = ndimage.binary_dilation(np.pad(near, 1), structure=EIGHT)[1:-1, 1:-1]
        adj = np.unique(blab[r0:r1, c0:c1][ring & (blab[r0:r1, c0:c1] > 0)])
        if adj.size < 2:
            continue
        dirs = {}
        around = within(cr, cc)
        for b in adj:
            sel = around[br_l[around] == b]
            if not sel.size:
                continue
            d = np.array([br_r[sel].mean() - cr, br_c[sel].mean() - cc])
            nrm = np.hypot(*d)
            if nrm > 0:
                dirs[int(b)] = d / nrm
        keys = sorted(dirs)
        pairs = sorted((float(dirs[a] @ dirs[b]), a, b)
                       for i, a in enumerate(keys) for b in keys[i + 1:])
        used: set[int] = set()
        for cos_ab, a, b in pairs:
            if cos_ab > cos_max:
                break
            if a in used or b in used:
                continue
            used.update((a, b))
            parent[find(a)] = find(b)
    # pieces of one fault separated by a short gap: end points facing each other
    ends = np.argwhere((crossing_number(body) == 1) & body)
    if ends.shape[0] >= 2:
        e_lab = blab[ends[:, 0], ends[:, 1]]
        e_dir = np.zeros((ends.shape[0], 2))
        for q, (r_, c_) in enumerate(ends):  # direction from the piece into the gap
            sel = within(float(r_), float(c_))
            sel = sel[br_l[sel] == e_lab[q]]
            d = np.array([r_ - br_r[sel].mean(), c_ - br_c[sel].mean()])
            nrm = np.hypot(*d)
            e_dir[q] = d / nrm if nrm > 0 else 0.0
        cos_gap = np.cos(np.radians(link_angle_deg))
        # candidate pairs (a < b, lexicographic: the order fixes the union-find roots)
        close = sorted(cKDTree(ends.astype(np.float64)).query_pairs(gap_cells + 1e-6))
        for a, b in close:
            if e_lab[a] == e_lab[b]:
                continue
            v = (ends[b] - ends[a]).astype(np.float64)
            dist = np.hypot(*v)
            if dist == 0 or dist > gap_cells:
                continue
            v /= dist
            if e_dir[a] @ v >= cos_gap and -(e_dir[b] @ v) >= cos_gap:
                parent[find(int(e_lab[a]))] = find(int(e_lab[b]))
    roots = np.array([find(i) for i in range(nb + 1)])
    lab = roots[blab]
    lab[~body] = 0
    # junction cells: id of the nearest branch cell
    idx = ndimage.distance_transform_edt(lab == 0, return_distances=False, return_indices=True)
    fill = lab[idx[0], idx[1]]
    lab = np.where(zone, fill, lab)
    lab[~s] = 0
    return _by_size(lab)


def strand_instances(inst: np.ndarray, strand: np.ndarray, link_angle_deg: float) -> np.ndarray:
    """Fault ids with the strands: a strand whose cells lie mostly within STRAND_ZONE_CELLS of
    a trace is a surface of that fault's shear zone and takes its id (the commonest id of the
    nearest trace cells); the others are faults of their own (ids by
    :func:`trace_instances` among themselves). Renumbered 1.. by size."""
    out = inst.copy()
    own = trace_instances(strand, link_angle_deg, LINK_GAP_CELLS)
    if inst.any():
        dist, idx = ndimage.distance_transform_edt(inst == 0, return_indices=True)
        nearest = inst[idx[0], idx[1]]
    else:
        dist, nearest = np.full(inst.shape, np.inf), np.zeros_like(inst)
    lab, n = ndimage.label(strand, structure=EIGHT)
    offset = int(inst.max())
    for q, sl in enumerate(ndimage.find_objects(lab), start=1):
        cells = lab[sl] == q
        d = dist[sl][cells]
        if np.median(d) <= STRAND_ZONE_CELLS:
            ids, counts = np.unique(nearest[sl][cells], return_counts=True)
            out[sl][cells] = ids[np.argmax(counts)]
        else:
            out[sl][cells] = own[sl][cells] + offset
    return _by_size(out)


def _by_size(lab: np.ndarray) -> np.ndarray:
    """Renumber positive labels 1.. by decreasing size (ties: lower old label first)."""
    ids, counts = np.unique(lab[lab > 0], return_counts=True)
    order = ids[np.lexsort((ids, -counts))]
    lut = np.zeros(int(lab.max()) + 1, dtype=np.int32)
    lut[order] = np.arange(1, order.size + 1, dtype=np.int32)
    return lut[lab]
