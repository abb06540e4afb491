"""``[labels] throw_from = "offset"``: picked faults drawn where the reflectors are offset by at
least ``min_throw_samples``, measured on the reference map at the output grid."""

from __future__ import annotations

import numpy as np
import pytest

from demseis.errors import ConfigError
from demseis.generator.config.sampling import plan_run
from demseis.generator.config.settings import load_config, parse_config
from demseis.generator.engines.planar import planar_model, reflectivity_strata

THROW_M = 60.0


def _cfg(**labels):
    """The planar preset, one fault of 60 m throw per run, the given ``[labels]`` keys."""
    raw = load_config(preset="planar").to_dict()
    raw["sweep"].update({"n_runs": 3, "planar_faults": 1, "planar_throw_min_m": THROW_M,
                         "planar_throw_max_m": THROW_M})
    raw["labels"] = {**raw.get("labels", {}), **labels}
    return parse_config(raw)


def _final_fault(cfg, run):
    """The final snapshot's ``fault`` array of ``run`` and the fault's throw in samples there
    (the planar engine's Vp is constant: 2 throw / (vp dt))."""
    from demseis.generator.sweep.pipeline import run_shard

    shard = run_shard(cfg, run)
    i = int(np.flatnonzero(shard.params["snapshot"] == cfg.model.n_snapshots - 1)[0])
    p = plan_run(cfg, run).params
    vp = float(np.unique(reflectivity_strata(cfg, p, run, planar_model(cfg, p, run)).vp_m_s)[0])
    return shard.arrays["fault"][i] > 0, 2.0 * THROW_M / (vp * cfg.output.dt_s)


def test_a_known_throw_is_drawn_below_it_and_not_above_it():
    for run in range(3):
        slip, throw = _final_fault(_cfg(), run)
        assert slip.sum() > 50
        below, _ = _final_fault(_cfg(throw_from="offset", min_throw_samples=0.8 * throw), run)
        above, _ = _final_fault(_cfg(throw_from="offset", min_throw_samples=1.25 * throw), run)
        # the offset-measured picks are the slip picks where the throw is read correctly
        near = np.zeros_like(slip)
        ys, xs = np.nonzero(slip)
        for dy in (-1, 0, 1):
            for dx in (-1, 0, 1):
                near[np.clip(ys + dy, 0, slip.shape[0] - 1), np.clip(xs + dx, 0, slip.shape[1] - 1)] = True
        assert below.sum() >= 0.8 * slip.sum(), run
        assert (below & near).sum() >= 0.95 * below.sum(), run
        assert not above.any(), run


def test_offset_needs_the_strata_rendering_and_an_odd_window():
    raw = load_config(preset="planar").to_dict()
    raw["labels"] = {"throw_from": "offset"}
    raw["output"]["rendering"] = "elements"
    with pytest.raises(ConfigError, match="throw_from.*rendering"):
        parse_config(raw)
    with pytest.raises(ConfigError, match="offset_window_traces"):
        _cfg(throw_from="offset", offset_window_traces=4)
    with pytest.raises(ConfigError, match="throw_from"):
        _cfg(throw_from="strain")
