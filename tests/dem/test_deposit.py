"""Syn-tectonic deposits never overlap the existing assembly, also beside a surface scarp.

Regression: the column-floor cut alone let a new disk sit metres inside an old disk whose
centre was 1.5-2 r_max away sideways (next to a fault scarp); the ~1e11 N overlap force blew
up the quick preset's run 0 (kinetic-energy blow-up at step 13709).
"""

from __future__ import annotations

import numpy as np
import pytest

from demseis.dem import settle_pack
from demseis.dem.fault import _deposit


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
    d = np.hypot(sink.added_xy[:, None, 0] - xy[None, :, 0], sink.added_xy[:, None, 1] - xy[None, :, 1])
    overlap = (sink.added_r[:, None] + r[None, :]) - d
    assert overlap.max() <= 0.0, f"a deposit overlaps an old disk by {overlap.max():.2f} m"
