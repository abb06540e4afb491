"""Faults refract through a strong-weak alternation: steeper in the competent layers.

Seed scale (5 km x 2.77 km, 45 deg basement normal fault, 450 m throw), 24 layers in 2-layer
units alternating sandstone and shale from the base, a brittle cover whose strong layers are
:data:`demseis.dem.BRITTLE` (strength contrast 9 about a base cohesion of BRITTLE's / 3: weak
layers 9x lower cohesion, 4x softer, half the friction; :func:`demseis.dem.strata.layer_materials`).
The dip of the fault in each unit is fitted in reference coordinates
(:func:`demseis_dev.measure.unit_dips`, checked on a kinematic fault with imposed
refraction in ``tests/demseis_dev/test_measure.py``). The same runs with uniform mechanics are
the control: the dip of a brittle fault wanders from unit to unit by itself (per run the
control's strong-minus-weak difference was -3.7 to +8 deg over three seeds, docs/dem.md), so
two seeds are averaged and the contrast must beat its own control.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from demseis.dem import BRITTLE, NormalFault, build_assembly, settle_pack, simulate
from demseis.dem.strata import alternation, is_strong, layer_materials
from demseis_dev.measure import strong_weak_dips

N_LAYERS, UNIT = 24, 2


@pytest.mark.slow
def test_faults_are_steeper_in_strong_layers_by_5_degrees():
    lith = alternation(N_LAYERS, UNIT)
    units = [tuple(range(f, f + UNIT)) for f in range(0, N_LAYERS, UNIT)]
    strong = np.array([is_strong(lith[u[0]]) for u in units])
    base = dataclasses.replace(BRITTLE, cohesion_n=BRITTLE.cohesion_n / 3)
    diff = {9.0: [], 1.0: []}
    for seed in (0, 1):
        pack = settle_pack(5000.0, 2770.0, rng=seed)
        asm = build_assembly(5000.0, 2770.0, n_layers=N_LAYERS, pack=pack)
        for contrast in diff:
            snaps = simulate(asm, NormalFault(), base, n_snapshots=6, rng=seed,
                             layer_materials=layer_materials(lith, base, contrast))
            d_strong, d_weak, _ = strong_weak_dips(snaps[0], snaps[-1], units, strong, 2500.0)
            diff[contrast].append(d_strong - d_weak)
    assert np.mean(diff[9.0]) >= 5.0, diff
    assert np.mean(diff[9.0]) - np.mean(diff[1.0]) >= 5.0, diff
