"""The picked fault target against kinematic faults of known geometry, and its shape on DEM runs."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

import demseis
from demseis.generator.config.layout import grid_of, trace_spacing
from demseis.generator.config.sampling import SEED_DEM, plan_run, rng_at
from demseis.generator.engines import get_engine
from demseis.generator.engines.kinematic import kinematic_faults
from demseis_dev.picks import kinematic_agreement, planar_fault_sweep, shape_counts, true_trace


def _pooled(rows, key, weight):
    return sum(r[key] * r[weight] for r in rows) / sum(r[weight] for r in rows)


@pytest.mark.parametrize("domain,throw,taper", [("time", (3.0, 30.0), 1.0),
                                                ("time", (20.0, 200.0), 0.5),
                                                ("depth", (5.0, 60.0), 1.0)])
def test_picks_lie_on_the_true_trace_and_find_it_where_the_throw_shows(domain, throw, taper):
    cfg = planar_fault_sweep(domain, throw, taper, 6)
    rows = kinematic_agreement(cfg, list(range(6)))
    assert sum(r["label_px"] for r in rows) > 200
    assert _pooled(rows, "on_trace", "label_px") >= 0.95
    assert _pooled(rows, "found", "visible_px") >= 0.95


def test_the_check_fails_for_a_trace_three_traces_off():
    cfg = planar_fault_sweep("time", (20.0, 200.0), 0.5, 6)
    engine = get_engine("kinematic")
    spec = plan_run(cfg, 0)
    er = engine.simulate(cfg, spec)
    fault = kinematic_faults(cfg, spec.params, 0, er.info, rng_at(cfg, 0, SEED_DEM))[0]
    vp = np.full((grid_of(cfg).nz, 80), 2500.0)
    here, _ = true_trace(cfg, fault, 1.0, vp)
    off, _ = true_trace(cfg, dataclasses.replace(fault, x_m=fault.x_m + 3 * trace_spacing(cfg)),
                        1.0, vp)
    assert here.sum() > 50 and off.sum() > 50
    rows_here = {(r, c) for r, c in zip(*np.nonzero(here))}
    shifted = {(r, c - 3) for r, c in zip(*np.nonzero(off))}
    assert len(rows_here & shifted) >= 0.9 * len(rows_here)     # the same line, 3 traces over
    assert not (here & off).any()


def test_picked_dem_labels_have_no_loops_or_rungs(tiny_store):
    store = demseis.open(tiny_store)
    seen = 0
    for i in range(len(store.params["run_id"])):
        s = store.sample(i)
        counts = shape_counts(s["fault"], s["fault_id"])
        seen += int(s["fault"].any())
        assert counts["instance_loops"] == 0, i
        assert counts["instance_rung_fraction"] == 0.0, i
        assert counts["rung_fraction"] == 0.0, i
    assert seen > 0


def test_shape_counts_see_a_loop_and_a_rung():
    mask = np.zeros((40, 40), np.uint8)
    fid = np.zeros((40, 40), np.int16)
    mask[5:35, 10] = 1
    mask[5:35, 20] = 1
    mask[20, 10:21] = 1                    # a flat rung between two lines, one fault
    fid[mask > 0] = 1
    counts = shape_counts(mask, fid)
    assert counts["instance_rung_fraction"] > 0.1 and counts["rung_fraction"] > 0.1
    ring = np.zeros((40, 40), np.uint8)
    ring[10, 10:30] = ring[30, 10:30] = ring[10:31, 10] = ring[10:31, 29] = 1
    assert shape_counts(ring, ring.astype(np.int16))["instance_loops"] == 1
    assert shape_counts(np.zeros((5, 5)), np.zeros((5, 5)))["loops"] == 0
