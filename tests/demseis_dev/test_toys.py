"""The toy inputs of demseis_dev.toys: one kinematic fault model behind every toy."""

import numpy as np

from demseis_dev.toys import (disk_pack, down_dip_vector, fault_signed_distance, faulted_section,
                              faulted_sequence, kinematic_fault)


def test_toy_sequence_geometry():
    snaps = faulted_sequence(1000.0, 600.0, n_layers=6, throw_m=120.0, dip_deg=60.0,
                             n_snapshots=4, rng=np.random.default_rng(0))
    assert [s.throw_m for s in snaps] == [0.0, 40.0, 80.0, 120.0]
    first, last = snaps[0], snaps[-1]
    np.testing.assert_array_equal(last.ids[: first.n], first.ids)  # ids are stable
    moved = np.linalg.norm(last.xy[: first.n] - first.xy, axis=1)
    # rigid hanging wall: moved by throw / sin(dip) down-dip, footwall not at all
    np.testing.assert_allclose(np.unique(np.round(moved, 6)), [0.0, 120.0 / np.sin(np.radians(60))])
    assert last.layer.max() == 6 + 3 - 1 and last.deposited.sum() > 0


def test_sequence_matches_kinematic_fault():
    """The hanging wall of the sequence is where kinematic_fault moves points, by the same vector."""
    snaps = faulted_sequence(1000.0, 600.0, n_layers=6, throw_m=90.0, dip_deg=50.0,
                             x_fault_m=600.0, n_snapshots=2, rng=np.random.default_rng(3))
    ref = snaps[0].xy
    expected = kinematic_fault(ref, x_m=600.0, dip_deg=50.0, slip_m=90.0 / np.sin(np.radians(50)))
    np.testing.assert_allclose(snaps[1].xy[: ref.shape[0]], expected, atol=1e-9)


def test_kinematic_fault_displacement_and_sides():
    xy, _ = disk_pack(600.0, 400.0, np.random.default_rng(0))
    d = fault_signed_distance(xy, 300.0, 60.0)
    cur = kinematic_fault(xy, x_m=300.0, dip_deg=60.0, slip_m=50.0)
    disp = cur - xy
    np.testing.assert_allclose(disp[d > 0], np.broadcast_to(50.0 * down_dip_vector(60.0),
                                                           disp[d > 0].shape))
    assert np.all(disp[d <= 0] == 0)
    # left-dipping: mirror image
    cur_l = kinematic_fault(xy * [-1, 1], x_m=-300.0, dip_deg=60.0, slip_m=50.0,
                            dip_direction="left")
    np.testing.assert_allclose(cur_l * [-1, 1], cur)


def test_faulted_section_offsets_the_hanging_wall():
    sec, truth = faulted_section(nz=64, nx=64, throw=8.0, regional=0.0, seed=1)
    unfaulted, none = faulted_section(nz=64, nx=64, throw=8.0, regional=0.0, seed=1, fault=False)
    assert none.sum() == 0 and truth.sum() > 0
    np.testing.assert_allclose(sec[:, 0], unfaulted[:, 0])      # footwall column unchanged
    np.testing.assert_allclose(sec[20:50, -1], unfaulted[12:42, -1], atol=1e-6)  # 8 samples down
