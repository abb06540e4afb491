"""demseis.diagnostics: code that measures, calibrates and times demseis, not part of it.

Nothing that generates, stores, reads or scores a data set imports this subpackage (checked by
``tests/test_layout.py``); only the ``demseis bench`` command (:mod:`demseis.cli.bench`, inside
its handlers), the scripts of ``benchmarks/`` and ``scripts/`` and the tests use it. Keeping it
apart lets the product change without carrying these tools, and lets them reach into any stage's
internals (they look at the engine, not through the API).

- :mod:`~demseis.diagnostics.bench`: what ``demseis bench dem|seismic|labels|loader`` times,
  each returning one JSON-ready dict;
- :mod:`~demseis.diagnostics.calibrate`: the biaxial test of a DEM material (bulk friction angle
  and cohesion);
- :mod:`~demseis.diagnostics.measure`: measures of a faulted assembly taken from its particles
  (horizon steps, displacement jumps, fault dips per unit);
- :mod:`~demseis.diagnostics.coverage`: how much of the particles' displacement jump a fault
  label covers;
- :mod:`~demseis.diagnostics.toys`: toy inputs (disk packs, a kinematic normal fault, toy
  sections) for tests, benchmarks and figure scripts.

The modules are imported one by one (``from demseis.diagnostics.toys import disk_pack``);
this file imports none of them.
"""
