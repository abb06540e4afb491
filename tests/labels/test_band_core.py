"""The fault core, the shear band's core around a trace (``core_halfwidth_cells``, ``damage``
class 2): against a slow per-cell reference, on a simple-shear band of known width, on a
rigid planar fault (no band: the core is the trace) and on a kinematic shear zone."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import ndimage

from demseis.errors import ConfigError
from demseis.labels import LabelConfig
from demseis.labels.core import CORE_HOLE_CELLS, CORE_MIN_EXTENT_CELLS, CORE_SIGMA_CELLS, band_core
from demseis.labels.crest import shear_field
from demseis.labels.direction import DIRECTION_WINDOW, local_direction
from demseis.labels.masks import fill_small_holes
from demseis_dev.toys import disk_pack, kinematic_fault

from ._helpers import CELL, XF, H, W, centres, labels_of, planar_line


def _band_core_ref(trace, t_r, t_c, field, rock, cohort, max_halfwidth, fraction=0.5):
    """One trace cell and one step at a time; the nearest trace cell of each cell from
    scipy's distance transform (the tie rule), the rest in plain loops. No hole filling."""
    nz, nx = trace.shape
    out = trace.copy()
    if max_halfwidth <= 0 or not trace.any():
        return out
    coh = np.zeros((nz, nx), np.int64) if cohort is None else cohort

    def cell(r, c, k, nr, nc):
        rr = min(max(int(np.rint(r + k * nr)), 0), nz - 1)
        cc = min(max(int(np.rint(c + k * nc)), 0), nx - 1)
        return rr, cc

    ext = {-1: np.zeros((nz, nx)), 1: np.zeros((nz, nx))}
    for r, c in zip(*np.nonzero(trace)):
        nr, nc = t_c[r, c], -t_r[r, c]
        crest = max(field[r, c], field[cell(r, c, -1, nr, nc)], field[cell(r, c, 1, nr, nc)])
        for side in (-1, 1):
            last = 0
            for k in range(1, max_halfwidth + 1):
                q = cell(r, c, side * k, nr, nc)
                if not rock[q] or coh[q] != coh[r, c] or not crest > 0:
                    break
                if field[q] >= fraction * crest:
                    last = k
            ext[side][r, c] = last
    w = DIRECTION_WINDOW // 2
    mean = {}
    for side in (-1, 1):
        mean[side] = np.zeros((nz, nx))
        for r, c in zip(*np.nonzero(trace)):
            box = (slice(max(r - w, 0), r + w + 1), slice(max(c - w, 0), c + w + 1))
            m = ext[side][box][trace[box]].mean()
            mean[side][r, c] = m if m >= CORE_MIN_EXTENT_CELLS - 1e-9 else 0.0
    _, idx = ndimage.distance_transform_edt(~trace, return_indices=True)
    for r in range(nz):
        for c in range(nx):
            qr, qc = idx[0][r, c], idx[1][r, c]
            d = np.hypot(r - qr, c - qc)
            if d == 0 or d > max_halfwidth + 0.5 or not rock[r, c] or coh[r, c] != coh[qr, qc]:
                continue
            off = (r - qr) * t_c[qr, qc] - (c - qc) * t_r[qr, qc]
            reach = mean[1][qr, qc] if off >= 0 else mean[-1][qr, qc]
            if abs(off) <= reach + 0.5 + 1e-9:
                out[r, c] = True
    return out


def test_band_core_matches_a_per_cell_reference():
    rng = np.random.default_rng(3)
    nz, nx = 60, 70
    trace = np.zeros((nz, nx), bool)
    rr = np.arange(5, 55)
    trace[rr, (20 + 0.6 * rr).astype(int)] = True  # a dipping line
    trace[30, 3:25] = True  # and a flat one crossing the edge region
    t_r, t_c = local_direction(trace)
    field = rng.random((nz, nx))
    rock = rng.random((nz, nx)) > 0.05
    cohort = (np.arange(nz)[:, None] > 45).astype(np.int64) * np.ones((1, nx), np.int64)
    for h in (0, 1, 2, 4):
        for coh in (None, cohort):
            got = band_core(trace, t_r, t_c, field, rock, coh, h, hole_cells=0)
            ref = _band_core_ref(trace, t_r, t_c, field, rock, coh, h)
            np.testing.assert_array_equal(got, ref)


@pytest.mark.parametrize("width", [1, 3, 5, 9])
def test_band_core_of_a_simple_shear_band_is_its_width(width):
    """A vertical band of simple shear ``width`` cells wide (u_y linear across it, rigid
    outside): the core is the band's cells (its smoothed shear's width at half maximum),
    capped at 2 h + 1, and nothing beside the trace where the band is too narrow for a core
    (half-width below CORE_MIN_EXTENT_CELLS: a sharp step, or a band of 3 cells)."""
    nz, nx, c0 = 40, 60, 30
    col = np.arange(nx) - c0
    half = 0.5 * width
    u_y = np.clip(col / width + 0.5, 0.0, 1.0) * 100.0 if width > 1 else (col > 0) * 100.0
    disp_y = np.broadcast_to(u_y, (nz, nx)).astype(float).copy()
    disp_x = np.zeros((nz, nx))
    rock = np.ones((nz, nx), bool)
    field = shear_field(disp_x, disp_y, rock, CELL, CORE_SIGMA_CELLS)
    trace = np.zeros((nz, nx), bool)
    trace[5:35, c0] = True
    t_r, t_c = local_direction(trace)
    for h in (1, 2, 3, 5):
        core = band_core(trace, t_r, t_c, field, rock, None, h)
        cols = np.nonzero(core[20])[0] - c0
        expect = min(int(np.floor(half)), h)
        if expect < CORE_MIN_EXTENT_CELLS:
            assert list(cols) == [0], (width, h, cols)
        else:
            assert cols.min() == -expect and cols.max() == expect, (width, h, cols)
            assert len(cols) == 2 * expect + 1
        assert (core[5:35] == core[20]).all()  # the same along the band


def test_fill_small_holes():
    """A band with a 2 x 2 hole (one cell of it a void) and a 5 x 3 one: the small one is
    filled but for the void, the large one (> CORE_HOLE_CELLS) and a notch open to the
    outside are not."""
    mask = np.zeros((40, 20), bool)
    mask[2:38, 5:15] = True
    mask[8:10, 8:10] = False  # 4 cells
    mask[20:25, 8:11] = False  # 15 cells
    mask[30:33, 12:15] = False  # a notch at the edge
    rock = np.ones(mask.shape, bool)
    rock[9, 9] = False
    got = fill_small_holes(mask, CORE_HOLE_CELLS, rock)
    assert (got & ~mask).sum() == 3 and got[8:10, 8:10].sum() == 3 and not got[9, 9]
    assert not got[20:25, 8:11].any() and not got[30:33, 12:15].any()
    assert 4 <= CORE_HOLE_CELLS < 15
    assert (fill_small_holes(mask, 0, rock) == mask).all()
    assert (fill_small_holes(mask, 15, rock) & ~mask).sum() == 18


def test_fault_core_of_a_sharp_planar_fault_is_its_trace():
    """On a rigid (sharp) planar fault the fault core (damage class 2) adds next to nothing to
    the fault mask: the raster's step is not a band. The fault mask does not change with the
    core, and every core cell is within 2.5 cells of the plane."""
    xy, r = disk_pack(W, H, np.random.default_rng(1))
    cur = kinematic_fault(xy, x_m=XF, dip_deg=50.0, slip_m=120.0)
    none, grid = labels_of(xy, cur, r, config=LabelConfig(core_halfwidth_cells=0))
    cored, _ = labels_of(xy, cur, r, config=LabelConfig(core_halfwidth_cells=5))
    assert (none["fault"] == cored["fault"]).all() and (none["damage"] == 2).sum() > 50
    assert ((none["damage"] == 2) == (none["fault"] > 0)).all()
    core, f = cored["damage"] == 2, cored["fault"] > 0
    assert (core >= f).all() and core.sum() <= 1.1 * f.sum()
    d, _ = planar_line(grid, 50.0)
    assert np.quantile(d[core], 0.95) <= 2.5


@pytest.mark.parametrize("seed", [1, 2])
@pytest.mark.parametrize("dip", [50.0, 65.0])
def test_fault_core_of_a_shear_zone_spans_it(seed, dip):
    """A 120 m (12-cell) wide zone of simple shear carrying 250 m (kinematic_fault's
    zone_width_m), scored where both walls face each other: the fault mask is a line, the fault
    core covers most of the zone and stays in it. Measured: zone covered 0.77-0.83 by the core
    (0.12-0.16 by the line), 0.3-2.4 % of core cells more than 1.5 cells outside the zone."""
    xy, r = disk_pack(W, H, np.random.default_rng(seed))
    slip, zone = 250.0, 120.0
    cur = kinematic_fault(xy, x_m=XF, dip_deg=dip, slip_m=slip, zone_width_m=zone)
    maps, grid = labels_of(xy, cur, r)
    d, _ = planar_line(grid, dip)
    xx, zz = centres(grid)
    th = np.radians(dip)
    region = (zz < H - slip * np.sin(th) - 5 * CELL) & (zz > 5 * CELL)
    region &= xx > slip * np.cos(th) + 2 * CELL
    inside = (d <= 0.5 * zone / CELL) & region
    core = (maps["damage"] == 2) & region
    line = (maps["fault"] > 0) & region
    assert (core & inside).sum() >= 0.7 * inside.sum()
    assert (line & inside).sum() <= 0.3 * inside.sum()
    assert (core & (d > 0.5 * zone / CELL + 1.5)).sum() <= 0.05 * core.sum()


def test_core_halfwidth_cells_is_validated():
    for bad in (-1, 11, 1.5):
        with pytest.raises(ConfigError, match="labels.core_halfwidth_cells"):
            LabelConfig(core_halfwidth_cells=bad).validate()
    assert LabelConfig(core_halfwidth_cells=3).validate().core_halfwidth_cells == 3
