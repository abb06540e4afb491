"""One DEM run → all of its labelled samples (one shard).

``simulate_run`` runs the DEM; ``render_run`` turns its snapshots into sections and labels.
They are separate so that ``demseis render`` can re-render stored particle snapshots at new
frequencies and noise levels without re-running the DEM.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from demseis.dem.types import Material, NormalFault
from demseis.types import Snapshot
from demseis.datasets.store import DEFAULT_ARRAYS, SAMPLE_ARRAYS
from demseis.generator.config import Config
from demseis.generator.sampling import (
    SEED_DEM,
    SEED_FAULTS,
    SEED_LAYERS,
    SEED_PROPERTIES,
    Render,
    RunSpec,
    plan_run,
    rng_at,
    seed_sequence,
)
from demseis.parameters import MATERIAL_FIELDS, PARAMS, PROPERTY_FIELDS, SCENARIO, STORED
from demseis.types import Grid

#: integer codes of string parameters in the store (``params/<name>`` holds the index)
PARAM_CODES: dict[str, tuple[str, ...]] = {
    "noise_kind": ("white", "band"),
    "dip_direction": ("right", "left"),
    "contact_model": PARAMS["contact_model"].choices,
    "imaging": ("1d", "psf"),
    "structure": PARAMS["structure"].choices,
    "fault_kind": PARAMS["fault_kind"].choices,
    "fold_kind": PARAMS["fold_kind"].choices,
}

#: value of every ``fault<k>_*`` record of a fault a run does not have (the store holds no
#: NaN); kind codes index PARAM_CODES["fault_kind"], direction codes
#: PARAM_CODES["dip_direction"] (declared in demseis.parameters.STORED).
ABSENT = -1.0


#: per-pixel fault attributes of the slip-trace labels, stored next to DEFAULT_ARRAYS
LABEL_ARRAYS: tuple[str, ...] = ("fault_id", "slip_m", "dip_deg", "sense")


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
    names = DEFAULT_ARRAYS + LABEL_ARRAYS + (("impedance",) if cfg.output.impedance else ())
    out = {name: str(SAMPLE_ARRAYS[name]) for name in names}
    return out


def param_dtypes() -> dict[str, str]:
    """Name → dtype of the per-sample parameter arrays (``params/`` in the store)."""
    out = {s.name: s.dtype for s in STORED}
    for key, pdef in SCENARIO.items():
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


def fault_system_of(cfg: Config, params: dict[str, Any], run: int) -> Any:
    """The basement of a run: a NormalFault for ``structure="single"`` + ``fault_kind="normal"``
    (today's model, placed by ``fault_x_frac``), else a :class:`demseis.dem.FaultSystem`."""
    from demseis.dem.basement import BasementFault, FaultSystem, draw_fault_system

    W = cfg.model.width_m
    structure, kind = str(params["structure"]), str(params["fault_kind"])
    if structure == "single" and kind == "normal":
        return NormalFault(x_m=float(params["fault_x_frac"]) * W, dip_deg=float(params["dip_deg"]),
                           throw_m=float(params["throw_m"]),
                           dip_direction=str(params["dip_direction"]),
                           speed_m_s=cfg.model.wall_speed_m_s)
    if structure == "single":
        f = BasementFault(float(params["fault_x_frac"]) * W, float(params["dip_deg"]),
                          float(params["throw_m"]), str(params["dip_direction"]), kind,
                          float(params["listric_radius_m"]))
        if kind == "listric":
            f = dataclasses.replace(f, throw_m=min(f.throw_m, f.max_listric_throw_m))
        system = FaultSystem((f,), structure="single")
    else:
        if kind == "listric" and structure != "half_graben":
            kind = "normal"  # a listric fault must bound an end block: only half-grabens
        system = draw_fault_system(rng_at(cfg, run, SEED_FAULTS), W, structure=structure,
                                   n_faults=int(params["n_faults"]), kind=kind,
                                   dip_deg=float(params["dip_deg"]),
                                   throw_m=float(params["throw_m"]),
                                   spacing_frac=float(params["fault_spacing_frac"]),
                                   listric_radius_m=float(params["listric_radius_m"]),
                                   dip_direction=str(params["dip_direction"]))
    return dataclasses.replace(system, speed_m_s=cfg.model.wall_speed_m_s)


def run_info(cfg: Config, params: dict[str, Any], run: int) -> dict[str, Any]:
    """Derived per-run values stored with every sample: the master fault's x at the base and
    target throw, and every basement fault (kind, x, dip, target throw, direction).

    ``fault_x_frac`` places a single basement fault where it meets the base of the model. The
    fault that grows through the cover is usually steeper than the basement fault (it is not
    imposed), so its trace at the surface lies on the footwall side of that point.
    """
    from demseis.dem.fault import as_system

    system = as_system(fault_system_of(cfg, params, run))
    m = system.faults[system.master]
    info: dict[str, Any] = {"fault_x_m": m.x_m, "throw_target_m": m.throw_m,
                            "n_basement_faults": len(system.faults)}
    for k in range(5):
        f = system.faults[k] if k < len(system.faults) else None
        info[f"fault{k}_kind"] = PARAM_CODES["fault_kind"].index(f.kind) if f else -1
        info[f"fault{k}_dip_direction"] = (PARAM_CODES["dip_direction"].index(f.dip_direction)
                                           if f else -1)
        info[f"fault{k}_x_m"] = f.x_m if f else ABSENT
        info[f"fault{k}_dip_deg"] = f.dip_deg if f else ABSENT
        info[f"fault{k}_throw_target_m"] = f.throw_m if f else ABSENT
        info[f"fault{k}_throw_m"] = ABSENT
    info["_system"] = system
    return info


def fault_throws_of(info: dict[str, Any], snapshot: int, n_snapshots: int) -> dict[str, float]:
    """``fault<k>_throw_m`` (throw so far) of every fault at snapshot ``snapshot``."""
    system = info["_system"]
    throws = system.throws_at(snapshot / (n_snapshots - 1))
    return {f"fault{k}_throw_m": float(t) for k, t in enumerate(throws)}  # absent ones stay -1


def material_of(params: dict[str, Any]) -> Material:
    """The DEM material of a run."""
    return Material(**{field: params[key] for field, key in MATERIAL_FIELDS.items()})


def property_model_of(cfg: Config, params: dict[str, Any]) -> Any:
    """The rock-property model of a run (scalar fields from the run's parameters)."""
    from demseis.seismic import PropertyModel

    scalar = {name: params[name] for name in PROPERTY_FIELDS}
    return PropertyModel(**cfg.properties, **scalar)


def simulate_run(
    cfg: Config, spec: RunSpec, progress: Callable[[float], None] | None = None
) -> tuple[list[Snapshot], dict[str, Any]]:
    """Build the assembly of run ``spec.run`` and fault it; returns (snapshots, run info)."""
    from demseis.dem import build_assembly, simulate

    p = spec.params
    material = material_of(p)
    thick = layer_thicknesses(cfg, int(p["n_layers"]), float(p["layer_thickness_cv"]),
                              rng_at(cfg, spec.run, SEED_LAYERS))
    info = run_info(cfg, p, spec.run)
    fault = fault_system_of(cfg, p, spec.run)
    rng = rng_at(cfg, spec.run, SEED_DEM)
    asm = build_assembly(
        cfg.model.width_m, cfg.model.height_m,
        radius_min_m=cfg.model.radius_min_m, radius_max_m=cfg.model.radius_max_m,
        n_layers=int(p["n_layers"]), layer_thickness_m=thick, material=material, rng=rng,
    )
    layers = None
    if float(p["strength_contrast"]) > 1.0:
        from demseis.dem.strata import layer_materials
        from demseis.seismic import draw_layer_properties

        model = property_model_of(cfg, p)
        # the same draw as render_run's (the first layers do not depend on the total)
        lith = draw_layer_properties(int(p["n_layers"]), model, rng_at(cfg, spec.run, SEED_PROPERTIES)).lithology
        layers = layer_materials([model.lithologies[k] for k in lith], material,
                                 float(p["strength_contrast"]))
    # uplift (reverse and listric faults) is eroded at the top of the sample grid
    uplift = not isinstance(fault, NormalFault) and any(
        f.kind != "normal" for f in fault.faults)
    snaps = simulate(asm, fault, material, n_snapshots=cfg.model.n_snapshots,
                     sedimentation=cfg.model.sedimentation, rng=rng, progress=progress,
                     erosion_level_m=cfg.model.height_m if uplift else None,
                     layer_materials=layers)
    return snaps, info


def run_properties(cfg: Config, run: int, model: Any, n_layers_total: int) -> tuple[Any, int]:
    """The per-layer rock properties of run ``run`` and its per-element scatter seed.

    Both come from the run's ``SEED_PROPERTIES`` node, so every snapshot (and a re-render or a
    preview) gets the same rock.
    """
    from demseis.seismic import draw_layer_properties

    layer_props = draw_layer_properties(n_layers_total, model, rng_at(cfg, run, SEED_PROPERTIES))
    elem_seed = int(seed_sequence(cfg, run, SEED_PROPERTIES).generate_state(2, dtype=np.uint64)[1])
    return layer_props, elem_seed


@dataclass(frozen=True)
class ShardData:
    """All samples of one run: (S, H, W) arrays, (S,) parameters and the particle snapshots."""

    arrays: dict[str, np.ndarray]
    params: dict[str, np.ndarray]
    snapshots: list[Snapshot]


def render_run(cfg: Config, spec: RunSpec, snapshots: list[Snapshot], info: dict[str, Any]) -> ShardData:
    """Sections and labels of every render of ``spec`` from its snapshots."""
    from demseis.labels import label_maps, strain_history
    from demseis.labels.traces import displacement_history
    from demseis.seismic import element_properties, property_grids

    grid = grid_of(cfg)
    p = spec.params
    model = property_model_of(cfg, p)
    n_layers_total = max(int(s.layer.max()) for s in snapshots) + 1
    layer_props, elem_seed = run_properties(cfg, spec.run, model, n_layers_total)
    history = strain_history(snapshots, cfg.labels)
    disp = displacement_history(snapshots) if cfg.labels.method == "slip_trace" \
        else [None] * len(snapshots)

    arrays, params = empty_shard(cfg, spec)
    for k, renders in renders_by_snapshot(spec):
        snap = snapshots[k]
        vp_e, rho_e = element_properties(snap.ids, snap.layer, layer_props, model, elem_seed)
        vp_g, rho_g = property_grids(snap.xy, snap.radius, vp_e, rho_e, snap.layer, grid, model)
        maps = dict(label_maps(snap, history[k], grid, cfg.labels, displacement=disp[k]))
        row = {"snapshot": k, "step": snap.step, "throw_m": snap.throw_m, "n_elements": snap.n,
               **fault_throws_of(info, k, len(snapshots))}
        render_samples(cfg, spec, renders, vp_g, rho_g, maps, {**info, **row}, arrays, params)
    return ShardData(arrays=arrays, params=params, snapshots=snapshots)


def empty_shard(cfg: Config, spec: RunSpec) -> tuple[dict[str, np.ndarray], dict[str, np.ndarray]]:
    """Zeroed (S, H, W) sample arrays and (S,) parameter arrays of run ``spec``."""
    S = len(spec.renders)
    arrays = {k: np.zeros((S, *sample_shape(cfg)), dtype=v) for k, v in array_dtypes(cfg).items()}
    params = {k: np.zeros(S, dtype=v) for k, v in param_dtypes().items()}
    return arrays, params


def renders_by_snapshot(spec: RunSpec) -> list[tuple[int, list[Render]]]:
    """The renders of ``spec`` grouped by snapshot, in snapshot order."""
    by_snap: dict[int, list[Render]] = {}
    for r in spec.renders:
        by_snap.setdefault(r.snapshot, []).append(r)
    return sorted(by_snap.items())


def render_samples(cfg: Config, spec: RunSpec, renders: list[Render], vp_g: np.ndarray,
                   rho_g: np.ndarray, maps: dict[str, np.ndarray], row: dict[str, Any],
                   arrays: dict[str, np.ndarray], params: dict[str, np.ndarray]) -> None:
    """Image, add noise and store the samples ``renders`` of one geological state.

    Shared by the DEM and the kinematic engine: ``vp_g``, ``rho_g`` are the depth-domain
    property grids, ``maps`` the label maps (``fault``, ``damage``, ``strain``, ``layer``,
    ``fault_id``, ``slip_m``, ``dip_deg``, ``sense``), ``row`` the per-sample values of this
    state (keys starting with ``_`` are ignored). Fills ``arrays[...][r.sample]`` and
    ``params[...][r.sample]`` in place.
    """
    from demseis.labels.maps import sample_facts
    from demseis.seismic import add_noise, depth_to_time, imaged_sections

    grid = grid_of(cfg)
    t_s = time_axis_of(cfg)
    maps = dict(maps)
    facts = sample_facts(maps)
    impedance = vp_g * rho_g
    domain = "depth" if t_s is None else "time"
    # one imaging call per (imaging, angle, aperture), all its frequencies at once
    wanted: dict[tuple[str, float, float], set[float]] = {}
    for r in renders:
        wanted.setdefault(_imaging_key(r), set()).add(r.freq_hz)
    images = {}
    for key, fset in wanted.items():
        freqs = sorted(fset)
        secs = imaged_sections(key[0], vp_g, rho_g, grid.cell_m, freqs, domain, t_s=t_s,
                               max_angle_deg=key[1], aperture_m=key[2])
        images.update({(key, f): sec for f, sec in zip(freqs, secs)})
    if t_s is not None:
        fills = {"fault": 0, "damage": 0, "strain": 0.0, "layer": -1, "fault_id": 0,
                 "slip_m": 0.0, "dip_deg": 0.0, "sense": 0}
        for name, fill in fills.items():
            maps[name] = depth_to_time(maps[name], vp_g, grid.cell_m, t_s, method="nearest", fill=fill)
        impedance = depth_to_time(impedance, vp_g, grid.cell_m, t_s, method="nearest", fill=0.0)
    for r in renders:
        clean = images[(_imaging_key(r), r.freq_hz)]
        noisy = add_noise(clean, r.snr_db, r.noise_kind, np.random.default_rng(r.seed))
        i = r.sample
        arrays["seismic"][i] = noisy
        for name in ("fault", "damage", "strain", "layer", "fault_id", "slip_m", "dip_deg",
                     "sense"):
            arrays[name][i] = maps[name]
        if "impedance" in arrays:
            arrays["impedance"][i] = impedance
        values = {
            "run_id": spec.run, "sample_in_run": i, "freq_hz": r.freq_hz,
            "snr_db": r.snr_db, "noise_seed": r.seed, "noise_kind": r.noise_kind,
            "imaging": r.imaging, "psf_max_angle_deg": r.psf_max_angle_deg,
            "psf_aperture_m": r.psf_aperture_m,
            **{k: v for k, v in row.items() if not k.startswith("_")},
            **facts,
        }
        for key, value in {**spec.params, **values}.items():
            if key in PARAM_CODES:
                value = PARAM_CODES[key].index(value)
            params[key][i] = value


def _imaging_key(r: Render) -> tuple[str, float, float]:
    """Renders sharing this key share one imaging call (the angle matters only for the PSF)."""
    if r.imaging == "1d":
        return ("1d", 90.0, math.inf)
    return (r.imaging, r.psf_max_angle_deg, r.psf_aperture_m if r.psf_aperture_m > 0 else math.inf)


def require_particles(cfg: Config, what: str) -> None:
    """Refuse ``what`` (a command that needs DEM particles) for a kinematic-engine config.

    Raises
    ------
    InputError
        ``cfg.model.engine`` is ``"kinematic"``: such runs have no particles.
    """
    if cfg.model.engine == "kinematic":
        from demseis.errors import InputError

        raise InputError(f"{what} needs DEM particle snapshots, and this is a kinematic-engine "
                         "config/store ([model] engine = \"kinematic\"), which has none: "
                         "run `demseis generate` with the settings you want instead")


def run_shard(cfg: Config, run: int, progress: Callable[[float], None] | None = None, *,
              timings: dict[str, float] | None = None) -> ShardData:
    """Run ``run`` and all its renders (the DEM, or the kinematic engine); ``timings`` (if given)
    gets dem_s (the engine) and render_s."""
    import time

    t0 = time.perf_counter()
    spec = plan_run(cfg, run)
    if cfg.model.engine == "kinematic":
        from demseis.generator.kinematic import kinematic_run

        data = kinematic_run(cfg, spec)
        if timings is not None:
            timings.update(dem_s=time.perf_counter() - t0, render_s=0.0)
        return data
    snaps, info = simulate_run(cfg, spec, progress)
    t1 = time.perf_counter()
    data = render_run(cfg, spec, snaps, info)
    if timings is not None:
        timings.update(dem_s=t1 - t0, render_s=time.perf_counter() - t1)
    return data
