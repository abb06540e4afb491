"""Slip-trace labels on a DEM run of the ``quick`` preset (slow: runs the DEM, ~10-30 s).

The displacement jump at a cell is computed here from the particles, independently of the
trace extraction: the element displacements (since first appearance) are rasterised with
:func:`demseis.seismic.raster.rasterise` (mean over the disks containing the cell centre) and
the jump is the largest |u(p + d) - u(p - d)| over the offsets d with |d_row|, |d_col| <= 2
cells whose two cells are rock of the same deposition cohort (displacements of different
cohorts have different references, so their difference is not a slip).
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy import ndimage

from demseis.labels import label_maps, strain_history
from demseis.labels.maps import rasterise_strain, sample_facts
from demseis.labels.traces import displacement_history, loop_count, rung_fraction
from demseis.seismic.raster import rasterise


def jump_field(snap, disp, birth, grid, reach=2):
    u, _ = rasterise(snap.xy, snap.radius, disp, grid)
    _, owner = rasterise_strain(snap.xy, snap.radius, np.zeros(snap.n), grid)
    rock = owner >= 0
    coh = np.where(rock, birth[np.maximum(owner, 0)], -1)
    nz, nx = grid.shape
    up = np.pad(u, ((reach, reach), (reach, reach), (0, 0)), constant_values=np.nan)
    cp = np.pad(coh, reach, constant_values=-2)
    jump = np.zeros(grid.shape)
    for dr in range(-reach, reach + 1):
        for dc in range(-reach, reach + 1):
            if (dr, dc) <= (0, 0):
                continue
            a = up[reach + dr:reach + dr + nz, reach + dc:reach + dc + nx]
            b = up[reach - dr:reach - dr + nz, reach - dc:reach - dc + nx]
            ca = cp[reach + dr:reach + dr + nz, reach + dc:reach + dc + nx]
            cb = cp[reach - dr:reach - dr + nz, reach - dc:reach - dc + nx]
            m = np.hypot(*(a - b).transpose(2, 0, 1))
            ok = (ca == cb) & (ca >= 0) & np.isfinite(m)
            jump = np.where(ok, np.maximum(jump, np.nan_to_num(m)), jump)
    return jump, rock


@pytest.fixture(scope="module")
def quick_run():
    from demseis.generator.config import load_config
    from demseis.generator.pipeline import grid_of, simulate_run
    from demseis.generator.sampling import plan_run

    cfg = load_config(None, preset="quick")
    snaps, _ = simulate_run(cfg, plan_run(cfg, 0))
    return cfg, grid_of(cfg), snaps


@pytest.mark.slow
def test_quick_dem_run_labels(quick_run):
    """Measured at the time of writing (quick run 0, snapshots 1-3): rungs 0.000-0.004, 1 loop
    (6 after the cross-machine fix redrew the pack: the count is reported, not bounded; what is
    asserted is that every loop is a lens whose cells all slip). Of the cells whose jump is
    >= 2 x min_slip_m, 0.57 lay within 2 cells of a 1-cell label (0.48 on the redrawn pack; 0.75
    with thickness 3, 0.83 with 5): the DEM's shear zones are 10+ cells wide and a trace marks
    their slip surface, not their width (issue 13 asks for 0.9; this guards against falling
    further)."""
    cfg, grid, snaps = quick_run
    lc = cfg.labels
    min_slip = lc.min_slip_for(grid.cell_m)
    hist = strain_history(snaps, lc)
    disp = displacement_history(snaps)
    n_hi = n_near = loops = 0
    for k, snap in enumerate(snaps):
        maps = label_maps(snap, hist[k], grid, lc, displacement=disp[k])
        f = maps["fault"].astype(bool)
        facts = sample_facts(maps)
        assert facts["has_fault"] == int(f.any())
        if k == 0:
            assert not f.any()  # nothing has moved yet
            continue
        assert f.any() and facts["n_faults"] >= 1
        # every labelled cell carries slip >= min_slip_m (thickness 1: the trace itself)
        assert (maps["slip_m"][f] >= min_slip).all()
        assert (maps["fault_id"][f] > 0).all() and (maps["sense"][f] > 0).all()
        assert rung_fraction(f) <= 0.01, (k, rung_fraction(f))
        # loops: every cell of a closed loop slips (a lens), by construction of the mask
        holes = ndimage.binary_fill_holes(f) & ~f
        ring = ndimage.binary_dilation(holes, np.ones((3, 3), bool)) & f
        loops += loop_count(f)
        assert (maps["slip_m"][ring] >= min_slip).all()
        jump, rock = jump_field(snap, disp[k][0], disp[k][1], grid)
        hi = (jump >= 2 * min_slip) & rock
        near = ndimage.distance_transform_edt(~f) <= 2
        n_hi += int(hi.sum())
        n_near += int((hi & near).sum())
    assert n_hi > 0 and n_near / n_hi >= 0.45, (n_near / n_hi, f"{loops} loops")
