"""label_maps: kinematic planar fault, thickness control, damage classes, layer and strain maps."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import ndimage
from scipy.spatial import cKDTree

from demseis.errors import ConfigError, InputError
from demseis.labels import (LabelConfig, displacement_history, element_strain, label_maps,
                            mask_thickness_cells, rasterise_strain, strain_history,
                            thin_and_dilate)
from demseis.labels.centreline import prune_spurs
from demseis.labels.masks import skeletonize
from demseis.schema import SAMPLE_ARRAYS, SampleArray, engine_labels, sample_array
from demseis.seismic.raster import rasterise
from demseis.types import Grid, Snapshot
from demseis_dev.toys import fault_signed_distance, kinematic_fault

W, H, XF = 2000.0, 1000.0, 1200.0


def snap_of(xy, r, layer=None, index=1):
    n = xy.shape[0]
    return Snapshot(index, index, 0.0, np.arange(n, dtype=np.int64), xy, r,
                    np.zeros(n, np.int16) if layer is None else layer, np.zeros(n, bool))


def line_metrics(fault, grid, dip, slip, tol_cells=2.0):
    """(fraction of mask cells within tol of the line, fraction of the line covered).

    Only the part of the section where both walls are present is scored: below the hanging
    wall's lowered top (H - slip sin(dip); above it the footwall's free scarp faces air) and
    right of its trailing left edge (moved to x = slip cos(dip); left of it the footwall faces
    the void the hanging wall left, which matters where the line leaves through the left side,
    i.e. at 30 deg). A point of the line is covered when a mask cell lies within tol_cells of it.
    """
    th = np.radians(dip)
    top = H - slip * np.sin(th) - 2 * grid.cell_m
    left = slip * np.cos(th) + 2 * grid.cell_m
    zz, xx = np.meshgrid(grid.y_centres(), grid.x_centres(), indexing="ij")
    f = fault.astype(bool) & (zz < top) & (xx > left)
    pts = np.column_stack([xx[f], zz[f]])
    assert pts.shape[0] > 0
    d = np.abs(fault_signed_distance(pts, XF, dip)) / grid.cell_m
    s = np.linspace(0.0, H / np.sin(th), 4000)
    lp = np.column_stack([XF - s * np.cos(th), s * np.sin(th)])
    lp = lp[(lp[:, 0] > left) & (lp[:, 1] < top)]
    dd, _ = cKDTree(pts).query(lp)
    return float((d <= tol_cells).mean()), float((dd <= tol_cells * grid.cell_m).mean())


@pytest.mark.parametrize("dip, slip", [(30.0, 150.0), (30.0, 300.0), (45.0, 150.0),
                                       (60.0, 150.0)])
def test_kinematic_fault_mask_lies_on_the_line(pack_fault, dip, slip):
    grid = Grid.covering(W, H, 10.0)
    for xy, r in pack_fault:
        cur = kinematic_fault(xy, x_m=XF, dip_deg=dip, slip_m=slip)
        res = element_strain(xy, cur, r)
        maps = label_maps(snap_of(cur, r), res.gamma_max, grid, LabelConfig(method="strain_band"))
        on_line, covered = line_metrics(maps["fault"], grid, dip, slip)
        assert on_line >= 0.9, (dip, slip, on_line)
        assert covered >= 0.9, (dip, slip, covered)
        # no fault far from the line
        zz, xx = np.meshgrid(grid.y_centres(), grid.x_centres(), indexing="ij")
        f = maps["fault"].astype(bool)
        d = np.abs(fault_signed_distance(np.column_stack([xx[f], zz[f]]), XF, dip))
        assert d.max() < 120.0


def test_prune_keeps_the_line_end_and_drops_side_spurs():
    sk = np.zeros((40, 80), dtype=bool)
    sk[20, 5:60] = True  # main line, 55 cells
    for k in range(1, 9):  # side spur off the middle: 8 cells up-right from (20, 30)
        sk[20 - k, 30 + k] = True
    # end fork at (20, 59): a 10-cell branch on along the line, a 6-cell one down-right
    sk[20, 60:70] = True
    for k in range(1, 7):
        sk[20 + k, 59 + k] = True
    out = prune_spurs(sk, 15)
    assert not out[12, 38] and not out[15, 35]  # side spur gone
    assert out[20, 69] and out[20, 64]  # the longer end branch is kept: the line reaches x = 69
    assert not out[26, 65] and not out[24, 63]  # the shorter one is gone
    assert out[20, 5:60].all()


def test_thickness_control_is_monotonic_and_near_target(pack_fault):
    xy, r = pack_fault[0]
    grid = Grid.covering(W, H, 10.0)
    cur = kinematic_fault(xy, x_m=XF, dip_deg=60.0, slip_m=150.0)
    g = element_strain(xy, cur, r).gamma_max
    measured = []
    for t in (1.0, 3.0, 5.0, 7.0):
        m = label_maps(snap_of(cur, r), g, grid, LabelConfig(method="strain_band", thickness_cells=t))["fault"]
        measured.append(mask_thickness_cells(m))
    assert np.all(np.diff(measured) > 0.5), measured
    for t, got in zip((3.0, 5.0, 7.0), measured[1:]):
        assert abs(got / t - 1) < 0.25, (t, got)
    raw = label_maps(snap_of(cur, r), g, grid, LabelConfig(method="strain_band", thickness_cells=0.0))["fault"]
    assert mask_thickness_cells(raw) > measured[1]  # thresholded band is wider than 3 cells


def test_thickness_measure_on_drawn_bands():
    # a band of cells within w/2 of a straight line has thickness ~w whatever the angle
    zz, xx = np.mgrid[0:200, 0:300].astype(float)
    for ang in (0.0, 30.0, 45.0, 80.0):
        a = np.radians(ang)
        d = np.abs((xx - 150) * np.sin(a) - (zz - 100) * np.cos(a))
        inside = (np.abs((xx - 150) * np.cos(a) + (zz - 100) * np.sin(a)) < 80)
        for w in (3.0, 5.0, 9.0):
            band = (d <= w / 2) & inside
            # area / length; the 45-degree band of w = 3 holds 5 diagonals (3.54 cells)
            assert mask_thickness_cells(band) == pytest.approx(w, rel=0.25)


def test_damage_classes_nest(pack_fault):
    xy, r = pack_fault[0]
    grid = Grid.covering(W, H, 10.0)
    cur = kinematic_fault(xy, x_m=XF, dip_deg=50.0, slip_m=60.0, zone_width_m=300.0)
    cur = kinematic_fault(cur, x_m=XF, dip_deg=50.0, slip_m=80.0)
    g = element_strain(xy, cur, r).gamma_max
    cfg = LabelConfig(method="strain_band", thickness_cells=0.0, damage_threshold=0.15)
    maps = label_maps(snap_of(cur, r), g, grid, cfg)
    dmg, flt = maps["damage"], maps["fault"]
    assert dmg.dtype == np.uint8 and flt.dtype == np.uint8
    assert set(np.unique(dmg)) == {0, 1, 2}
    assert np.array_equal(dmg == 2, flt == 1)
    # the damage zone (shear zone gamma = 0.2 > damage_threshold) is wider than the core
    assert (dmg == 1).sum() > (dmg == 2).sum()
    lower = label_maps(snap_of(cur, r), g, grid,
                       LabelConfig(method="strain_band", thickness_cells=0.0, damage_threshold=0.05))["damage"]
    assert ((lower >= 1).sum() >= (dmg >= 1).sum())


def test_strain_target_and_layer_map(pack_small):
    xy, r = pack_small
    # layers: 5 bands of 100 m by centre height; grid taller than the pack (air on top)
    layer = np.minimum(xy[:, 1] // 100, 4).astype(np.int16)
    grid = Grid(x0_m=0.0, top_m=600.0, cell_m=10.0, nz=60, nx=80)
    g = np.abs(np.sin(xy[:, 0] / 97.0))
    maps = label_maps(snap_of(xy, r, layer), g, grid, LabelConfig(method="strain_band"))
    st, lay = maps["strain"], maps["layer"]
    assert st.dtype == np.float32 and lay.dtype == np.int16 and st.shape == grid.shape
    assert np.all(np.isfinite(st))
    mean, count = rasterise(xy, r, g, grid)
    cov = count > 0
    np.testing.assert_allclose(st[cov], mean[cov].astype(np.float32))
    # air above the pack: layer -1, strain 0
    assert np.all(lay[:5] == -1) and np.all(st[:5] == 0)
    # inside: the cell's band, except within an element radius of a band boundary
    yc = grid.y_centres()[:, None] * np.ones((1, grid.nx))
    band = np.minimum(yc // 100, 4)
    rock = lay >= 0
    far = rock & (np.abs(yc - np.round(yc / 100) * 100) > 26) & (yc < 470)
    assert (lay[far] == band[far]).mean() > 0.97


def test_rasterise_fills_gaps_and_ignores_nan(pack_small):
    xy, r = pack_small
    grid = Grid.covering(800.0, 500.0, 10.0)
    v = np.full(xy.shape[0], 2.0)
    v[::7] = np.nan
    field, owner = rasterise_strain(xy, r, v, grid)
    rock = owner >= 0
    assert rock.mean() > 0.95
    np.testing.assert_allclose(field[rock], 2.0)
    assert np.all(field[~rock] == 0.0)


def test_label_maps_accepts_strain_state_and_is_deterministic(pack_small):
    xy, r = pack_small
    cur = kinematic_fault(xy, x_m=500.0, dip_deg=60.0, slip_m=80.0)
    snaps = [snap_of(xy, r, index=0), snap_of(cur, r, index=1)]
    hist = strain_history(snaps)
    grid = Grid.covering(800.0, 500.0, 10.0)
    a = label_maps(snaps[1], hist[1], grid, LabelConfig(method="strain_band", strain_measure="total"))
    b = label_maps(snaps[1], hist[1].total, grid, LabelConfig(method="strain_band"))
    c = label_maps(snaps[1], hist[1].total, grid, LabelConfig(method="strain_band"))
    for key in ("fault", "damage", "strain", "layer"):
        assert np.array_equal(a[key], b[key]) and a[key].tobytes() == c[key].tobytes()
    assert a["fault"].sum() > 0
    with pytest.raises(InputError, match="strain_per_element"):
        label_maps(snaps[1], hist[1].total[:-1], grid)
    with pytest.raises(InputError, match="ids do not match"):
        n = xy.shape[0]
        label_maps(Snapshot(1, 1, 0.0, np.arange(n)[::-1].copy(), cur[::-1], r[::-1],
                            np.zeros(n, np.int16), np.zeros(n, bool)), hist[1], grid)


def test_skeleton_matches_scikit_image_thin():
    from skimage.morphology import thin  # optional dev dependency, heavy to import

    rng = np.random.default_rng(0)
    for _ in range(10):
        img = ndimage.gaussian_filter(rng.random((80, 120)), rng.uniform(1.0, 4.0)) > 0.5
        sk = skeletonize(img)
        assert np.array_equal(sk, thin(img))
        assert not (sk & ~img).any()
        lab, n = ndimage.label(img, structure=np.ones((3, 3)))
        assert len(np.unique(lab[sk])) == n  # every object keeps a skeleton


def test_thin_and_dilate_reaches_grid_edge():
    # a vertical band 9 cells wide crossing the whole grid: the centre line reaches both edges
    m = np.zeros((60, 40), bool)
    m[:, 16:25] = True
    line = thin_and_dilate(m, 1.0)
    assert line[0].any() and line[-1].any()
    assert np.all(np.nonzero(line)[1] == 20)


@pytest.mark.parametrize(
    "field,value",
    [("strain_measure", "max"), ("neighbour_method", "delaunay"),
     ("neighbour_radius_factor", 0.0), ("neighbour_k", 2), ("min_neighbours", 1),
     ("fault_threshold", -1.0), ("damage_threshold", 5.0), ("min_component_cells", -3),
     ("smooth_sigma_cells", 50.0), ("thickness_cells", 60.0), ("centreline_window_cells", 0),
     ("neighbour_k", 2.5), ("fault_threshold", float("nan"))],
)
def test_config_validation_names_field(field, value):
    with pytest.raises(ConfigError, match=field):
        LabelConfig(**{field: value}).validate()


def test_config_from_mapping():
    assert LabelConfig.from_mapping({"fault_threshold": 1.0}).fault_threshold == 1.0
    with pytest.raises(ConfigError, match="unknown key"):
        LabelConfig.from_mapping({"treshold": 1.0})
    LabelConfig().validate()


def test_thin_bands_survive_thinning():
    # Zhang-Suen would erase a two-cell-thick diagonal line; Guo-Hall keeps it
    m = np.zeros((40, 40), bool)
    for i in range(5, 35):
        m[i, i] = m[i, i + 1] = True
    line = thin_and_dilate(m, 1.0)
    assert line.sum() >= 25
    assert mask_thickness_cells(m) == pytest.approx(np.sqrt(2), rel=0.25)


@pytest.mark.parametrize("method", ["slip_trace", "strain_band"])
def test_label_maps_gives_the_schema_engine_labels(pack_small, method):
    """Both methods give every engine label of demseis.schema, in store order and dtype, with
    and without a fault."""
    xy, r = pack_small
    grid = Grid.covering(800.0, 500.0, 10.0)
    for cur in (xy, kinematic_fault(xy, x_m=500.0, dip_deg=60.0, slip_m=80.0)):
        snaps = [snap_of(xy, r, index=0), snap_of(cur, r, index=1)]
        maps = label_maps(snaps[1], strain_history(snaps)[1], grid, LabelConfig(method=method),
                          displacement=displacement_history(snaps)[1])
        assert tuple(maps) == engine_labels()
        for name, a in maps.items():
            assert a.dtype == sample_array(name).np_dtype and a.shape == grid.shape, name
        assert maps["fault"].any() == (cur is not xy)


def test_label_maps_fails_on_an_engine_label_it_does_not_make(pack_small):
    xy, r = pack_small
    grid = Grid.covering(800.0, 500.0, 10.0)
    snaps = [snap_of(xy, r, index=0), snap_of(xy, r, index=1)]
    hist, disp = strain_history(snaps), displacement_history(snaps)
    extra = SampleArray("throw_m", "float32", "label", "m", "throw of the nearest fault")
    with SAMPLE_ARRAYS.registered("throw_m", extra):  # no producer: an engine label
        for method in ("slip_trace", "strain_band"):
            with pytest.raises(InputError, match=r"missing \['throw_m'\]"):
                label_maps(snaps[1], hist[1], grid, LabelConfig(method=method),
                           displacement=disp[1])
    assert "throw_m" not in label_maps(snaps[1], hist[1], grid, displacement=disp[1])
