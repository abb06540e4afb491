"""demseis_dev: code that measures, calibrates and times demseis, not part of it.

A package at the root of the checkout, beside ``demseis`` and not installed with it: no module
of ``demseis`` imports it (checked by ``tests/test_layout.py``); the tests (pytest's
``pythonpath``), the scripts of ``benchmarks/`` and ``scripts/`` (which put the checkout on
``sys.path``) and ``python -m demseis_dev.bench`` use it. Keeping it apart lets the product
change without carrying these tools, and lets them reach into any stage's internals (they look
at the engine, not through the API).

- :mod:`~demseis_dev.bench`: the stage speed benchmarks, each returning one JSON-ready dict;
  ``python -m demseis_dev.bench dem|seismic|labels|loader`` prints one JSON line;
- :mod:`~demseis_dev.calibrate`: the biaxial test of a DEM material (bulk friction angle
  and cohesion);
- :mod:`~demseis_dev.measure`: measures of a faulted assembly taken from its particles
  (horizon steps, displacement jumps, fault dips per unit);
- :mod:`~demseis_dev.coverage`: how much of the particles' displacement jump a fault
  label covers;
- :mod:`~demseis_dev.toys`: toy inputs (disk packs, a kinematic normal fault, toy
  sections) for tests, benchmarks and figure scripts.

The modules are imported one by one (``from demseis_dev.toys import disk_pack``);
this file imports none of them.
"""
