"""The sample schema: every per-sample array a store holds, declared once.

Each :class:`SampleArray` gives an array's name, dtype, role (a network ``input`` or a
``label``), units, description, the value of a cell where there is nothing (no rock, or past
the end of the rock on a time axis), the valid range of an integer label, and how it is made.
The store layout (:mod:`demseis.datasets`), the rendering pipeline's fills and array list
(:mod:`demseis.generator`), the engines' label output, plotting and ``demseis info`` all read
:data:`SAMPLE_ARRAYS`.

How an array is made:

- ``seismic`` and ``impedance`` by the renderer (:data:`RENDERED`), and ``fault_uncertain``
  by the renderer from the labels on the output grid (:data:`RENDERED_LABELS`);
- a label with a ``producer`` by calling it on each geological state of a run (the engine's
  :class:`demseis.generator.engines.State`): ``producer(state) -> (nz, nx)`` array on the
  depth grid, converted to time by the pipeline like every label;
- every other label by the engine itself (``State.labels[name]``).

A new label array is one :func:`register_array` call with its producer::

    from demseis.schema import SampleArray, register_array
    register_array(SampleArray("fault_wide", "uint8", "label", "1", "fault mask grown by 1 cell",
                               fill=0, valid_range=(0, 1),
                               producer=lambda s: grow(s.labels["fault"])))

This module imports only NumPy, :mod:`demseis.registry` and :mod:`demseis.errors`.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from demseis.errors import InputError
from demseis.registry import Registry

ROLES = ("input", "label")
#: arrays the renderer makes from the property grids (every other array is a label)
RENDERED = ("seismic", "impedance")
#: labels the renderer makes on the output grid from the engine's labels and the reference map
#: (:func:`demseis.labels.offsets.offset_disagreement`), not the engines
RENDERED_LABELS = ("fault_uncertain",)


@dataclass(frozen=True)
class SampleArray:
    """Declaration of one per-sample (H, W) array.

    Attributes
    ----------
    name : the array's name in the store (units in the name where it has them).
    dtype : fixed on-disk dtype (a NumPy dtype string).
    role : ``"input"`` (what a network reads) or ``"label"`` (a target).
    units : UDUNITS string (``"1"`` for dimensionless values and labels).
    description : what the array holds (the ``long_name`` attribute).
    fill : the value of a cell where there is nothing: above the free surface, and below the
        deepest rock on a two-way-time axis. (The store marks never-written chunks with a
        different value, outside every valid range: NaN, 255 or the dtype minimum.)
    valid_range : inclusive (low, high) of an integer label (high None: unbounded), checked on
        write and by ``validate``; None for float arrays.
    compressed : Blosc-lz4 (labels, strain) or raw (network inputs, read as zero-copy crops).
    option : name of the boolean ``[output]`` or ``[labels]`` key that turns the array on;
        None: always stored.
    producer : ``producer(state) -> (nz, nx)`` array for a label the engines do not make
        (see the module docstring); None for the built-in arrays.
    """

    name: str
    dtype: str
    role: str
    units: str
    description: str
    fill: float | int = 0
    valid_range: tuple[int, int | None] | None = None
    compressed: bool = True
    option: str | None = None
    producer: Callable[[Any], np.ndarray] | None = None

    def __post_init__(self) -> None:
        if self.role not in ROLES:
            raise InputError(f"sample array {self.name!r}: role must be one of {ROLES}, "
                             f"got {self.role!r}")
        try:
            dt = np.dtype(self.dtype)
        except TypeError as exc:
            raise InputError(f"sample array {self.name!r}: dtype {self.dtype!r} is not a NumPy "
                             "dtype") from exc
        if dt.kind not in "iuf":
            raise InputError(f"sample array {self.name!r}: dtype {self.dtype} is not an integer "
                             "or float dtype")
        if self.valid_range is not None and dt.kind == "f":
            raise InputError(f"sample array {self.name!r}: a valid_range is for integer labels")

    @property
    def np_dtype(self) -> np.dtype:
        return np.dtype(self.dtype)

    def store_attributes(self) -> dict[str, Any]:
        """The array's attributes in a store (JSON): the CF pair ``units`` and ``long_name``,
        and under ``demseis`` its ``role``, ``fill``, ``valid_range`` (a list, or None) and
        ``raw`` (stored uncompressed), so that the store describes the array without the code
        that declared it (:func:`spec_from_attributes` reads them back)."""
        rng = None if self.valid_range is None else list(self.valid_range)
        fill = float(self.fill) if self.np_dtype.kind == "f" else int(self.fill)
        return {"units": self.units, "long_name": self.description,
                "demseis": {"role": self.role, "fill": fill, "valid_range": rng,
                            "raw": not self.compressed}}


#: every per-sample array, in store order (a store holds them in this order)
SAMPLE_ARRAYS: Registry[SampleArray] = Registry("sample array", group="demseis.arrays",
                                                paths=False)

for _a in (
    SampleArray("seismic", "float32", "input", "1", "seismic amplitude (band-limited, with noise)",
                fill=0.0, compressed=False),
    SampleArray("fault", "uint8", "label", "1", "fault label: 1 on a slip surface, 0 elsewhere",
                fill=0, valid_range=(0, 1)),
    SampleArray("damage", "uint8", "label", "1",
                "damage class: 0 background, 1 damage zone, 2 fault core", fill=0,
                valid_range=(0, 2)),
    SampleArray("strain", "float32", "label", "1",
                "maximum shear strain since the reference snapshot", fill=0.0),
    SampleArray("layer", "int16", "label", "1", "layer index (-1: no rock, above the free surface)",
                fill=-1, valid_range=(-1, None)),
    SampleArray("fault_id", "int16", "label", "1", "fault instance id on fault cells (0: no fault)",
                fill=0, valid_range=(0, None)),
    SampleArray("slip_m", "float32", "label", "m",
                "slip (displacement jump) of the nearest fault trace", fill=0.0),
    SampleArray("dip_deg", "float32", "label", "degree", "dip of the nearest fault trace",
                fill=0.0),
    SampleArray("sense", "uint8", "label", "1", "sense of slip: 0 none, 1 normal, 2 reverse",
                fill=0, valid_range=(0, 2)),
    SampleArray("impedance", "float32", "input", "kg/(m^2 s)", "acoustic impedance", fill=0.0,
                compressed=False, option="impedance"),
    SampleArray("fault_uncertain", "uint8", "label", "1",
                "where the fault label and the visible offsets disagree: 0 they agree, "
                "1 labelled but offset less than min_throw_samples, 2 offset but unlabelled",
                fill=0, valid_range=(0, 2), option="fault_uncertain"),
):
    SAMPLE_ARRAYS.register(_a.name, _a)
del _a


def spec_from_attributes(name: str, dtype: Any, attrs: Mapping[str, Any]) -> SampleArray | None:
    """The declaration of a stored array from its attributes (:meth:`SampleArray.store_attributes`),
    without a producer; None when the attributes hold no ``demseis`` entry (a store written
    before the arrays described themselves: its arrays are the registered built-ins).

    Raises
    ------
    InputError
        The attributes name a role, but are not a valid declaration (the message says why).
    """
    own = attrs.get("demseis")
    if own is None:
        return None
    try:
        rng = own.get("valid_range")
        valid = None if rng is None else (int(rng[0]), None if rng[1] is None else int(rng[1]))
        dt = np.dtype(dtype)
        fill = own.get("fill", 0)
        fill = float(fill) if dt.kind == "f" else int(fill)
        return SampleArray(name, dt.name, str(own["role"]), str(attrs.get("units", "1")),
                           str(attrs.get("long_name", name)), fill=fill, valid_range=valid,
                           compressed=not own.get("raw", False))
    except (TypeError, ValueError, IndexError, KeyError, AttributeError) as exc:
        raise InputError(f"sample array {name!r}: its stored attributes are not a valid "
                         f"declaration ({exc})") from None


def register_array(spec: SampleArray) -> SampleArray:
    """Add a label array (after the built-in ones); it needs a ``producer``.

    Raises
    ------
    InputError
        The name is taken, or the array has no producer (only the renderer and the engines make
        the built-in arrays).
    """
    if spec.producer is None:
        raise InputError(f"sample array {spec.name!r} needs a producer(state) -> array")
    SAMPLE_ARRAYS.register(spec.name, spec)
    return spec


def sample_array(name: str) -> SampleArray:
    """The declaration of ``name`` (an :class:`InputError` listing the known ones if absent)."""
    return SAMPLE_ARRAYS.get(name)


def stored_arrays(options: Iterable[str] = ()) -> tuple[str, ...]:
    """Names of the arrays a store holds when the ``[output]`` switches ``options`` are on."""
    on = set(options)
    return tuple(n for n, a in SAMPLE_ARRAYS.items() if a.option is None or a.option in on)


def engine_labels() -> tuple[str, ...]:
    """The labels every engine makes itself (no producer), in store order."""
    return tuple(n for n, a in SAMPLE_ARRAYS.items()
                 if a.role == "label" and a.producer is None and n not in RENDERED_LABELS)
