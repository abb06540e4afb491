"""A plug-in outside the package, as a user's own module would be: the toy engine and label
array of ``_flat.py``. The sweep test with dask workers names this module in the config
(``plugins = ["tests.generator._plugin"]``, ``engine = "tests.generator._plugin:FLAT"``), so
that every worker imports it. Importing it registers :data:`PARITY`, so only subprocesses
import it (the test's own process would store the array in every later store)."""

from __future__ import annotations

from demseis.schema import SAMPLE_ARRAYS, register_array
from tests.generator._flat import FLAT, PARITY

__all__ = ["FLAT", "PARITY"]

if "layer_parity" not in SAMPLE_ARRAYS:
    register_array(PARITY)
