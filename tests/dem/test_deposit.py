"""Syn-tectonic deposits never overlap the existing assembly, also beside a surface scarp, and
relaxed deposits do not overlap each other either.

Regression: the column-floor cut alone let a new disk sit metres inside an old disk whose
centre was 1.5-2 r_max away sideways (next to a fault scarp); the ~1e11 N overlap force blew
up the quick preset's run 0 (kinetic-energy blow-up at step 13709). A deposit cut from the
settled pack keeps its lithostatic overlaps (up to metres across the periodic seam), whose
release at the surface blew up the seed preset's run 6 on every slower try.
"""

from __future__ import annotations

import numpy as np
import pytest

from demseis.dem import settle_pack
from demseis.dem.fault import _deposit, _unoverlapped

from ._helpers import overlaps, pair_overlaps


class _Sink:
    """The part of Integrator that _deposit uses."""

    def __init__(self, pos: np.ndarray, radius: np.ndarray) -> None:
        self.pos = pos
        self.radius = radius
        self.added_xy = np.zeros((0, 2))
        self.added_r = np.zeros(0)

    def add_elements(self, xy: np.ndarray, r: np.ndarray) -> None:
        self.added_xy = np.asarray(xy)
        self.added_r = np.asarray(r)


@pytest.fixture(scope="module")
def pack():
    return settle_pack(1000.0, 400.0, rng=3)


@pytest.mark.parametrize("seed", range(16))
def test_deposit_clears_bumps_on_the_surface(pack, seed):
    """Isolated disks standing on a flat bed (a rough scarp top): the column floor misses a bump
    whose centre is 1.5-2 r_max away sideways, the exact overlap check must not."""
    rng = np.random.default_rng(seed)
    bed = pack.xy[:, 1] < 300.0
    xy, r = pack.xy[bed], pack.radius[bed]
    bump_x = np.arange(60.0, 960.0, 90.0) + rng.uniform(-20.0, 20.0)
    bump_xy = np.c_[bump_x, np.full(bump_x.size, 320.0)]
    xy = np.vstack([xy, bump_xy])
    r = np.concatenate([r, np.full(bump_x.size, 25.0)])
    sink = _Sink(xy, r)
    added = _deposit(sink, 0.0, 1000.0, 460.0, pack.xy, pack.radius, 1000.0, 400.0, rng)
    assert added == sink.added_r.size > 0
    overlap = overlaps(sink.added_xy, sink.added_r, xy, r)
    assert overlap.max() <= 0.0, f"a deposit overlaps an old disk by {overlap.max():.2f} m"


def test_unoverlapped_against_a_pairwise_reference():
    """Disks of a settled pack overlap by their lithostatic load; after _unoverlapped no pair
    does, no kept disk is below r_min, and each disk lost exactly the largest half-overlap of
    its pairs (computed here pair by pair)."""
    pack = settle_pack(600.0, 400.0, rng=5)
    xy, r = pack.xy, pack.radius
    before = pair_overlaps(xy, r)
    assert before.max() > 0.1                      # the pack does hold overlaps to remove
    r_min = float(r.min())
    out, kept = _unoverlapped(xy, r, r_min)
    assert kept.any() and out[kept].min() >= r_min
    assert pair_overlaps(xy[kept], out[kept]).max() <= 1e-9
    n = r.size
    for i in range(0, n, max(n // 40, 1)):        # the slow obvious loss of 40 disks
        half = [0.5 * (r[i] + r[j] - np.hypot(*(xy[i] - xy[j]))) for j in range(n) if j != i]
        assert out[i] == pytest.approx(r[i] - max(0.0, max(half)), abs=1e-9)
    # a disk that would fall below r_min is dropped, not shrunk below it
    two = np.array([[0.0, 0.0], [15.0, 0.0]])
    out, kept = _unoverlapped(two, np.array([10.0, 10.0]), 9.0)
    assert kept.tolist() == [False, False] and out.tolist() == [7.5, 7.5]
    out, kept = _unoverlapped(two[:1], np.array([10.0]), 9.0)
    assert kept.tolist() == [True] and out.tolist() == [10.0]


@pytest.mark.parametrize("seed", range(4))
def test_relaxed_deposit_overlaps_nothing(pack, seed):
    """A deposit cut across the template's periodic seam: without relaxing, new disks overlap
    each other (the pack's contacts); relaxed, neither each other nor the old disks."""
    rng = np.random.default_rng(seed)
    bed = pack.xy[:, 1] < 150.0
    xy, r = pack.xy[bed], pack.radius[bed]
    raw = _Sink(xy, r)
    assert _deposit(raw, 0.0, 2500.0, 400.0, pack.xy, pack.radius, 1000.0, 400.0,
                    np.random.default_rng(seed)) > 0
    assert pair_overlaps(raw.added_xy, raw.added_r).max() > 0.05
    sink = _Sink(xy, r)
    added = _deposit(sink, 0.0, 2500.0, 400.0, pack.xy, pack.radius, 1000.0, 400.0, rng,
                     relax=True)
    assert added == sink.added_r.size > 0.9 * raw.added_r.size
    assert sink.added_r.min() >= pack.radius.min()
    assert pair_overlaps(sink.added_xy, sink.added_r).max() <= 1e-9
    assert overlaps(sink.added_xy, sink.added_r, xy, r).max() <= 0.0
