"""demseis: labelled synthetic seismic from discrete-element fault models.

Importing :mod:`demseis` is light: it does not import torch, dask or matplotlib.
Subpackages:

- :mod:`demseis.dem`       2D discrete element model (Numba) and normal-fault boundary conditions
- :mod:`demseis.seismic`   rock properties, rasterisation, impedance, reflectivity, wavelets, noise
- :mod:`demseis.labels`    strain from element displacements, fault / damage / layer labels, scoring
- :mod:`demseis.datasets`  sharded Zarr store, validation, PyTorch Dataset
- :mod:`demseis.generator` config, scenario sampling, dask sweep, CLI
"""

from demseis.errors import DemseisError

__version__ = "0.1.0"

__all__ = ["DemseisError", "__version__"]
