"""What a sweep stores: its raster grid, sample shape, sample arrays and parameter arrays.

Everything here is derived from a :class:`~demseis.generator.config.settings.Config` and the
declarations on the ground floor: the sample arrays from :mod:`demseis.schema`, the
per-sample parameters from :mod:`demseis.parameters` (``SCENARIO`` and ``STORED``).
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any

import numpy as np

from demseis.generator.config.params import spec_candidates, spec_values_hint
from demseis.generator.config.settings import Config
from demseis.parameters import SAMPLING_STORED, SCENARIO, STORED
from demseis.schema import SAMPLE_ARRAYS, stored_arrays
from demseis.seismic import time_axis
from demseis.types import Grid

#: the order of the code tables in a store's ``param_codes`` attribute: the order in which
#: these parameters were added, so that a store keeps its bytes; a new ``str`` parameter goes
#: after them
_CODES_ORDER = ("noise_kind", "dip_direction", "contact_model", "imaging", "structure",
                "fault_kind", "fold_kind", "wavelet", "wavelet_phase")


def param_codes() -> dict[str, tuple[str, ...]]:
    """Integer codes of every ``str`` per-sample parameter: the ``params`` table holds the index
    of the value among its declared choices (``fault<k>_kind`` and ``fault<k>_dip_direction``
    index ``fault_kind`` and ``dip_direction``)."""
    names = sorted((k for k, p in SCENARIO.items() if p.kind is str),
                   key=lambda k: _CODES_ORDER.index(k) if k in _CODES_ORDER else len(_CODES_ORDER))
    return {k: tuple(SCENARIO[k].choices) for k in names}


def grid_of(cfg: Config) -> Grid:
    """The raster grid shared by every sample of a sweep."""
    return Grid.covering(cfg.model.width_m, cfg.model.height_m, cfg.grid.cell_m)


def trace_spacing(cfg: Config) -> float:
    """The distance between output traces (m): ``[output] trace_spacing_m``, or the cell."""
    dx = float(cfg.output.trace_spacing_m)
    return dx if dx > 0 else float(cfg.grid.cell_m)


def on_grid(cfg: Config) -> bool:
    """Whether the traces are the grid's columns (no lateral resampling)."""
    return float(cfg.output.trace_spacing_m) in (0.0, float(cfg.grid.cell_m))


def trace_x(cfg: Config) -> np.ndarray:
    """(ntr,) x (m) of the traces: ``(j + 0.5) dx`` for every trace inside the model width."""
    dx = trace_spacing(cfg)
    n = max(1, int(math.floor(cfg.model.width_m / dx + 1e-9)))
    return (np.arange(n) + 0.5) * dx


def time_axis_of(cfg: Config) -> np.ndarray | None:
    """The two-way-time axis (s) of a time-domain sweep, None in the depth domain.

    Its length must be the same for every run. ``[output] time_window = "model"``: built for
    the slowest Vp any run can produce (the smallest lithology Vp, lowered by the largest
    ``vp_scatter`` the sweep allows), so the whole model fits. ``"rock"``: the two-way time of
    the model's height at the fastest Vp (the largest lithology Vp, raised by three times the
    largest ``vp_scatter`` and by the largest burial gradient over the height), so every
    column holds rock to the last sample.
    """
    if cfg.output.domain != "time":
        return None
    scatter_hi = float(spec_values_hint(cfg.sweep.params["vp_scatter"])[1])
    grid = grid_of(cfg)
    if cfg.output.time_window == "rock":
        grad_hi = float(spec_values_hint(cfg.sweep.params["vp_gradient_per_km"])[1])
        vp_fast = (float(max(cfg.properties["vp_max_m_s"])) * (1.0 + 3.0 * scatter_hi)
                   * (1.0 + grad_hi * grid.nz * grid.cell_m / 1000.0))
        n = max(int(np.floor(2.0 * grid.nz * grid.cell_m / (vp_fast * cfg.output.dt_s))), 1)
        return np.arange(n) * float(cfg.output.dt_s)
    vp_min = float(min(cfg.properties["vp_min_m_s"])) * (1.0 - 3.0 * scatter_hi)
    return time_axis(grid.nz, grid.cell_m, vp_min, cfg.output.dt_s)


def section_shape(cfg: Config) -> tuple[int, int]:
    """(H, W) of a section rendered with ``cfg.output``'s sampling: (grid rows or time samples,
    traces); the traces are the grid's columns unless ``[output] trace_spacing_m`` says
    otherwise (:func:`trace_x`)."""
    grid = grid_of(cfg)
    t_s = time_axis_of(cfg)
    width = int(trace_x(cfg).size)
    return (grid.nz, width) if t_s is None else (int(t_s.size), width)


def sample_shape(cfg: Config) -> tuple[int, int]:
    """(H, W) of every stored sample. With one sampling per store, the section's shape
    (:func:`section_shape`). Where ``[output] dt_s`` or ``trace_spacing_m`` varies from run to
    run (``Config.sampling``), the smallest section any run can give (at the largest
    ``dt_s`` and ``trace_spacing_m``): every run's section is cropped to it, never padded
    (:func:`crop_to`)."""
    if not cfg.sampling:
        return section_shape(cfg)
    shapes = [section_shape(dataclasses.replace(cfg, output=dataclasses.replace(cfg.output, **c)))
              for c in _corners(cfg)]
    return min(h for h, _ in shapes), min(w for _, w in shapes)


def _corners(cfg: Config) -> list[dict[str, Any]]:
    """Every combination of the extreme values of the varied sampling keys."""
    combos: list[dict[str, Any]] = [{}]
    for key, spec in cfg.sampling.items():
        combos = [{**c, key: v} for c in combos for v in spec_candidates(spec)]
    return combos


def crop_to(section: np.ndarray, shape: tuple[int, int]) -> np.ndarray:
    """``section`` (..., H, W) cut to ``shape`` (h, w) <= (H, W): the first ``h`` rows (from the
    top of the model, or time zero) and the ``w`` middle traces (``(W - w) // 2`` dropped on
    the left)."""
    h, w = shape
    H, W = section.shape[-2:]
    if h > H or w > W:
        raise ValueError(f"a section of {H} x {W} cannot be cropped to {h} x {w}")
    left = (W - w) // 2
    return section[..., :h, left:left + w]


def array_dtypes(cfg: Config) -> dict[str, str]:
    """Name → dtype of the per-sample arrays this config stores, in store order."""
    options = {a.option for _, a in SAMPLE_ARRAYS.items() if a.option is not None
               and (getattr(cfg.output, a.option, False) or getattr(cfg.labels, a.option, False))}
    return {name: SAMPLE_ARRAYS.get(name).dtype for name in stored_arrays(options)}


def param_dtypes(cfg: Config) -> dict[str, str]:
    """Name → dtype of the per-sample parameter arrays of ``cfg``'s store (the columns of its
    ``params`` table), the sampling of each sample among them where it varies from run to run
    (:data:`demseis.parameters.SAMPLING_STORED`)."""
    out = {s.name: s.dtype for s in STORED}
    if cfg.sampling:
        out.update({s.name: s.dtype for s in SAMPLING_STORED})
    codes = param_codes()
    for key, pdef in cfg.scenario.items():   # the engine's own parameters last
        if key in out:
            continue
        if key in codes:
            out[key] = "int8"
        elif pdef.kind is int:
            out[key] = "int32"
        elif pdef.kind is bool:
            out[key] = "uint8"
        else:
            out[key] = "float32"
    return out
