"""Mechanical stratigraphy: contact properties per layer drawn from the layer's lithology.

Competent lithologies (sandstone, limestone, carbonate, dolomite) are *strong*; the others
(shale, mudstone, ...) are *weak*. With a strength contrast ``s >= 1`` and a base Material:

- strong: cohesion ``C0 * sqrt(s)``, friction ``mu``, Kn ``Kn`` (the base stiffness);
- weak: cohesion ``C0 / sqrt(s)``, friction ``mu * (1 - 0.25 (1 - 1/s))`` (at most 25% lower),
  Kn ``Kn / 2`` (softer; dt is set by the largest Kn, so this costs nothing);
- the bond strain r0 of both is the base's.

``s = 1`` gives every layer the base material (uniform mechanics).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence

from demseis.dem.types import Material
from demseis.errors import InputError

STRONG_LITHOLOGIES = ("sandstone", "limestone", "carbonate", "dolomite")


def is_strong(lithology: str) -> bool:
    """True for a competent lithology (see :data:`STRONG_LITHOLOGIES`)."""
    return lithology.lower() in STRONG_LITHOLOGIES


def layer_materials(lithologies: Sequence[str], base: Material, contrast: float
                    ) -> list[Material]:
    """One Material per layer from its lithology name (see the module docstring).

    Parameters
    ----------
    lithologies : lithology name of each pre-kinematic layer, bottom to top.
    base : the run's material (model, damping and the rest are kept).
    contrast : strength contrast s >= 1 between strong and weak layers.
    """
    if not (math.isfinite(contrast) and contrast >= 1.0):
        raise InputError(f"strength contrast={contrast!r} must be >= 1")
    root = math.sqrt(contrast)
    strong = dataclasses.replace(base, cohesion_n=base.cohesion_n * root)
    weak = dataclasses.replace(base, cohesion_n=base.cohesion_n / root,
                               friction=base.friction * (1 - 0.25 * (1 - 1 / contrast)),
                               kn_n_m=base.kn_n_m / 2 if contrast > 1 else base.kn_n_m)
    return [strong if is_strong(name) else weak for name in lithologies]
