"""``python -m demseis`` is the same as the ``demseis`` console script."""

from demseis.cli import main

raise SystemExit(main())
