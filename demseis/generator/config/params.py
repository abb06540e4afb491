"""Parameter specifications: a fixed value, a list (a grid) or a distribution.

Every scenario parameter of a sweep is given in the config's ``[sweep]`` table in one of three
forms::

    dip_deg = 45                                        # fixed
    freq_hz = [20, 40, 60]                              # a grid (list)
    throw_m = { dist = "uniform", low = 200, high = 450 }
    kn_n_m  = { dist = "loguniform", low = 5e9, high = 2e10 }
    snr_db  = { dist = "choice", values = [inf, 20, 10] }
    friction = { dist = "truncnormal", mean = 0.4, std = 0.1, low = 0.2, high = 0.6 }

Run-level grids are crossed and cycled over the runs; render-level grids are crossed and
all rendered for every snapshot. Distributions are drawn from the run's (or the render's) own
seeded Generator.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy.special import ndtr, ndtri  # the truncated normal without scipy.stats (0.6 s import)

from demseis.errors import ConfigError
from demseis.parameters import Param

DISTRIBUTIONS = ("uniform", "loguniform", "choice", "truncnormal")


@dataclass(frozen=True)
class Fixed:
    """One value for every run or render."""

    value: Any

    def to_json(self) -> Any:
        return _json_value(self.value)


@dataclass(frozen=True)
class GridSpec:
    """A list of values, crossed with the other grids of the same level."""

    values: tuple

    def to_json(self) -> Any:
        return [_json_value(v) for v in self.values]


@dataclass(frozen=True)
class DistSpec:
    """A distribution, drawn once per run (run level) or per render (render level)."""

    dist: str
    low: float | None = None
    high: float | None = None
    mean: float | None = None
    std: float | None = None
    values: tuple | None = None
    kind: type = float

    def sample(self, rng: np.random.Generator) -> Any:
        """One draw from ``rng``."""
        if self.dist == "choice":
            return self.values[int(rng.integers(len(self.values)))]
        if self.dist == "uniform":
            x = rng.uniform(self.low, self.high)
        elif self.dist == "loguniform":
            x = math.exp(rng.uniform(math.log(self.low), math.log(self.high)))
        else:  # truncnormal, by inversion: x = mean + std * Phi^-1(Phi(a) + u (Phi(b) - Phi(a)))
            a = (self.low - self.mean) / self.std
            b = (self.high - self.mean) / self.std
            u = rng.uniform()
            x = self.mean + self.std * float(ndtri(ndtr(a) + u * (ndtr(b) - ndtr(a))))
            x = min(max(x, self.low), self.high)
        if self.kind is int:
            return int(round(x))
        return float(x)

    def to_json(self) -> Any:
        out: dict[str, Any] = {"dist": self.dist}
        for key in ("low", "high", "mean", "std"):
            val = getattr(self, key)
            if val is not None:
                out[key] = _json_value(val)
        if self.values is not None:
            out["values"] = [_json_value(v) for v in self.values]
        return out


Spec = Fixed | GridSpec | DistSpec


def _json_value(v: Any) -> Any:
    if isinstance(v, float) and math.isinf(v):
        return "inf" if v > 0 else "-inf"
    return v


def parse_spec(pdef: Param, raw: Any, where: str) -> Spec:
    """Parse the TOML value of one sweep parameter into a spec.

    Raises
    ------
    ConfigError naming ``where``, the value and what is allowed.
    """
    if isinstance(raw, list):
        if not raw:
            raise ConfigError(f"{where} = [] is an empty list: give at least one value")
        return GridSpec(tuple(pdef.check_value(v, f"{where}[{i}]") for i, v in enumerate(raw)))
    if isinstance(raw, dict):
        return _parse_dist(pdef, raw, where)
    return Fixed(pdef.check_value(raw, where))


def _parse_dist(pdef: Param, raw: dict, where: str) -> DistSpec:
    dist = raw.get("dist")
    if dist not in DISTRIBUTIONS:
        raise ConfigError(
            f"{where}.dist = {dist!r} is not a known distribution: expected one of "
            + ", ".join(repr(d) for d in DISTRIBUTIONS)
        )
    needed = {
        "uniform": ("low", "high"),
        "loguniform": ("low", "high"),
        "choice": ("values",),
        "truncnormal": ("mean", "std", "low", "high"),
    }[dist]
    extra = sorted(set(raw) - set(needed) - {"dist"})
    if extra:
        raise ConfigError(
            f"{where}: unknown key {extra[0]!r} for dist = {dist!r}: expected keys "
            + ", ".join(needed)
        )
    missing = [k for k in needed if k not in raw]
    if missing:
        raise ConfigError(f"{where}: dist = {dist!r} needs key {missing[0]!r}")
    if dist == "choice":
        vals = raw["values"]
        if not isinstance(vals, list) or not vals:
            raise ConfigError(f"{where}.values = {vals!r}: expected a non-empty list")
        return DistSpec(
            "choice",
            values=tuple(pdef.check_value(v, f"{where}.values[{i}]") for i, v in enumerate(vals)),
            kind=pdef.kind,
        )
    if pdef.kind not in (int, float):
        raise ConfigError(
            f"{where}: dist = {dist!r} needs a numeric parameter; use dist = \"choice\" for "
            f"{pdef.allowed()}"
        )
    vals = {k: pdef.check_value(raw[k], f"{where}.{k}") if k in ("low", "high", "mean")
            else raw[k] for k in needed}
    if "std" in vals:
        std = vals["std"]
        if isinstance(std, bool) or not isinstance(std, (int, float)) or not std > 0 or math.isinf(std):
            raise ConfigError(f"{where}.std = {std!r} is not allowed: expected a number > 0")
        if not vals["low"] <= vals["mean"] <= vals["high"]:
            raise ConfigError(f"{where}: mean = {vals['mean']!r} must lie in [low, high]")
    low, high = vals["low"], vals["high"]
    if any(math.isinf(v) for v in (low, high)):
        raise ConfigError(f"{where}: low and high of dist = {dist!r} must be finite")
    if not low < high:
        raise ConfigError(f"{where}: low = {low!r} must be < high = {high!r}")
    if dist == "loguniform" and low <= 0:
        raise ConfigError(f"{where}.low = {low!r} must be > 0 for dist = 'loguniform'")
    return DistSpec(dist, low=float(low), high=float(high),
                    mean=None if "mean" not in vals else float(vals["mean"]),
                    std=None if "std" not in vals else float(vals["std"]), kind=pdef.kind)


def spec_from_json(pdef: Param, raw: Any, where: str) -> Spec:
    """Inverse of ``Spec.to_json`` (used when a config is read back from a store)."""
    return parse_spec(pdef, raw, where)


def spec_candidates(spec: Spec) -> tuple:
    """The values a spec can give that bound what it can do: a fixed value, every value of a
    list or a choice, the low and high of a continuous distribution."""
    if isinstance(spec, Fixed):
        return (spec.value,)
    if isinstance(spec, GridSpec):
        return spec.values
    if spec.dist == "choice":
        return spec.values
    return tuple(v for v in (spec.low, spec.high) if v is not None)


def spec_values_hint(spec: Spec) -> tuple[Any, Any] | None:
    """The (min, max) a numeric spec can produce, or None for strings and bools."""
    vals = spec_candidates(spec)
    if all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in vals):
        return (min(vals), max(vals))
    return None
