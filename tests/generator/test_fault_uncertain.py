"""``[labels] fault_uncertain = true``: the ``fault_uncertain`` array, where the fault label and
the reflectors' visible offsets disagree, stored beside unchanged labels and seismic."""

from __future__ import annotations

import numpy as np
import pytest

from demseis.errors import ConfigError
from demseis.generator.config.settings import load_config, parse_config
from demseis.generator.sweep.pipeline import run_shard
from demseis.labels.offsets import LABEL_NOT_SHOWN, OFFSET_NOT_LABELLED
from tests.generator.test_throw_from_offset import _cfg  # one planar fault of 60 m throw


def test_the_array_is_added_and_nothing_else_changes():
    for run in range(2):
        plain = run_shard(_cfg(), run)
        shard = run_shard(_cfg(fault_uncertain=True), run)
        assert "fault_uncertain" not in plain.arrays
        assert set(shard.arrays) == set(plain.arrays) | {"fault_uncertain"}
        for name, a in plain.arrays.items():
            np.testing.assert_array_equal(shard.arrays[name], a, err_msg=name)
        unc, fault = shard.arrays["fault_uncertain"], shard.arrays["fault"] > 0
        assert set(np.unique(unc).tolist()) <= {0, 1, 2}
        assert not (unc == LABEL_NOT_SHOWN)[~fault].any()      # class 1 only on labels
        assert not (unc == OFFSET_NOT_LABELLED)[fault].any()   # class 2 only off them


def test_a_planar_fault_is_labelled_where_it_offsets_the_reflectors():
    """A pasted plane offsets the reflectors by its whole throw along its length, and its
    label follows it: label and offsets agree almost everywhere, on every snapshot with
    labels."""
    for run in range(2):
        shard = run_shard(_cfg(fault_uncertain=True), run)
        fault = shard.arrays["fault"] > 0
        unc = shard.arrays["fault_uncertain"]
        assert fault.sum() > 100
        assert (unc == LABEL_NOT_SHOWN).sum() <= 0.02 * fault.sum(), run
        assert (unc == OFFSET_NOT_LABELLED).sum() <= 0.02 * fault.sum(), run


def test_it_needs_the_strata_rendering():
    raw = load_config(preset="planar").to_dict()
    raw["labels"] = {"fault_uncertain": True}
    raw["output"]["rendering"] = "elements"
    with pytest.raises(ConfigError, match="fault_uncertain.*rendering"):
        parse_config(raw)
