"""demseis.generator: from a config to a store, in four layers, each importing only those before it.

- :mod:`~demseis.generator.config`: what a config means: its parameters and distributions
  (``params``), the parsed config (``settings``), the runs and renders drawn from it
  (``sampling``), and the grid, traces and arrays of its store (``layout``);
- :mod:`~demseis.generator.engines`: the engine protocol and table, the engines (DEM,
  kinematic, planar), the set-up shared by every run (``runsetup``) and the DEM's physics
  checks (``physics``);
- :mod:`~demseis.generator.render`: a run's states imaged and labelled into samples
  (``section``), with the survey sampling and the ``strata`` rendering (``survey``);
- :mod:`~demseis.generator.sweep`: the sweep that writes a store (``driver``), one run from
  simulation to shard (``pipeline``), the worker processes (``workers``), re-rendering a stored
  store (``rerender``) and the fault-system summary of ``demseis info`` (``faultinfo``).

``tests/test_layout.py`` checks the order.
"""
