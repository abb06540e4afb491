"""Configuration of the labels stage (the ``[labels]`` table of a sweep config maps 1:1 onto it).

The keys, their types, ranges, defaults and meanings are declared once, in
:mod:`demseis.parameters` (section ``labels``; ``demseis params`` and ``docs/parameters.md``
list them). :class:`LabelConfig` has one field per declaration; :meth:`LabelConfig.validate`
checks each against it and adds the rules that combine several keys.
"""

from __future__ import annotations

from typing import Any

from demseis.errors import ConfigError
from demseis.labels.picks import PickConfig
from demseis.parameters import PARAMS, Param, declared_dataclass

#: the ``[labels]`` declarations, in field order
LABEL_PARAMS: dict[str, Param] = {k: p for k, p in PARAMS.items() if p.section == "labels"}
STRAIN_MEASURES: tuple[str, ...] = tuple(PARAMS["strain_measure"].choices)
NEIGHBOUR_METHODS: tuple[str, ...] = tuple(PARAMS["neighbour_method"].choices)
THROW_SOURCES: tuple[str, ...] = tuple(PARAMS["throw_from"].choices)


class _LabelRules:
    """The methods of :class:`LabelConfig` (its fields come from the declarations)."""

    def validate(self) -> LabelConfig:
        """Check every field; returns ``self`` so it chains.

        Raises
        ------
        demseis.errors.ConfigError
            Naming the field, its value and the allowed range or choices.
        """
        for name, pdef in LABEL_PARAMS.items():
            pdef.check_value(getattr(self, name), f"labels.{name}")
        if self.neighbour_method == "knn" and self.min_neighbours > self.neighbour_k:
            raise ConfigError(
                f"labels.min_neighbours = {self.min_neighbours} exceeds labels.neighbour_k = "
                f"{self.neighbour_k}; allowed: min_neighbours <= neighbour_k"
            )
        if self.damage_threshold > self.fault_threshold:
            raise ConfigError(f"labels.damage_threshold = {self.damage_threshold!r} exceeds "
                              f"labels.fault_threshold = {self.fault_threshold!r}; allowed: "
                              "damage_threshold <= fault_threshold")
        if self.offset_window_traces % 2 != 1:
            raise ConfigError(f"labels.offset_window_traces = {self.offset_window_traces} is "
                              "even; allowed: an odd number in [1, 9]")
        if self.offset_faults and self.throw_from != "offset":
            raise ConfigError("labels.offset_faults = true needs labels.throw_from = 'offset' "
                              "(it measures the offsets on the reference map)")
        return self

    def picks(self) -> PickConfig:
        """The :class:`demseis.labels.picks.PickConfig` of these settings."""
        return PickConfig(min_throw_samples=float(self.min_throw_samples),
                          smooth_px=float(self.pick_smooth_px),
                          max_gap_px=int(self.pick_max_gap_px),
                          min_length_px=int(self.pick_min_length_px))

    def min_slip_for(self, cell_m: float) -> float:
        """``min_slip_m``, or one grid cell (``cell_m``) when it is not set."""
        return float(cell_m) if self.min_slip_m is None else float(self.min_slip_m)

    @classmethod
    def from_mapping(cls, table: dict[str, Any]) -> LabelConfig:
        """Build from a ``[labels]`` TOML table; unknown keys and bad values raise ConfigError."""
        if not isinstance(table, dict):
            raise ConfigError(f"[labels] must be a table, got {type(table).__name__}")
        known = set(LABEL_PARAMS)
        unknown = sorted(set(table) - known)
        if unknown:
            raise ConfigError(
                f"unknown key(s) in [labels]: {', '.join(unknown)}; "
                f"allowed: {', '.join(sorted(known))}"
            )
        return cls(**table).validate()


LabelConfig = declared_dataclass("LabelConfig", LABEL_PARAMS.values(), module=__name__,
                                 bases=(_LabelRules,), doc="""How per-element strain and
displacement become fault, damage-zone, strain and layer labels: one field per ``[labels]``
parameter of :mod:`demseis.parameters` (``demseis params`` documents each: ``method``,
``min_slip_m``, ``fault_style``, ...). Build it with keyword arguments or :meth:`from_mapping`;
:meth:`validate` checks it.""")
