"""Mechanical stratigraphy: contact properties per layer drawn from the layer's lithology.

Competent lithologies (sandstone, limestone, carbonate, dolomite) are *strong*; the others
(shale, mudstone, ...) are *weak*. With a strength contrast ``s >= 1`` and a base Material:

- strong: cohesion ``C0 * sqrt(s)``, friction ``mu``, Kn ``Kn`` (the base stiffness);
- weak: cohesion ``C0 / sqrt(s)``, friction ``mu / min(sqrt(s), 2)`` (at most halved), Kn
  ``Kn / min(s, 4)`` (at most 4x softer; dt is set by the largest Kn, so this costs nothing);
- the bond strain r0 of both is the base's.

The ratios stay within what rocks show: unconfined strength of sandstone and limestone against
shale up to about 10x, Young's modulus 1-5x, friction coefficient 0.6-0.85 against 0.2-0.4 for
clay-rich shale. The stiffness contrast is what makes faults refract (steeper in the stiff,
strong layers: docs/dem.md, "Refraction"); cohesion alone does not.

``s = 1`` gives every layer the base material (uniform mechanics). Each value is clipped to
its field's stage domain (:meth:`demseis.parameters.Param.stage`, the range the DEM accepts), so
a base material at the edge of its range still gives layers the DEM accepts; weak layers may be
softer or weaker than a config's range (Kn / 4 of the lowest declared Kn).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence

from demseis.dem.types import Material
from demseis.errors import InputError
from demseis.parameters import PARAMS

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
    strong = dataclasses.replace(base, cohesion_n=_clip("cohesion_n", base.cohesion_n * root))
    weak = dataclasses.replace(base, cohesion_n=_clip("cohesion_n", base.cohesion_n / root),
                               friction=_clip("friction", base.friction / min(root, 2.0)),
                               kn_n_m=_clip("kn_n_m", base.kn_n_m / min(contrast, 4.0)))
    return [strong if is_strong(name) else weak for name in lithologies]


def _clip(name: str, value: float) -> float:
    """``value`` clipped to the stage domain of parameter ``name``."""
    p = PARAMS[name].stage()
    return min(max(value, float(p.lo)), float(p.hi))


def alternation(n_layers: int, unit_layers: int, strong: str = "sandstone",
                weak: str = "shale") -> list[str]:
    """Lithology names of ``n_layers`` layers in units of ``unit_layers`` alternating strong
    and weak from the base (the first unit is strong)."""
    if n_layers < 1 or unit_layers < 1:
        raise InputError(f"n_layers={n_layers} and unit_layers={unit_layers} must be >= 1")
    return [strong if (k // unit_layers) % 2 == 0 else weak for k in range(n_layers)]
