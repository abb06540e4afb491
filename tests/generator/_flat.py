"""A toy engine outside the package (no faulting, flat beds of alternating rock) and a toy
label array, defined but not registered. Used by ``test_extensions.py`` (registered in the
test's process), by the plug-in module ``_plugin.py`` (imported by a sweep's workers) and as
the target of entry points (``test_registry.py``)."""

from __future__ import annotations

from collections.abc import Iterator, Mapping, Sequence
from typing import Any

import numpy as np

from demseis.errors import ConfigError
from demseis.generator.config.layout import grid_of
from demseis.generator.engines import EngineRun, State
from demseis.generator.engines.runsetup import run_info, run_strata
from demseis.parameters import Param
from demseis.schema import SampleArray, engine_labels, sample_array
from demseis.seismic import LayerProperties


class FlatEngine:
    """No faulting: horizontal beds of alternating rock, ``bed_cells`` cells thick (its own
    run-level parameter), the same at every snapshot."""

    particles = False
    strata = True
    parameters = (Param("bed_cells", int, "run", 5, 2, 20, unit="cells",
                        doc="flat engine: thickness of its beds"),)

    def __init__(self) -> None:
        self.simulated: list[int] = []

    def check(self, cfg) -> None:
        if cfg.model.width_m < 500:
            raise ConfigError("flat engine: model.width_m must be >= 500")

    def cost(self, cfg, params: Mapping[str, Any]) -> float:
        return 1.0

    def describe(self, cfg) -> tuple[str, float]:
        return "flat beds", 0.01

    def simulate(self, cfg, spec, progress=None) -> EngineRun:
        self.simulated.append(spec.run)
        return EngineRun(spec=spec, info=run_info(cfg, spec.params, spec.run))

    def states(self, cfg, run: EngineRun, snapshots: Sequence[int]) -> Iterator[State]:
        grid = grid_of(cfg)
        cells = run.spec.params.bed_cells
        rows = np.arange(grid.nz)[:, None] * np.ones((1, grid.nx))
        bed = (rows // cells).astype(np.int16)
        vp = np.where(bed % 2 == 0, 2500.0, 3200.0)
        rho = np.full(grid.shape, 2300.0)
        # the strata rendering: the same beds as mechanical units (bottom first), and rock
        # that never moved (reference coordinates = present ones)
        n = grid.nz // cells
        top = grid.top_m - cells * grid.cell_m * np.arange(n)      # unit tops, top first
        props = LayerProperties(lithology=np.zeros(n, np.int16),
                                vp=np.where(np.arange(n)[::-1] % 2 == 0, 2500.0, 3200.0),
                                rho=np.full(n, 2300.0))
        strata = run_strata(cfg, run.spec.params, run.spec.run, top[::-1] - cells * grid.cell_m,
                            top[::-1], props)

        def unmoved(x_m, depth_m):
            return x_m, grid.top_m - depth_m, np.full(np.shape(x_m), -1)

        for k in snapshots:
            labels = {n: np.zeros(grid.shape, sample_array(n).dtype) for n in engine_labels()}
            labels["layer"] = bed
            yield State(snapshot=k, vp_m_s=vp, rho_kg_m3=rho, labels=labels,
                        values={"step": k, "throw_m": 0.0, "n_elements": 0},
                        reference=unmoved, strata=strata)


#: the engine a config names as "tests.generator._plugin:FLAT"
FLAT = FlatEngine()


def _parity(state: State) -> np.ndarray:
    """1 on odd layers, 0 on even ones and above the rock (from the engine's layer label)."""
    layer = state.labels["layer"]
    return ((layer >= 0) & (layer % 2 == 1)).astype(np.uint8)


#: a label array that exists in every process that imports this module
PARITY = SampleArray("layer_parity", "uint8", "label", "1", "1 on odd layers", fill=0,
                     valid_range=(0, 1), producer=_parity)
