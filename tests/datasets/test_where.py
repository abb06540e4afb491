"""``where=`` filters: category names, numbers as strings, unknown values, empty selections."""

from __future__ import annotations

import numpy as np
import pytest

from demseis.datasets import FaultSegDataset, ParamSpec
from demseis.errors import InputError
from tests.datasets._helpers import PARAMS, make_store

S = 6
CAT_PARAMS = {**PARAMS, "noise_kind": ParamSpec("int8", categories=("white", "band"))}


@pytest.fixture(scope="module")
def store(tmp_path_factory):
    return make_store(tmp_path_factory.mktemp("where") / "s.zarr", n_shards=3, s=S,
                      shape=(8, 8), params=CAT_PARAMS)


def _kinds(ds):
    return [ds.params(i)["noise_kind"] for i in range(len(ds))]


def test_category_names_select_like_their_codes(store):
    band = FaultSegDataset(store, where={"noise_kind": "band"})
    assert len(band) == 9 and set(_kinds(band)) == {1}
    np.testing.assert_array_equal(band.indices,
                                  FaultSegDataset(store, where={"noise_kind": 1}).indices)
    both = FaultSegDataset(store, where={"noise_kind": ["white", "band"]})
    assert len(both) == 18


def test_unknown_category_lists_the_valid_ones(store):
    with pytest.raises(InputError, match=r"'pink' is not a category of noise_kind; valid: "
                                         r"'white', 'band'"):
        FaultSegDataset(store, where={"noise_kind": "pink"})
    with pytest.raises(InputError, match=r"expected one of 'white', 'band'"):
        FaultSegDataset(store, where={"noise_kind": 7})


def test_inf_as_a_string(store):
    noiseless = FaultSegDataset(store, where={"snr_db": "inf"})
    assert len(noiseless) == 9
    np.testing.assert_array_equal(noiseless.indices,
                                  FaultSegDataset(store, where={"snr_db": float("inf")}).indices)
    assert len(FaultSegDataset(store, where={"snr_db": ("5", "inf")})) == 18
    with pytest.raises(InputError, match=r"where\['snr_db'\] = 'loud': expected a number"):
        FaultSegDataset(store, where={"snr_db": "loud"})


def test_empty_selection_is_an_error_naming_the_filter(store):
    with pytest.raises(InputError, match=r"where=\{'freq_hz': 25\} selects none of the 18 done"):
        FaultSegDataset(store, where={"freq_hz": 25})
    with pytest.raises(InputError, match="selects none"):
        FaultSegDataset(store, where={"noise_kind": "band", "snr_db": "inf"})  # never together
