"""demseis: labelled synthetic seismic from discrete-element fault models.

The front door (:mod:`demseis.api`)::

    import demseis
    store = demseis.generate("tiny", out="t.zarr")   # run a sweep -> demseis.Store
    store = demseis.open("t.zarr")                   # samples, params, torch_dataset(), to_xarray()
    result = demseis.score(pred, store)              # precision / recall / F1 / IoU / AP
    demseis.train(store, out="model.pt")             # a U-Net (needs demseis[torch])
    demseis.predict("model.pt", "in.sgy", out="out.sgy")  # fault probability of any section
    demseis.fit("survey.sgy", out="survey.toml")     # a config that looks like a survey

Importing :mod:`demseis` is light: it does not import torch, dask, matplotlib or even NumPy;
the names above load on first use. Subpackages, in data-flow order:

- :mod:`demseis.dem`        2D discrete element model (Numba) and normal-fault boundary conditions
- :mod:`demseis.seismic`    rock properties, rasterisation, impedance, reflectivity, wavelets, noise
- :mod:`demseis.labels`     strain from element displacements; fault, damage-zone and layer labels
- :mod:`demseis.datasets`   the sharded Zarr store (every read and write), the PyTorch Dataset
- :mod:`demseis.evaluation` scoring predictions against a store, a no-learning baseline
- :mod:`demseis.generator`  config, scenario sampling, the dask sweep
- :mod:`demseis.cli`        the ``demseis`` command
- :mod:`demseis.parameters` every parameter declared once (``demseis params``)
- :mod:`demseis.types`      the shared :class:`~demseis.types.Grid` and :class:`~demseis.types.Snapshot`

Beside them, in the checkout but not installed, ``demseis_dev`` holds what measures and times
the package (stage speed benchmarks, the DEM biaxial calibration, particle measures, toy
inputs); nothing above imports it.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from demseis.errors import DemseisError

__version__ = "0.1.0"

__all__ = ["DemseisError", "Store", "__version__", "fit", "generate", "open", "predict", "score",
           "train"]

_API = ("Store", "generate", "open", "predict", "score", "train")

if TYPE_CHECKING:  # pragma: no cover
    from demseis.api import Store, generate, open, predict, score, train  # noqa: A004
    from demseis.survey_fit import fit


def __getattr__(name: str) -> Any:
    if name == "fit":
        # lazy: demseis.fit(sections, out=...) -> FitResult (demseis.survey_fit)
        from demseis.survey_fit import fit

        return fit
    if name in _API:
        # lazy: the front door; `import demseis` must not import NumPy (tests/test_import.py)
        from demseis import api

        return getattr(api, name)
    raise AttributeError(f"module 'demseis' has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_API) | {"fit"})
