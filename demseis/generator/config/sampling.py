"""From a :class:`Config` to concrete runs and renders, with one SeedSequence tree.

Seed tree (spawn keys under the sweep seed; the second key is one of the named constants)::

    (run,)                           the run's root
    (run, SEED_RUN_PARAMS)           run-level parameter draws
    (run, SEED_DEM)                  the DEM (packing, settling, sedimentation)
    (run, SEED_PROPERTIES)           rock properties (per-layer draws; per-element scatter seed)
    (run, SEED_RENDER, sample)       one sample's render draws and its noise seed
    (run, SEED_LAYERS)               layer thicknesses (``layer_thickness_cv > 0``)
    (run, SEED_FAULTS)               placement of a fault system (``structure != "single"``)
    (run, SEED_STRATA)               the beds of the ``strata`` rendering
    (run, SEED_POPULATION)           the kinematic engine's fault population (``base_stretch``)
    (run, SEED_PACK)                 the order in which runs run .. run + K - 1 take the K packs
                                     of ``[model] pack_library`` (run a multiple of K)
    (run, SEED_SAMPLING)             the run's section sampling (``[output] dt_s`` and
                                     ``trace_spacing_m`` given as distributions)

A run's values depend only on the sweep seed and the run index, never on worker count or order.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Iterator, Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from demseis.generator.config.params import DistSpec, Fixed, GridSpec
from demseis.generator.config.settings import Config, _cross, engine_parameters
from demseis.parameters import SCENARIO, Param, declared_dataclass
from demseis.seismic.wavelet import Wavelet

#: second spawn key of a run's seed tree (values fixed: changing one changes every dataset)
SEED_RUN_PARAMS = 0
SEED_DEM = 1
SEED_PROPERTIES = 2
SEED_RENDER = 3
SEED_LAYERS = 4
SEED_FAULTS = 6
SEED_STRATA = 7
SEED_POPULATION = 8
SEED_PACK = 9
SEED_SAMPLING = 10


def seed_sequence(cfg: Config, *key: int) -> np.random.SeedSequence:
    """The SeedSequence at ``key`` in the sweep's tree."""
    return np.random.SeedSequence(cfg.sweep.seed, spawn_key=tuple(int(k) for k in key))


def rng_at(cfg: Config, *key: int) -> np.random.Generator:
    """A Generator seeded from the tree node ``key``."""
    return np.random.default_rng(seed_sequence(cfg, *key))


#: the sample-level parameters, in declaration order: the order in which a render draws them
#: (a parameter declared later draws after the others, so older configs keep their values)
SAMPLE_KEYS: tuple[str, ...] = tuple(k for k, p in SCENARIO.items() if p.level == "sample")


@dataclass(frozen=True)
class Render:
    """One rendered sample of a snapshot.

    Attributes
    ----------
    sample : index within the run.
    snapshot : the snapshot it renders.
    seed : 64-bit seed of the noise Generator.
    values : every sample-level parameter (:data:`SAMPLE_KEYS`: ``freq_hz``, ``snr_db``,
        ``noise_kind``, ``imaging`` and the imaging modes' options).
    """

    sample: int
    snapshot: int
    seed: int
    values: dict[str, Any]

    @property
    def freq_hz(self) -> float:
        return float(self.values["freq_hz"])

    @property
    def snr_db(self) -> float:
        return float(self.values["snr_db"])

    @property
    def noise_kind(self) -> str:
        return str(self.values["noise_kind"])

    @property
    def imaging(self) -> str:
        return str(self.values["imaging"])

    @property
    def wavelet(self) -> Wavelet:
        """The sample's source wavelet (a zero-phase Ricker of ``freq_hz`` by default)."""
        v = self.values
        return Wavelet(str(v.get("wavelet", "ricker")), float(v["freq_hz"]),
                       float(v.get("band_octaves", 2.0)), float(v.get("wavelet_phase_deg", 0.0)),
                       str(v.get("wavelet_phase", "zero")))


#: the run-level parameters, in declaration order (the fields of :class:`RunParams`)
RUN_KEYS: tuple[str, ...] = tuple(k for k, p in SCENARIO.items() if p.level == "run")


class _RunValues(Mapping):
    """The methods of :class:`RunParams`: besides its typed fields (``params.dip_deg``), it
    reads as the mapping ``name -> value`` of every run-level parameter (``params["dip_deg"]``,
    ``{**params}``), in declaration order, then the engine's own parameters
    (:func:`demseis.generator.config.settings.engine_parameters`), which read the same way
    (``params.my_param``, ``params["my_param"]``)."""

    engine_values: tuple[tuple[str, Any], ...]

    def __getitem__(self, key: str) -> Any:
        if key not in RUN_KEYS and all(name != key for name, _ in self.engine_values):
            raise KeyError(key)
        return getattr(self, key)

    def __getattr__(self, name: str) -> Any:   # only for names that are not fields
        if name.startswith("__") or name == "engine_values":
            raise AttributeError(name)
        for key, value in self.engine_values:
            if key == name:
                return value
        raise AttributeError(f"no run parameter {name!r}")

    def __iter__(self) -> Iterator[str]:
        yield from RUN_KEYS
        yield from (name for name, _ in self.engine_values)

    def __len__(self) -> int:
        return len(RUN_KEYS) + len(self.engine_values)

    @classmethod
    def of(cls, values: Mapping[str, Any],
           engine: Mapping[str, Param] | None = None) -> RunParams:
        """The run parameters ``values``, each coerced to its declared kind (a run-level
        parameter not given takes its declared default); ``engine``: the declarations of the
        engine's own parameters among them (:meth:`Config.scenario`). A :class:`KeyError`
        names a key that is neither."""
        engine = engine or {}
        unknown = sorted(set(values) - set(RUN_KEYS) - set(engine))
        if unknown:
            raise KeyError(f"not run-level parameters: {', '.join(unknown)}; declared: "
                           f"{', '.join(RUN_KEYS)}")
        own = tuple((k, engine[k].kind(v)) for k, v in values.items() if k in engine)
        return cls(**{k: SCENARIO[k].kind(v) for k, v in values.items() if k in RUN_KEYS},
                   engine_values=own)

    def replace(self, **changes: Any) -> RunParams:
        """These values with ``changes``, each coerced to the kind of the value it replaces."""
        kinds = {k: type(v) for k, v in self.engine_values}
        unknown = sorted(set(changes) - set(RUN_KEYS) - set(kinds))
        if unknown:
            raise KeyError(f"not parameters of this run: {', '.join(unknown)}")
        merged = {**self, **changes}
        own = tuple((k, kind(merged[k])) for k, kind in kinds.items())
        return dataclasses.replace(self.of({k: merged[k] for k in RUN_KEYS}), engine_values=own)


RunParams = declared_dataclass(
    "RunParams", (SCENARIO[k] for k in RUN_KEYS), module=__name__, bases=(_RunValues,),
    extra=[("engine_values", tuple, dataclasses.field(default=()))],
    doc="""The run-level parameter values of one run, built once by :func:`run_params`: a
frozen object with one typed field per run-level parameter of :mod:`demseis.parameters`
(``dip_deg: float``, ``structure: str``, ``n_layers: int``, ...) and ``engine_values``, the
(name, value) pairs of the engine's own parameters; it reads as a mapping too (see
``_RunValues``).""")


@dataclass(frozen=True)
class RunSpec:
    """Everything one run (of any engine) and its renders need.

    ``params``: the run-level values, a :class:`RunParams` (a mapping given is made one).
    """

    run: int
    params: RunParams
    renders: tuple[Render, ...]

    def __post_init__(self) -> None:
        if not isinstance(self.params, RunParams):
            object.__setattr__(self, "params", RunParams.of(self.params))


def run_params(cfg: Config, run: int) -> RunParams:
    """Run-level parameter values of run ``run``.

    Run-level grids are crossed (in key order) and cycled over the runs: run ``i`` takes
    combination ``i mod G``. Distributions are drawn from node ``(run, SEED_RUN_PARAMS)`` in
    key order: the declared parameters, then the engine's own.
    """
    own = engine_parameters(cfg.model.engine)
    run_specs = {k: s for k, s in cfg.sweep.params.items()
                 if k in own or SCENARIO[k].level == "run"}
    return RunParams.of(_draw(run_specs, run, rng_at(cfg, run, SEED_RUN_PARAMS)), own)


def plan_run(cfg: Config, run: int) -> RunSpec:
    """Run-level values and the list of renders (samples) of run ``run``."""
    renders = []
    combos = cfg.render_grid()
    sample = 0
    for snap in range(cfg.model.n_snapshots):
        for combo in combos:
            for _ in range(cfg.sweep.renders_per_snapshot):
                ss = seed_sequence(cfg, run, SEED_RENDER, sample)
                rng = np.random.default_rng(ss)
                vals = {}
                for key in SAMPLE_KEYS:
                    spec = combo[key]
                    if isinstance(spec, Fixed):
                        value = spec.value
                    elif isinstance(spec, DistSpec):
                        value = spec.sample(rng)
                    elif isinstance(spec, GridSpec):  # pragma: no cover - crossed away
                        raise AssertionError(key)
                    else:
                        value = spec
                    vals[key] = SCENARIO[key].kind(value)
                noise_seed = int(ss.generate_state(2, dtype=np.uint64)[1])
                renders.append(Render(sample=sample, snapshot=snap, seed=noise_seed, values=vals))
                sample += 1
    return RunSpec(run=run, params=run_params(cfg, run), renders=tuple(renders))


def _draw(specs: dict[str, Any], run: int, rng: np.random.Generator) -> dict[str, Any]:
    """Values of run ``run``: lists crossed (in key order) and cycled over the runs (run ``i``
    takes combination ``i mod G``), distributions drawn from ``rng`` in key order."""
    combos = _cross(specs)
    out: dict[str, Any] = {}
    for key, spec in combos[run % len(combos)].items():
        if isinstance(spec, Fixed):
            out[key] = spec.value
        elif isinstance(spec, DistSpec):
            out[key] = spec.sample(rng)
        else:
            out[key] = spec
    return out


def config_of_run(cfg: Config, run: int) -> Config:
    """The config run ``run`` renders with: ``cfg`` with its ``[output]`` sampling keys
    (``Config.sampling``) set to the run's values; ``cfg`` itself when the store has one
    sampling. Lists cycle over the runs, distributions are drawn from node
    ``(run, SEED_SAMPLING)``; the result keeps ``sampling``, so the store's shape and parameter
    table (:mod:`demseis.generator.config.layout`) are the same for every run."""
    if not cfg.sampling:
        return cfg
    values = _draw(cfg.sampling, run, rng_at(cfg, run, SEED_SAMPLING))
    return dataclasses.replace(cfg, output=dataclasses.replace(cfg.output, **values))
