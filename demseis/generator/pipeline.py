"""One DEM run → all of its labelled samples (one shard).

``simulate_run`` runs the DEM; ``render_run`` turns its snapshots into sections and labels.
They are separate so that ``demseis render`` can re-render stored particle snapshots at new
frequencies and noise levels without re-running the DEM.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from demseis.dem.types import Material, NormalFault
from demseis.types import Snapshot
from demseis.generator.config import _MATERIAL_FIELDS, Config, _property_params, all_params
from demseis.generator.sampling import RunSpec, plan_run, rng_at, seed_sequence
from demseis.types import Grid

#: integer codes of string parameters in the store (``params/<name>`` holds the index)
PARAM_CODES: dict[str, tuple[str, ...]] = {
    "noise_kind": ("white", "band"),
    "dip_direction": ("right", "left"),
    "contact_model": ("frictional", "bonded"),
}

SAMPLE_ARRAYS: dict[str, str] = {
    "seismic": "float32",
    "fault": "uint8",
    "damage": "uint8",
    "strain": "float32",
    "layer": "int16",
}


def grid_of(cfg: Config) -> Grid:
    """The raster grid shared by every sample of a sweep."""
    return Grid.covering(cfg.model.width_m, cfg.model.height_m, cfg.grid.cell_m)


def time_axis_of(cfg: Config) -> np.ndarray | None:
    """The two-way-time axis (s) of a time-domain sweep, None in the depth domain.

    Its length must be the same for every run, so it is built for the slowest Vp any run can
    produce: the smallest lithology Vp, lowered by the largest ``vp_scatter`` the sweep allows.
    """
    if cfg.output.domain != "time":
        return None
    from demseis.generator.params import spec_values_hint
    from demseis.seismic import time_axis

    scatter_hi = spec_values_hint(cfg.sweep.params["vp_scatter"])[1]
    vp_min = float(min(cfg.properties["vp_min_m_s"])) * (1.0 - 3.0 * float(scatter_hi))
    grid = grid_of(cfg)
    return time_axis(grid.nz, grid.cell_m, vp_min, cfg.output.dt_s)


def sample_shape(cfg: Config) -> tuple[int, int]:
    """(H, W) of every stored sample: grid cells (depth) or (time samples, columns)."""
    grid = grid_of(cfg)
    t_s = time_axis_of(cfg)
    return grid.shape if t_s is None else (int(t_s.size), grid.nx)


def array_dtypes(cfg: Config) -> dict[str, str]:
    """Name → dtype of the per-sample arrays this config stores."""
    out = dict(SAMPLE_ARRAYS)
    if cfg.output.impedance:
        out["impedance"] = "float32"
    return out


def param_dtypes() -> dict[str, str]:
    """Name → dtype of the per-sample parameter arrays (``params/`` in the store)."""
    out = {
        "run_id": "int32",
        "sample_in_run": "int32",
        "snapshot": "int16",
        "step": "int64",
        "throw_m": "float32",
        "throw_target_m": "float32",
        "fault_x_m": "float32",
        "n_elements": "int32",
        "freq_hz": "float32",
        "snr_db": "float32",
        "noise_seed": "uint64",
    }
    for key, pdef in all_params().items():
        if key in out:
            continue
        if key in PARAM_CODES:
            out[key] = "int8"
        elif pdef.kind is int:
            out[key] = "int32"
        elif pdef.kind is bool:
            out[key] = "uint8"
        else:
            out[key] = "float32"
    return out


def layer_thicknesses(cfg: Config, n_layers: int, cv: float, rng: np.random.Generator) -> np.ndarray | None:
    """Layer thicknesses (bottom to top) summing to the model height; None for equal layers.

    With ``cv > 0`` relative thicknesses are Gamma(1/cv², ·) draws (coefficient of variation
    ``cv``), floored at two minimum element diameters so that every layer holds elements.
    """
    if cv <= 0 or n_layers == 1:
        return None
    w = rng.gamma(1.0 / cv**2, 1.0, size=n_layers)
    h = cfg.model.height_m * w / w.sum()
    floor = min(4.0 * cfg.model.radius_min_m, cfg.model.height_m / n_layers)
    for _ in range(50):
        short = h < floor
        if not short.any():
            break
        deficit = (floor - h[short]).sum()
        h[short] = floor
        h[~short] -= deficit * h[~short] / h[~short].sum()
    return h


def run_info(cfg: Config, params: dict[str, Any]) -> dict[str, Any]:
    """Derived per-run values stored with every sample: the fault's x at the base, the target throw.

    ``fault_x_frac`` places the basement fault where it meets the base of the model. The fault
    that grows through the cover is usually steeper than the basement fault (it is not
    imposed), so its trace at the surface lies on the footwall side of that point.
    """
    return {"fault_x_m": float(params["fault_x_frac"]) * cfg.model.width_m,
            "throw_target_m": float(params["throw_m"])}


def material_of(params: dict[str, Any]) -> Material:
    """The DEM material of a run."""
    return Material(**{field: params[key] for key, field in _MATERIAL_FIELDS.items()})


def property_model_of(cfg: Config, params: dict[str, Any]) -> Any:
    """The rock-property model of a run (scalar fields from the run's parameters)."""
    from demseis.seismic import PropertyModel

    scalar = {p.name: params[p.name] for p in _property_params()}
    return PropertyModel(**cfg.properties, **scalar)


def simulate_run(
    cfg: Config, spec: RunSpec, progress: Callable[[float], None] | None = None
) -> tuple[list[Snapshot], dict[str, Any]]:
    """Build the assembly of run ``spec.run`` and fault it; returns (snapshots, run info)."""
    from demseis.dem import build_assembly, simulate

    p = spec.params
    material = material_of(p)
    thick = layer_thicknesses(cfg, int(p["n_layers"]), float(p["layer_thickness_cv"]),
                              rng_at(cfg, spec.run, 4))
    info = run_info(cfg, p)
    fault = NormalFault(
        x_m=info["fault_x_m"],
        dip_deg=float(p["dip_deg"]),
        throw_m=float(p["throw_m"]),
        dip_direction=str(p["dip_direction"]),
        speed_m_s=cfg.model.wall_speed_m_s,
    )
    rng = rng_at(cfg, spec.run, 1)
    asm = build_assembly(
        cfg.model.width_m, cfg.model.height_m,
        radius_min_m=cfg.model.radius_min_m, radius_max_m=cfg.model.radius_max_m,
        n_layers=int(p["n_layers"]), layer_thickness_m=thick, material=material, rng=rng,
    )
    snaps = simulate(asm, fault, material, n_snapshots=cfg.model.n_snapshots,
                     sedimentation=cfg.model.sedimentation, rng=rng, progress=progress)
    return snaps, info


@dataclass(frozen=True)
class ShardData:
    """All samples of one run: (S, H, W) arrays, (S,) parameters and the particle snapshots."""

    arrays: dict[str, np.ndarray]
    params: dict[str, np.ndarray]
    snapshots: list[Snapshot]


def render_run(cfg: Config, spec: RunSpec, snapshots: list[Snapshot], info: dict[str, Any]) -> ShardData:
    """Sections and labels of every render of ``spec`` from its snapshots."""
    from demseis.labels import label_maps, strain_history
    from demseis.seismic import (
        add_noise,
        depth_to_time,
        draw_layer_properties,
        element_properties,
        property_grids,
        synthetic_sections,
    )

    grid = grid_of(cfg)
    p = spec.params
    model = property_model_of(cfg, p)
    n_layers_total = max(int(s.layer.max()) for s in snapshots) + 1
    layer_props = draw_layer_properties(n_layers_total, model, rng_at(cfg, spec.run, 2))
    elem_seed = int(seed_sequence(cfg, spec.run, 2).generate_state(2, dtype=np.uint64)[1])
    history = strain_history(snapshots, cfg.labels)

    dtypes = array_dtypes(cfg)
    S = len(spec.renders)
    t_s = time_axis_of(cfg)
    arrays = {k: np.zeros((S, *sample_shape(cfg)), dtype=v) for k, v in dtypes.items()}
    pdt = param_dtypes()
    params = {k: np.zeros(S, dtype=v) for k, v in pdt.items()}

    by_snap: dict[int, list] = {}
    for r in spec.renders:
        by_snap.setdefault(r.snapshot, []).append(r)
    for k, renders in sorted(by_snap.items()):
        snap = snapshots[k]
        vp_e, rho_e = element_properties(snap.ids, snap.layer, layer_props, model, elem_seed)
        vp_g, rho_g = property_grids(snap.xy, snap.radius, vp_e, rho_e, snap.layer, grid, model)
        maps = dict(label_maps(snap, history[k], grid, cfg.labels))
        freqs = sorted({r.freq_hz for r in renders})
        impedance = vp_g * rho_g
        if t_s is None:
            sections = synthetic_sections(vp_g, rho_g, grid.cell_m, freqs)
        else:
            sections = synthetic_sections(vp_g, rho_g, grid.cell_m, freqs, domain="time", t_s=t_s)
            fills = {"fault": 0, "damage": 0, "strain": 0.0, "layer": -1}
            for name, fill in fills.items():
                maps[name] = depth_to_time(maps[name], vp_g, grid.cell_m, t_s, method="nearest", fill=fill)
            impedance = depth_to_time(impedance, vp_g, grid.cell_m, t_s, method="nearest", fill=0.0)
        for r in renders:
            clean = sections[freqs.index(r.freq_hz)]
            noisy = add_noise(clean, r.snr_db, r.noise_kind, np.random.default_rng(r.seed))
            i = r.sample
            arrays["seismic"][i] = noisy
            arrays["fault"][i] = maps["fault"]
            arrays["damage"][i] = maps["damage"]
            arrays["strain"][i] = maps["strain"]
            arrays["layer"][i] = maps["layer"]
            if "impedance" in arrays:
                arrays["impedance"][i] = impedance
            row = {
                "run_id": spec.run, "sample_in_run": i, "snapshot": k, "step": snap.step,
                "throw_m": snap.throw_m, "n_elements": snap.n, "freq_hz": r.freq_hz,
                "snr_db": r.snr_db, "noise_seed": r.seed, "noise_kind": r.noise_kind, **info,
            }
            for key, value in {**p, **row}.items():
                if key in PARAM_CODES:
                    value = PARAM_CODES[key].index(value)
                params[key][i] = value
    return ShardData(arrays=arrays, params=params, snapshots=snapshots)


def run_shard(cfg: Config, run: int, progress: Callable[[float], None] | None = None, *,
              timings: dict[str, float] | None = None) -> ShardData:
    """DEM run ``run`` and all its renders; ``timings`` (if given) gets dem_s and render_s."""
    import time

    t0 = time.perf_counter()
    spec = plan_run(cfg, run)
    snaps, info = simulate_run(cfg, spec, progress)
    t1 = time.perf_counter()
    data = render_run(cfg, spec, snaps, info)
    if timings is not None:
        timings.update(dem_s=t1 - t0, render_s=time.perf_counter() - t1)
    return data
