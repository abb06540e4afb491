"""Shared fixtures: dense polydisperse disk packs (radii 12.5-25 m) built in-tree."""

from __future__ import annotations

import numpy as np
import pytest

from demseis_dev.toys import disk_pack


@pytest.fixture(scope="session")
def pack_small():
    """~330 disks in 800 m x 500 m."""
    return disk_pack(800.0, 500.0, np.random.default_rng(11))


@pytest.fixture(scope="session")
def pack_fault():
    """Two ~1300-disk packs in 2000 m x 1000 m for the kinematic-fault checks."""
    return [disk_pack(2000.0, 1000.0, np.random.default_rng(s)) for s in (1, 2)]
