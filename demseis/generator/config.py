"""Configuration: a TOML file (or a built-in preset) parsed into frozen dataclasses.

Layout of a config file (every key optional; defaults are the ``quick`` preset's)::

    name = "my-sweep"

    [sweep]                  # what is sampled, and how many DEM runs
    seed = 0
    n_runs = 4
    renders_per_snapshot = 1 # extra draws per snapshot for distributions of render parameters
    dip_deg = { dist = "uniform", low = 30, high = 70 }
    freq_hz = [20, 40, 60]
    ...                      # every scenario parameter: see ``demseis.generator.config.PARAMS``

    [model]                  # the DEM box and run control (fixed for a sweep)
    [grid]                   # the raster grid (fixed: all samples share one shape)
    [labels]                 # fault / damage-zone label settings (fixed)
    [output]                 # which optional arrays are stored

Every key is validated: an unknown key, a wrong type or an out-of-range value raises
:class:`demseis.errors.ConfigError` naming the key, the value and what is allowed.
"""

from __future__ import annotations

import dataclasses
import functools
import math
import tomllib
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path
from typing import Any

from demseis.dem.types import Material
from demseis.errors import ConfigError
from demseis.generator.params import (
    DistSpec,
    Fixed,
    GridSpec,
    ParamDef,
    Spec,
    parse_spec,
    spec_values_hint,
)

PRESETS = ("tiny", "quick", "seed")

_MAT = Material()

INF = math.inf

# Scenario parameters that live in [sweep]. Property-model fields are appended from
# demseis.seismic.PropertyModel by _property_params().
_BASE_PARAMS: tuple[ParamDef, ...] = (
    # fault
    ParamDef("dip_deg", float, "run", 45.0, 10.0, 89.0, doc="basement fault dip (degrees)"),
    ParamDef("throw_m", float, "run", 450.0, 1.0, 1.0e5, doc="final vertical throw of the basement fault (m)"),
    ParamDef("fault_x_frac", float, "run", 0.5, 0.05, 0.95,
             doc="x where the basement fault meets the model base, as a fraction of the width"),
    ParamDef("dip_direction", str, "run", "right", choices=("right", "left"),
             doc="side of the hanging wall"),
    # layering
    ParamDef("n_layers", int, "run", 48, 1, 250, doc="number of pre-kinematic layers"),
    ParamDef("layer_thickness_cv", float, "run", 0.0, 0.0, 0.9,
             doc="coefficient of variation of layer thicknesses (0 = equal thicknesses)"),
    # mechanics (demseis.dem.Material; defaults are Material's)
    ParamDef("density_kg_m3", float, "run", _MAT.density_kg_m3, 500.0, 6000.0, doc="element density (kg/m^3)"),
    ParamDef("kn_n_m", float, "run", _MAT.kn_n_m, 1.0e6, 1.0e13, doc="normal contact stiffness Kn (N/m)"),
    ParamDef("ks_ratio", float, "run", _MAT.ks_ratio, 0.0, 2.0, doc="shear stiffness Ks / Kn"),
    ParamDef("friction", float, "run", _MAT.friction, 0.0, 2.0, doc="inter-element friction coefficient mu"),
    ParamDef("cohesion_n", float, "run", _MAT.cohesion_n, 0.0, 1.0e12, doc="contact cohesion C0 (N)"),
    ParamDef("bond_strain", float, "run", _MAT.bond_strain, 1.0e-5, 1.0, doc="bond-breaking strain r0"),
    ParamDef("contact_model", str, "run", _MAT.model, choices=("frictional", "bonded"),
             doc="frictional-cohesive (bonds start broken) or bonded"),
    ParamDef("damping_scale", float, "run", _MAT.damping_scale, 0.0, 1.0e13,
             doc="viscous damping eta = dt * damping_scale (N s/m per s)"),
    ParamDef("gravity_m_s2", float, "run", _MAT.gravity_m_s2, 0.0, 100.0, doc="gravity (m/s^2)"),
    # rendering
    ParamDef("freq_hz", float, "render", 40.0, 1.0, 500.0, doc="Ricker peak frequency (Hz)"),
    ParamDef("snr_db", float, "render", INF, -40.0, INF,
             doc="signal-to-noise ratio in dB, 20 log10(rms signal / rms noise); inf = no noise"),
    ParamDef("noise_kind", str, "render", "white", choices=("white", "band"),
             doc="white or band-limited noise"),
)

_MATERIAL_FIELDS = {
    "density_kg_m3": "density_kg_m3",
    "kn_n_m": "kn_n_m",
    "ks_ratio": "ks_ratio",
    "friction": "friction",
    "cohesion_n": "cohesion_n",
    "bond_strain": "bond_strain",
    "contact_model": "model",
    "damping_scale": "damping_scale",
    "gravity_m_s2": "gravity_m_s2",
}


@functools.cache
def _property_params() -> tuple[ParamDef, ...]:
    """Sweepable (numeric scalar) fields of :class:`demseis.seismic.PropertyModel` (run level).

    Its string and tuple fields (lithology names and Vp/density ranges, density law,
    background rule) are set in ``[properties]``.
    """
    from demseis.seismic import PropertyModel

    out = []
    defaults = PropertyModel()
    for f in dataclasses.fields(PropertyModel):
        value = getattr(defaults, f.name)
        if isinstance(value, bool):
            kind: type = bool
        elif isinstance(value, int):
            kind = int
        elif isinstance(value, float):
            kind = float
        else:
            continue  # strings and tuples are set in [properties]
        out.append(ParamDef(f.name, kind, "run", value, doc=f"PropertyModel.{f.name}"))
    return tuple(out)


@functools.cache
def all_params() -> dict[str, ParamDef]:
    """Every scenario parameter accepted in ``[sweep]``, by name (shared: do not mutate)."""
    params = {p.name: p for p in _BASE_PARAMS}
    for p in _property_params():
        if p.name in params:
            raise RuntimeError(f"PropertyModel field {p.name!r} collides with a sweep parameter")
        params[p.name] = p
    return params


@dataclass(frozen=True)
class ModelSection:
    """The DEM box and run control; fixed for a whole sweep.

    Attributes
    ----------
    width_m, height_m : model box (m).
    radius_min_m, radius_max_m : element radii (m), drawn uniformly.
    n_snapshots : snapshots per run, equally spaced in throw, the first the undeformed reference.
    sedimentation : fill hanging-wall accommodation with growth layers.
    wall_speed_m_s : speed of the moving basement along dip (m/s of model time).
    """

    width_m: float = 2400.0
    height_m: float = 1200.0
    radius_min_m: float = 12.5
    radius_max_m: float = 25.0
    n_snapshots: int = 4
    sedimentation: bool = True
    wall_speed_m_s: float = 5.0


_MODEL_DEFS = {
    "width_m": ParamDef("width_m", float, "fixed", 2400.0, 100.0, 1.0e5),
    "height_m": ParamDef("height_m", float, "fixed", 1200.0, 50.0, 1.0e5),
    "radius_min_m": ParamDef("radius_min_m", float, "fixed", 12.5, 0.1, 1.0e3),
    "radius_max_m": ParamDef("radius_max_m", float, "fixed", 25.0, 0.1, 1.0e3),
    "n_snapshots": ParamDef("n_snapshots", int, "fixed", 4, 2, 1000),
    "sedimentation": ParamDef("sedimentation", bool, "fixed", True),
    "wall_speed_m_s": ParamDef("wall_speed_m_s", float, "fixed", 5.0, 1.0e-3, 100.0),
}


@dataclass(frozen=True)
class GridSection:
    """Raster grid; fixed for a sweep because every sample shares one (H, W) shape."""

    cell_m: float = 10.0


_GRID_DEFS = {"cell_m": ParamDef("cell_m", float, "fixed", 10.0, 0.5, 1000.0)}


@dataclass(frozen=True)
class OutputSection:
    """Optional arrays and the output domain.

    Attributes
    ----------
    impedance : also store the smoothed impedance grid (float32).
    domain : ``"depth"`` (sections convolved in two-way time and mapped back to depth, so the
        arrays are (H, W) cells of the grid) or ``"time"`` (sections and every label array on a
        two-way-time axis of ``dt_s`` samples, long enough for the slowest possible column).
    dt_s : time-domain sample interval (s).
    """

    impedance: bool = False
    domain: str = "depth"
    dt_s: float = 0.002


_OUTPUT_DEFS = {
    "impedance": ParamDef("impedance", bool, "fixed", False),
    "domain": ParamDef("domain", str, "fixed", "depth", choices=("depth", "time")),
    "dt_s": ParamDef("dt_s", float, "fixed", 0.002, 1.0e-4, 0.02),
}


@dataclass(frozen=True)
class SweepSection:
    """How many DEM runs, the root seed and the spec of every scenario parameter."""

    seed: int = 0
    n_runs: int = 4
    renders_per_snapshot: int = 1
    params: dict[str, Spec] = field(default_factory=dict)


_SWEEP_DEFS = {
    "seed": ParamDef("seed", int, "fixed", 0, 0, 2**63 - 1),
    "n_runs": ParamDef("n_runs", int, "fixed", 4, 1, 10**7),
    "renders_per_snapshot": ParamDef("renders_per_snapshot", int, "fixed", 1, 1, 10**4),
}


@dataclass(frozen=True)
class Config:
    """A fully resolved, validated configuration.

    ``labels`` is a :class:`demseis.labels.LabelConfig`, ``properties`` holds non-scalar
    :class:`demseis.seismic.PropertyModel` fields (scalar ones are sweep parameters).
    """

    name: str
    sweep: SweepSection
    model: ModelSection
    grid: GridSection
    output: OutputSection
    labels: Any
    properties: dict[str, Any]

    # ---- derived sizes -------------------------------------------------------------
    def render_grid(self) -> list[dict[str, Any]]:
        """The render-level combinations of one snapshot (grids crossed, in key order)."""
        return _cross({k: s for k, s in self.sweep.params.items()
                       if all_params()[k].level == "render"})

    @property
    def renders_per_run_snapshot(self) -> int:
        return len(self.render_grid()) * self.sweep.renders_per_snapshot

    @property
    def samples_per_run(self) -> int:
        return self.model.n_snapshots * self.renders_per_run_snapshot

    @property
    def n_samples(self) -> int:
        return self.sweep.n_runs * self.samples_per_run

    def to_dict(self) -> dict[str, Any]:
        """A JSON-able dict with every key resolved (inf as the string "inf")."""
        return {
            "name": self.name,
            "sweep": {
                "seed": self.sweep.seed,
                "n_runs": self.sweep.n_runs,
                "renders_per_snapshot": self.sweep.renders_per_snapshot,
                **{k: s.to_json() for k, s in self.sweep.params.items()},
            },
            "model": dataclasses.asdict(self.model),
            "grid": dataclasses.asdict(self.grid),
            "output": dataclasses.asdict(self.output),
            "labels": dataclasses.asdict(self.labels),
            "properties": {k: list(v) if isinstance(v, tuple) else v
                           for k, v in self.properties.items()},
        }


def _cross(specs: dict[str, Spec]) -> list[dict[str, Any]]:
    """Cartesian product of the GridSpec values; Fixed/DistSpec entries are carried as specs."""
    combos: list[dict[str, Any]] = [{}]
    for key, spec in specs.items():
        if isinstance(spec, GridSpec):
            combos = [{**c, key: v} for c in combos for v in spec.values]
        else:
            combos = [{**c, key: spec} for c in combos]
    return combos


# ---- parsing -----------------------------------------------------------------------

def _parse_table(raw: Any, defs: dict[str, ParamDef], where: str) -> dict[str, Any]:
    if not isinstance(raw, dict):
        raise ConfigError(f"[{where}] must be a table, got {type(raw).__name__}")
    out = {}
    for key, value in raw.items():
        if key not in defs:
            raise ConfigError(
                f"{where}.{key}: unknown key; allowed keys are " + ", ".join(sorted(defs))
            )
        if isinstance(value, (list, dict)):
            raise ConfigError(
                f"{where}.{key} = {value!r}: must be a single value (only [sweep] parameters "
                "take lists or distributions)"
            )
        out[key] = defs[key].check_value(value, f"{where}.{key}")
    return out


def _dataclass_table(cls: type, raw: Any, where: str) -> Any:
    """Build a helper-owned frozen dataclass (LabelConfig) from a TOML table, then validate."""
    if not isinstance(raw, dict):
        raise ConfigError(f"[{where}] must be a table, got {type(raw).__name__}")
    fields = {f.name: f for f in dataclasses.fields(cls)}
    defaults = cls()
    kwargs = {}
    for key, value in raw.items():
        if key not in fields:
            raise ConfigError(f"{where}.{key}: unknown key; allowed keys are " + ", ".join(sorted(fields)))
        default = getattr(defaults, key)
        kwargs[key] = _coerce_like(default, value, f"{where}.{key}")
    obj = cls(**kwargs)
    obj.validate()
    return obj


def _coerce_like(default: Any, value: Any, where: str) -> Any:
    """Check that ``value`` has the type of ``default`` (ints accepted for floats)."""
    if isinstance(default, bool):
        ok = isinstance(value, bool)
    elif isinstance(default, int):
        ok = isinstance(value, int) and not isinstance(value, bool)
    elif isinstance(default, float):
        if isinstance(value, str) and value.lower() in ("inf", "+inf"):
            value = math.inf
        ok = isinstance(value, (int, float)) and not isinstance(value, bool)
        if ok:
            value = float(value)
            ok = not math.isnan(value)
    elif isinstance(default, str):
        ok = isinstance(value, str)
    elif isinstance(default, tuple):
        ok = isinstance(value, (list, tuple))
        if ok and default:
            value = tuple(_coerce_like(default[0], v, f"{where}[{i}]") for i, v in enumerate(value))
        elif ok:
            value = tuple(value)
    else:
        ok = True
    if not ok:
        raise ConfigError(f"{where} = {value!r} has the wrong type: expected {type(default).__name__}")
    return value


def parse_config(raw: dict[str, Any], *, source: str = "config") -> Config:
    """Validate a config dict (from TOML, a preset or a store) into a :class:`Config`.

    Missing keys take the defaults; every present key is checked.
    """
    from demseis.labels import LabelConfig
    from demseis.seismic import PropertyModel

    if not isinstance(raw, dict):
        raise ConfigError(f"{source}: expected a table at the top level")
    allowed_top = {"name", "sweep", "model", "grid", "labels", "output", "properties"}
    for key in raw:
        if key not in allowed_top:
            raise ConfigError(f"{key}: unknown top-level key; allowed are " + ", ".join(sorted(allowed_top)))
    name = raw.get("name", "demseis")
    if not isinstance(name, str) or not name:
        raise ConfigError(f"name = {name!r}: expected a non-empty string")

    pdefs = all_params()
    sweep_raw = raw.get("sweep", {})
    if not isinstance(sweep_raw, dict):
        raise ConfigError(f"[sweep] must be a table, got {type(sweep_raw).__name__}")
    sweep_fixed = _parse_table({k: v for k, v in sweep_raw.items() if k in _SWEEP_DEFS},
                               _SWEEP_DEFS, "sweep")
    specs: dict[str, Spec] = {}
    for key, value in sweep_raw.items():
        if key in _SWEEP_DEFS:
            continue
        if key not in pdefs:
            raise ConfigError(
                f"sweep.{key}: unknown key; allowed keys are "
                + ", ".join(sorted(set(pdefs) | set(_SWEEP_DEFS)))
            )
        specs[key] = parse_spec(pdefs[key], value, f"sweep.{key}")
    for key, pdef in pdefs.items():
        specs.setdefault(key, Fixed(pdef.default))
    specs = {k: specs[k] for k in pdefs}  # canonical order
    sweep = SweepSection(params=specs, **sweep_fixed)

    model = ModelSection(**_parse_table(raw.get("model", {}), _MODEL_DEFS, "model"))
    if model.radius_min_m > model.radius_max_m:
        raise ConfigError(
            f"model.radius_min_m = {model.radius_min_m:g} must be <= model.radius_max_m = "
            f"{model.radius_max_m:g}"
        )
    grid = GridSection(**_parse_table(raw.get("grid", {}), _GRID_DEFS, "grid"))
    output = OutputSection(**_parse_table(raw.get("output", {}), _OUTPUT_DEFS, "output"))
    labels = _dataclass_table(LabelConfig, raw.get("labels", {}), "labels")

    # non-scalar PropertyModel fields live in [properties]
    prop_raw = raw.get("properties", {})
    if not isinstance(prop_raw, dict):
        raise ConfigError(f"[properties] must be a table, got {type(prop_raw).__name__}")
    scalar_props = {p.name for p in _property_params()}
    prop_defaults = PropertyModel()
    prop_fields = {f.name for f in dataclasses.fields(PropertyModel)} - scalar_props
    properties: dict[str, Any] = {}
    for key, value in prop_raw.items():
        if key in scalar_props:
            raise ConfigError(f"properties.{key}: set scalar property parameters in [sweep] ({key} = ...)")
        if key not in prop_fields:
            raise ConfigError(f"properties.{key}: unknown key; allowed keys are " + ", ".join(sorted(prop_fields)))
        properties[key] = _coerce_like(getattr(prop_defaults, key), value, f"properties.{key}")
    for key in sorted(prop_fields):
        properties.setdefault(key, getattr(prop_defaults, key))

    cfg = Config(name=name, sweep=sweep, model=model, grid=grid, output=output, labels=labels,
                 properties=properties)
    _cross_checks(cfg)
    return cfg


def _cross_checks(cfg: Config) -> None:
    """Checks that involve more than one key."""
    from demseis.seismic import PropertyModel

    throw = spec_values_hint(cfg.sweep.params["throw_m"])
    if throw and throw[1] > 0.6 * cfg.model.height_m:
        raise ConfigError(
            f"sweep.throw_m up to {throw[1]:g} m is too large for model.height_m = "
            f"{cfg.model.height_m:g}: at most 0.6 * height_m = {0.6 * cfg.model.height_m:g} m"
        )
    if cfg.model.radius_max_m * 8 > min(cfg.model.width_m, cfg.model.height_m):
        raise ConfigError(
            f"model.radius_max_m = {cfg.model.radius_max_m:g} is too large for a "
            f"{cfg.model.width_m:g} x {cfg.model.height_m:g} m box: at most 1/8 of the smaller side"
        )
    n_layers = spec_values_hint(cfg.sweep.params["n_layers"])
    if n_layers and cfg.model.height_m / n_layers[1] < 2 * cfg.model.radius_min_m:
        raise ConfigError(
            f"sweep.n_layers up to {n_layers[1]} gives layers thinner than one element "
            f"(height_m / n_layers < 2 * radius_min_m = {2 * cfg.model.radius_min_m:g} m)"
        )
    if cfg.grid.cell_m * 4 > min(cfg.model.width_m, cfg.model.height_m):
        raise ConfigError(f"grid.cell_m = {cfg.grid.cell_m:g} is too coarse for the model box")
    # every extreme value of every property parameter must make a valid PropertyModel
    scalar = {p.name for p in _property_params()}
    for key in scalar:
        spec = cfg.sweep.params[key]
        candidates = _spec_candidates(spec)
        for value in candidates:
            try:
                PropertyModel(**{**cfg.properties, key: value}).validate()
            except ConfigError as exc:
                raise ConfigError(f"sweep.{key}: {exc}") from None
    from demseis.generator.physics import check_physics

    check_physics(cfg)  # cross-parameter physics: a fault can form, the run is quasi-static


def _spec_candidates(spec: Spec) -> tuple:
    if isinstance(spec, Fixed):
        return (spec.value,)
    if isinstance(spec, GridSpec):
        return spec.values
    if isinstance(spec, DistSpec) and spec.dist == "choice":
        return spec.values
    assert isinstance(spec, DistSpec)
    return tuple(v for v in (spec.low, spec.high) if v is not None)


def preset_path(name: str) -> Path:
    """Path of a built-in preset file."""
    if name not in PRESETS:
        raise ConfigError(f"--preset {name!r} is not a preset: expected one of " + ", ".join(PRESETS))
    return Path(str(resources.files("demseis.generator") / "presets" / f"{name}.toml"))


def load_config(path: str | Path | None = None, *, preset: str | None = None) -> Config:
    """Load a TOML config file layered on a preset (default ``quick``); validate it.

    Every key of the file overrides the preset's; keys it does not give keep the preset's
    values, so a file may be as short as ``[sweep] n_runs = 100``.
    """
    raw = tomllib.loads(preset_path(preset or "quick").read_text())
    if path is not None:
        p = Path(path)
        if not p.is_file():
            raise ConfigError(f"config file {str(p)!r} does not exist")
        try:
            user = tomllib.loads(p.read_text())
        except tomllib.TOMLDecodeError as exc:
            raise ConfigError(f"config file {str(p)!r} is not valid TOML: {exc}") from None
        except UnicodeDecodeError:
            raise ConfigError(f"config file {str(p)!r} is not a text (TOML) file") from None
        raw = _merge(raw, user)
    return parse_config(raw, source=str(path) if path else f"preset {preset or 'quick'}")


def _merge(base: dict[str, Any], over: dict[str, Any]) -> dict[str, Any]:
    out = dict(base)
    for key, value in over.items():
        if isinstance(value, dict) and isinstance(out.get(key), dict) and key != "sweep":
            out[key] = _merge(out[key], value)
        elif key == "sweep" and isinstance(value, dict) and isinstance(out.get(key), dict):
            out[key] = {**out[key], **value}
        else:
            out[key] = value
    return out
