"""Configuration: a TOML file (or a built-in preset) parsed into frozen dataclasses.

Layout of a config file (every key optional; defaults are the ``quick`` preset's)::

    name = "my-sweep"

    [sweep]                  # what is sampled, and how many runs
    seed = 0
    n_runs = 4
    renders_per_snapshot = 1 # extra draws per snapshot for distributions of render parameters
    dip_deg = { dist = "uniform", low = 30, high = 70 }
    freq_hz = [20, 40, 60]
    ...                      # every scenario parameter: see ``demseis params``

    [model]                  # the DEM box and run control (fixed for a sweep)
    [grid]                   # the raster grid (fixed: all samples share one shape)
    [labels]                 # fault / damage-zone label settings (fixed)
    [output]                 # which optional arrays are stored

Every key is validated: an unknown key, a wrong type or an out-of-range value raises
:class:`demseis.errors.ConfigError` naming the key, the value and what is allowed.
"""

from __future__ import annotations

import dataclasses
import difflib
import math
import tomllib
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path
from typing import Any

from demseis.errors import ConfigError, InputError
from demseis.generator.config.params import (DistSpec, Fixed, GridSpec, Spec, parse_spec,
                                             spec_candidates, spec_values_hint)
from demseis.labels import LabelConfig
from demseis.parameters import (BED_FIELDS, PARAMS, PROPERTY_FIELDS, SCENARIO, Param,
                                declared_dataclass)
from demseis.registry import ENGINES, RENDERINGS, load_plugins
from demseis.seismic import BedModel, PropertyModel

PRESETS = ("tiny", "quick", "seed", "variety", "field", "planar")


def _section(name: str) -> dict[str, Param]:
    """The declared keys of config table ``[name]`` (``sweep``: only the sweep-level ones)."""
    return {k: p for k, p in PARAMS.items() if p.section == name and p.level == "sweep"}


def _default(name: str) -> Any:
    return PARAMS[name].default


def _section_class(table: str, cls_name: str, doc: str) -> type:
    """A frozen dataclass with one field per declared key of ``[table]`` (type and default from
    :mod:`demseis.parameters`; ``demseis params`` documents each field)."""
    return declared_dataclass(cls_name, _section(table).values(), module=__name__, doc=doc)


ModelSection = _section_class("model", "ModelSection", """The DEM box and run control; fixed for a
whole sweep: ``width_m``, ``height_m``, ``radius_min_m``, ``radius_max_m``, ``n_snapshots``,
``sedimentation``, ``wall_speed_m_s``, ``engine``, ``pack_library``.""")
GridSection = _section_class("grid", "GridSection", """The raster grid (``cell_m``); fixed for a
sweep because every sample shares one (H, W) shape.""")
OutputSection = _section_class("output", "OutputSection", """Optional arrays and the output domain:
``impedance`` (also store the smoothed impedance grid), ``domain`` (``"depth"``: sections
convolved in two-way time and mapped back to depth cells; ``"time"``: sections and every label
on a two-way-time axis of ``dt_s`` samples, long enough for the slowest possible column).""")
_MODEL_DEFS = _section("model")
_GRID_DEFS = _section("grid")
_OUTPUT_DEFS = _section("output")
_LABEL_DEFS = _section("labels")


@dataclass(frozen=True)
class SweepSection:
    """How many runs, the root seed and the spec of every scenario parameter."""

    seed: int = _default("seed")
    n_runs: int = _default("n_runs")
    renders_per_snapshot: int = _default("renders_per_snapshot")
    params: dict[str, Spec] = field(default_factory=dict)


_SWEEP_DEFS = _section("sweep")


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
    #: plug-in modules imported before the config is read (demseis.registry.load_plugins)
    plugins: tuple[str, ...] = ()
    #: the ``[output]`` sampling keys given a list or a distribution (:data:`SAMPLING_KEYS`),
    #: drawn per run (:func:`demseis.generator.config.sampling.config_of_run`); empty when the
    #: whole store has one sampling. ``output`` holds each one's nominal value (the first
    #: listed, or the low end).
    sampling: dict[str, Spec] = field(default_factory=dict)

    @property
    def scenario(self) -> dict[str, Param]:
        """The declarations of ``sweep.params``: every ``run`` and ``sample`` parameter of
        :mod:`demseis.parameters`, then the run-level parameters this config's engine declares
        (:func:`engine_parameters`)."""
        return {**SCENARIO, **engine_parameters(self.model.engine)}

    # ---- derived sizes -------------------------------------------------------------
    def render_grid(self) -> list[dict[str, Any]]:
        """The render-level combinations of one snapshot (grids crossed, in key order)."""
        return _cross({k: s for k, s in self.sweep.params.items()
                       if k in SCENARIO and SCENARIO[k].level == "sample"})

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
            "model": self._model_dict(),
            "grid": dataclasses.asdict(self.grid),
            "output": {**dataclasses.asdict(self.output),
                       **{k: spec.to_json() for k, spec in self.sampling.items()}},
            "labels": dataclasses.asdict(self.labels),
            "properties": {k: list(v) if isinstance(v, tuple) else v
                           for k, v in self.properties.items()},
            # only when set: a config without plug-ins keeps the dict (and store) it had
            **({"plugins": list(self.plugins)} if self.plugins else {}),
        }


    def _model_dict(self) -> dict[str, Any]:
        """``[model]`` as a dict; ``pack_library`` only where it is set and the engine takes
        packs (``packs`` attribute): a config that settles every run, or whose engine has no
        packs, keeps the dict (and store bytes) it had before the pack library existed."""
        out = dataclasses.asdict(self.model)
        if not out["pack_library"] or not getattr(ENGINES.get(self.model.engine), "packs", False):
            del out["pack_library"]
        return out


def _cross(specs: dict[str, Spec]) -> list[dict[str, Any]]:
    """Cartesian product of the GridSpec values; Fixed/DistSpec entries are carried as specs."""
    combos: list[dict[str, Any]] = [{}]
    for key, spec in specs.items():
        if isinstance(spec, GridSpec):
            combos = [{**c, key: v} for c in combos for v in spec.values]
        else:
            combos = [{**c, key: spec} for c in combos]
    return combos


def engine_parameters(engine: str) -> dict[str, Param]:
    """The run-level parameters that engine ``engine`` declares besides those of
    :mod:`demseis.parameters`: its optional ``parameters`` attribute, a sequence of
    :class:`~demseis.parameters.Param` (level ``"run"``, section ``"sweep"``, kind ``float``,
    ``int`` or ``bool``, a name no other parameter has). A config for that engine takes them
    in ``[sweep]`` (fixed, a list or a distribution), every run draws them after the declared
    ones (so those keep their values) and its store holds them as columns after the others.

    Raises
    ------
    ConfigError
        A declaration breaks one of those rules (naming the engine and the parameter).
    """
    out: dict[str, Param] = {}
    for pdef in getattr(ENGINES.get(engine), "parameters", ()):
        name = getattr(pdef, "name", repr(pdef))
        problem = None
        if not isinstance(pdef, Param):
            problem = "is not a demseis.parameters.Param"
        elif pdef.level != "run" or pdef.section != "sweep":
            problem = (f"has level {pdef.level!r} and section {pdef.section!r}: an engine "
                       "declares run-level [sweep] parameters only")
        elif pdef.kind not in (float, int, bool):
            problem = (f"has kind {pdef.kind.__name__}: an engine's parameters are numbers or "
                       "booleans (give a choice as an integer code)")
        elif pdef.name in PARAMS or pdef.name in out:
            problem = "has the name of another parameter"
        if problem:
            raise ConfigError(f"engine {engine!r} declares parameter {name!r}, which {problem}")
        out[pdef.name] = pdef
    return out


# ---- parsing -----------------------------------------------------------------------

def unknown_key(where: str, key: str, allowed: Any) -> ConfigError:
    """The error for ``where.key`` that is not a key of ``where``: the closest allowed keys
    ("did you mean"), the section a known key belongs to, and the list itself where it is
    short (``demseis params`` prints the long ones)."""
    allowed = sorted(allowed)
    close = difflib.get_close_matches(key, allowed, n=3, cutoff=0.75)
    text = f"{where}.{key}: unknown key"
    home = PARAMS[key].section if key in PARAMS else None
    if home and home != where:
        text += f"; it belongs in [{home}]"
    elif close:
        text += "; did you mean " + " or ".join(repr(c) for c in close) + "?"
    if len(allowed) <= 12:
        text += "; allowed keys are " + ", ".join(allowed)
    else:
        text += f" ({len(allowed)} keys are allowed there: `demseis params` lists them)"
    return ConfigError(text)


def _parse_table(raw: Any, defs: dict[str, Param], where: str) -> dict[str, Any]:
    if not isinstance(raw, dict):
        raise ConfigError(f"[{where}] must be a table, got {type(raw).__name__}")
    out = {}
    for key, value in raw.items():
        if key not in defs:
            raise unknown_key(where, key, defs)
        if isinstance(value, (list, dict)):
            raise ConfigError(
                f"{where}.{key} = {value!r}: must be a single value (only [sweep] parameters "
                f"and [output] {', '.join(SAMPLING_KEYS)} take lists or distributions)"
            )
        out[key] = defs[key].check_value(value, f"{where}.{key}")
    return out


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


def _load_plugins(value: Any) -> tuple[str, ...]:
    """Import the ``plugins`` modules (in this process: each sweep worker parses the config
    too); ConfigError naming the one that fails."""
    if not isinstance(value, (list, tuple)) or not all(isinstance(v, str) for v in value):
        raise ConfigError(f"plugins = {value!r}: expected a list of module names "
                          "(\"package.module\")")
    try:
        load_plugins(value)
    except InputError as exc:
        raise ConfigError(str(exc)) from None
    return tuple(value)


def parse_config(raw: dict[str, Any], *, source: str = "config") -> Config:
    """Validate a config dict (from TOML, a preset or a store) into a :class:`Config`.

    Missing keys take the defaults; every present key is checked.
    """
    if not isinstance(raw, dict):
        raise ConfigError(f"{source}: expected a table at the top level")
    allowed_top = {"name", "sweep", "model", "grid", "labels", "output", "properties", "plugins"}
    for key in raw:
        if key not in allowed_top:
            close = difflib.get_close_matches(key, sorted(allowed_top), n=1, cutoff=0.75)
            raise ConfigError(f"{key}: unknown top-level key"
                              + (f"; did you mean {close[0]!r}?" if close else "")
                              + "; allowed are " + ", ".join(sorted(allowed_top)))
    plugins = _load_plugins(raw.get("plugins", []))  # first: they may add engines, modes, arrays
    name = raw.get("name", "demseis")
    if not isinstance(name, str) or not name:
        raise ConfigError(f"name = {name!r}: expected a non-empty string")

    model = ModelSection(**_parse_table(raw.get("model", {}), _MODEL_DEFS, "model"))
    if model.radius_min_m > model.radius_max_m:
        raise ConfigError(
            f"model.radius_min_m = {model.radius_min_m:g} must be <= model.radius_max_m = "
            f"{model.radius_max_m:g}"
        )
    pdefs = {**SCENARIO, **engine_parameters(model.engine)}
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
            raise unknown_key("sweep", key, set(pdefs) | set(_SWEEP_DEFS))
        specs[key] = parse_spec(pdefs[key], value, f"sweep.{key}")
    for key, pdef in pdefs.items():
        specs.setdefault(key, Fixed(pdef.default))
    specs = {k: specs[k] for k in pdefs}  # canonical order
    sweep = SweepSection(params=specs, **sweep_fixed)
    grid = GridSection(**_parse_table(raw.get("grid", {}), _GRID_DEFS, "grid"))
    output, sampling = _parse_output(raw.get("output", {}))
    labels = LabelConfig(**_parse_table(raw.get("labels", {}), _LABEL_DEFS, "labels")).validate()

    # non-scalar PropertyModel fields live in [properties]
    prop_raw = raw.get("properties", {})
    if not isinstance(prop_raw, dict):
        raise ConfigError(f"[properties] must be a table, got {type(prop_raw).__name__}")
    scalar_props = set(PROPERTY_FIELDS)
    prop_defaults = PropertyModel()
    prop_fields = {f.name for f in dataclasses.fields(PropertyModel)} - scalar_props
    properties: dict[str, Any] = {}
    for key, value in prop_raw.items():
        if key in scalar_props:
            raise ConfigError(f"properties.{key}: set scalar property parameters in [sweep] ({key} = ...)")
        if key not in prop_fields:
            raise unknown_key("properties", key, prop_fields)
        properties[key] = _coerce_like(getattr(prop_defaults, key), value, f"properties.{key}")
    for key in sorted(prop_fields):
        properties.setdefault(key, getattr(prop_defaults, key))

    cfg = Config(name=name, sweep=sweep, model=model, grid=grid, output=output, labels=labels,
                 properties=properties, plugins=plugins, sampling=sampling)
    _cross_checks(cfg)
    return cfg


#: the ``[output]`` keys that take a list or a distribution, drawn per run: the sampling of
#: the sections (one shape per store all the same, see :func:`demseis.generator.config.layout.sample_shape`)
SAMPLING_KEYS = ("dt_s", "trace_spacing_m", "domain")


def _parse_output(raw: Any) -> tuple[Any, dict[str, Spec]]:
    """``[output]``: the section, and the specs of its :data:`SAMPLING_KEYS` given a list or a
    distribution (a list or choice of one value is that value). The section holds the nominal
    value of such a key: its first value, or the low end of its range."""
    if not isinstance(raw, dict):
        raise ConfigError(f"[output] must be a table, got {type(raw).__name__}")
    fixed = {k: v for k, v in raw.items() if k not in SAMPLING_KEYS or not isinstance(v, (list, dict))}
    output = _parse_table(fixed, _OUTPUT_DEFS, "output")
    sampling: dict[str, Spec] = {}
    for key in SAMPLING_KEYS:
        if key in fixed or key not in raw:
            continue
        spec = parse_spec(PARAMS[key], raw[key], f"output.{key}")
        values = spec_candidates(spec)
        if not isinstance(spec, DistSpec) or spec.dist == "choice":
            if len(set(values)) == 1:
                output[key] = values[0]
                continue
        sampling[key] = spec
        output[key] = values[0]
    return OutputSection(**output), sampling


#: ``[output]`` keys added after stores were written, and the value that reproduces the bytes
#: of a store whose config lacks them
_STORED_DEFAULTS = {"rendering": "elements"}
#: likewise for ``[labels]`` keys (a store written before the picked fault target drew its
#: traces)
_STORED_LABEL_DEFAULTS = {"fault_style": "traces"}


def stored_config(raw: dict[str, Any], *, source: str = "store config") -> Config:
    """The config of an existing store (its ``config`` attribute): a key the store's version did
    not know takes the value that reproduces its bytes (a store written before the ``strata``
    rendering was rendered from elements, and drew its faults as traces), then
    :func:`parse_config`."""
    raw = dict(raw)
    output = dict(raw.get("output", {}))
    for key, value in _STORED_DEFAULTS.items():
        output.setdefault(key, value)
    raw["output"] = output
    labels = dict(raw.get("labels", {}))
    for key, value in _STORED_LABEL_DEFAULTS.items():
        labels.setdefault(key, value)
    raw["labels"] = labels
    return parse_config(raw, source=source)


def _cross_checks(cfg: Config) -> None:
    """Checks that involve more than one key."""
    throw = spec_values_hint(cfg.sweep.params["throw_m"])
    if throw and throw[1] > 0.6 * cfg.model.height_m:
        raise ConfigError(
            f"sweep.throw_m up to {throw[1]:g} m is too large for model.height_m = "
            f"{cfg.model.height_m:g}: at most 0.6 * height_m = {0.6 * cfg.model.height_m:g} m"
        )
    if cfg.grid.cell_m * 4 > min(cfg.model.width_m, cfg.model.height_m):
        raise ConfigError(f"grid.cell_m = {cfg.grid.cell_m:g} is too coarse for the model box")
    # a basement without faults deforms only through its stretching base
    if ("none" in spec_candidates(cfg.sweep.params["structure"])
            and 0.0 in spec_candidates(cfg.sweep.params["base_stretch"])):
        raise ConfigError("sweep.structure = 'none' (no basement fault) needs sweep.base_stretch "
                          "!= 0, and base_stretch can be 0 in this sweep: nothing would deform "
                          "the model")
    # every extreme value of every property parameter must make a valid PropertyModel
    for key in PROPERTY_FIELDS:
        spec = cfg.sweep.params[key]
        candidates = spec_candidates(spec)
        for value in candidates:
            try:
                PropertyModel(**{**cfg.properties, key: value}).validate()
            except ConfigError as exc:
                raise ConfigError(f"sweep.{key}: {exc}") from None
    # and of every bed parameter a valid BedModel (thinnest <= median <= thickest bed)
    fixed = {k: (s.value if isinstance(s, Fixed) else PARAMS[k].default)
             for k, s in ((k, cfg.sweep.params[k]) for k in BED_FIELDS)}
    for key in BED_FIELDS:
        for value in spec_candidates(cfg.sweep.params[key]):
            try:
                BedModel(**{**fixed, key: value}).validate()
            except ConfigError as exc:  # BedModel names its fields strata.<name>
                raise ConfigError(str(exc).replace("strata.", "sweep.")) from None
    domains = (spec_candidates(cfg.sampling["domain"]) if "domain" in cfg.sampling
               else (cfg.output.domain,))
    if "dt_s" in cfg.sampling and "time" not in domains:
        raise ConfigError("output.dt_s is given several values, but output.domain = "
                          f"{cfg.output.domain!r}: dt_s samples only time-domain sections (set "
                          "[output] domain = 'time', or give dt_s one value)")
    # the engine's own rules (the DEM's: elements fit, a fault can form, quasi-static)
    engine = ENGINES.get(cfg.model.engine)
    rendering = RENDERINGS.get(cfg.output.rendering)
    if rendering.reference and not getattr(engine, "strata", False):
        raise ConfigError(f"output.rendering = {cfg.output.rendering!r} needs an engine whose "
                          f"states carry a reference map and stratigraphy, and engine "
                          f"{cfg.model.engine!r} has none: set [output] rendering = 'elements'")
    if cfg.labels.throw_from == "offset" and not rendering.reference:
        raise ConfigError("labels.throw_from = 'offset' measures the reflectors' offsets on the "
                          "reference map, which output.rendering = "
                          f"{cfg.output.rendering!r} has not: set [output] rendering = 'strata' "
                          "or labels.throw_from = 'slip'")
    if cfg.labels.fault_uncertain and not rendering.reference:
        raise ConfigError("labels.fault_uncertain = true compares the labels with the "
                          "reflectors' offsets on the reference map, which output.rendering = "
                          f"{cfg.output.rendering!r} has not: set [output] rendering = 'strata' "
                          "or labels.fault_uncertain = false")
    engine.check(cfg)


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


#: the tables whose values may be distributions (tables themselves): merged key by key
_SPEC_TABLES = ("sweep", "output")


def _merge(base: dict[str, Any], over: dict[str, Any]) -> dict[str, Any]:
    out = dict(base)
    for key, value in over.items():
        if isinstance(value, dict) and isinstance(out.get(key), dict) and key not in _SPEC_TABLES:
            out[key] = _merge(out[key], value)
        elif key in _SPEC_TABLES and isinstance(value, dict) and isinstance(out.get(key), dict):
            out[key] = {**out[key], **value}  # a distribution replaces, never merges into, another
        else:
            out[key] = value
    return out
