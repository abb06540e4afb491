"""The kinematic engine (``[model] engine = "kinematic"``): FaultSeg-style sections, no DEM.

A run is a stack of random layers (thicknesses Gamma-distributed with ``layer_thickness_cv``,
rock from the run's :class:`~demseis.seismic.PropertyModel`), optionally folded
(``fold_amplitude_m``, ``fold_kind``), cut by the faults of the run's basement system (the same
``structure``, ``n_faults``, ``fault_kind``, ``dip_deg``, ``throw_m``, ``dip_direction``,
``listric_radius_m`` draws as the DEM engine's, :func:`demseis.generator.engines.runsetup.run_info`).

Faulting is geometry. Fault ``k`` meets the base of the model at ``x_m`` and rises towards the
footwall: planar at ``dip_deg``, or listric (a circular arc of radius ``listric_radius_m``,
``dip_deg`` at the top, flattening with depth: cos(dip(d)) = cos(dip_deg) + d / R). Its
hanging wall is moved along the fault by the local throw, which dies out along the fault
(``throw_taper``: throw(d) = throw (1 - taper ((d - c) / L)^2), clipped at 0, centre ``c``
drawn in the middle of the section, half-length ``L = 0.6 height``). Faults are applied oldest
first; a sample is computed backwards, youngest fault first, by mapping every present cell to
where its rock came from, so older faults are offset by younger ones.

With ``base_stretch`` != 0 a fault population (:func:`population`) that takes up the same
extension or shortening is added, older than the basement faults: the kinematic counterpart of
the DEM's stretching base.

Snapshot ``k`` of ``n_snapshots`` holds the fraction ``k / (n - 1)`` of every throw, so a run
has the same samples as a DEM run. Each snapshot is a
:class:`~demseis.generator.engines.State` whose properties and labels go through the imaging,
noise and storage every engine shares (:mod:`demseis.generator.render.section`):

- ``fault`` cells lie within ``max(thickness_cells, 1) / 2`` cells (perpendicular) of a fault
  where its throw is > 0; ``damage`` is 2 there and 1 within three times that distance;
- ``fault_id`` is the fault's number (1..), ``slip_m`` its local dip-slip (throw / sin dip),
  ``dip_deg`` its local dip, ``sense`` 1 (normal, listric) or 2 (reverse);
- ``layer`` is the layer index the rock came from (0 = deepest of the stack, which extends
  above and below the section so that every cell holds rock); ``strain`` is 0 (no strain field
  without particles).

For the ``strata`` rendering each state's reference map is :func:`unfault` (exact: where
each point's rock was before the faults and folds moved it) and the beds are drawn in the
run's layer stack (:func:`kinematic_strata`).

There are no particles: the store's ``particles/`` group stays empty.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass
from functools import partial

import numpy as np
from scipy.ndimage import gaussian_filter

from demseis.generator.config.layout import grid_of
from demseis.generator.config.sampling import (SEED_DEM, SEED_LAYERS, SEED_POPULATION,
                                               SEED_PROPERTIES, RunParams, RunSpec, rng_at)
from demseis.generator.config.settings import Config
from demseis.generator.engines import EngineRun, State
from demseis.generator.engines.runsetup import RunInfo, property_model_of, run_info, run_strata
from demseis.registry import RENDERINGS
from demseis.schema import engine_labels, sample_array
from demseis.seismic import LayerProperties, Strata, draw_layer_properties

#: the layer stack covers depths [-ABOVE, 1 + BELOW] x height (uplift, subsidence and folds)
ABOVE, BELOW = 1.0, 1.0
#: half-length of a fault as a fraction of the model height (the throw taper's L)
HALF_LENGTH_FRAC = 0.6
#: standard deviation of the dips of a population's faults around the run's dip_deg
POPULATION_DIP_SD_DEG = 8.0
#: share of a population's faults that dip towards the run's dip_direction
SYNTHETIC_FRACTION = 0.7
#: largest throw of a population over its smallest (the power law's cap)
MAX_THROW_RATIO = 50.0
#: range of a population fault's displacement / length ratio (log-uniform)
DL_RATIO = (0.02, 0.1)
#: a population fault's half-length, as fractions of the model height, at least and at most
HALF_LENGTH_RANGE = (0.15, 1.5)


def fault_geometry(depth_m: np.ndarray, x_base_m: float, dip_deg: float, height_m: float,
                   direction: int, listric_radius_m: float | None) -> tuple[np.ndarray, np.ndarray]:
    """x of a fault (m) and its dip (deg) at each depth of the increasing axis ``depth_m``.

    The fault meets depth ``height_m`` at ``x_base_m``; ``direction`` +1 dips right (the
    trace moves to larger x with depth), -1 left. ``listric_radius_m`` None: planar.
    """
    d = np.asarray(depth_m, dtype=np.float64)
    if listric_radius_m is None:
        dip = np.full(d.shape, float(dip_deg))
    else:
        cos = np.cos(np.radians(dip_deg)) + np.clip(d, 0.0, None) / listric_radius_m
        dip = np.degrees(np.arccos(np.clip(cos, 0.0, np.cos(np.radians(10.0)))))
    cot = 1.0 / np.tan(np.radians(dip))
    # x(d) = x_base - direction * integral_d^H cot(dip) (trapezoid on the axis, then to H)
    cum = np.concatenate([[0.0], np.cumsum(0.5 * (cot[1:] + cot[:-1]) * np.diff(d))])
    at_h = np.interp(height_m, d, cum)
    return x_base_m - direction * (at_h - cum), dip


def fold_field(x_m: np.ndarray, width_m: float, amplitude_m: float, kind: str,
               rng: np.random.Generator) -> np.ndarray:
    """Vertical displacement (m, down positive) of the layers at ``x_m`` by folding."""
    x = np.asarray(x_m, dtype=np.float64)
    n_bumps = int(rng.integers(1, 5))
    centres = rng.uniform(0.0, width_m, n_bumps)
    widths = rng.uniform(0.1, 0.3, n_bumps) * width_m
    signs = rng.uniform(-1.0, 1.0, n_bumps)
    wavelength = rng.uniform(0.5, 2.0) * width_m
    phase = rng.uniform(0.0, 2 * np.pi)
    if amplitude_m <= 0:
        return np.zeros_like(x)
    if kind == "sinusoidal":
        return amplitude_m * np.sin(2 * np.pi * x / wavelength + phase)
    return amplitude_m * sum(s * np.exp(-0.5 * ((x - c) / w) ** 2)
                             for s, c, w in zip(signs, centres, widths))


def layer_tops(n_layers: int, cv: float, height_m: float, rng: np.random.Generator) -> np.ndarray:
    """Increasing depths (m) of the layer boundaries of a stack covering
    ``[-ABOVE, 1 + BELOW] * height_m``, ``n_layers`` per model height on average, thicknesses
    Gamma with coefficient of variation ``cv`` (equal for cv = 0)."""
    n_total = int(np.ceil(n_layers * (1.0 + ABOVE + BELOW)))
    w = rng.gamma(1.0 / cv**2, 1.0, size=n_total) if cv > 0 else np.ones(n_total)
    h = (1.0 + ABOVE + BELOW) * height_m * w / w.sum()
    return -ABOVE * height_m + np.concatenate([[0.0], np.cumsum(h)])


@dataclass(frozen=True)
class KinematicFault:
    """One fault of the kinematic engine.

    Attributes
    ----------
    x_m : x where the fault meets the base of the model (depth ``height_m``).
    dip_deg : dip (at the top, for a listric fault).
    throw_m : final throw at the fault's centre.
    direction : +1 dips right (hanging wall at larger x), -1 left.
    kind : ``"normal"``, ``"reverse"`` or ``"listric"``.
    radius_m : radius of a listric fault; None: planar.
    centre_m : depth of the fault's centre (largest throw).
    half_length_m : distance from the centre (along depth) over which the throw tapers.
    taper : throw(d) = throw_m (1 - taper ((d - centre) / half_length)^2), clipped at 0.
    """

    x_m: float
    dip_deg: float
    throw_m: float
    direction: int
    kind: str
    radius_m: float | None
    centre_m: float
    half_length_m: float
    taper: float


def population(cfg: Config, params: RunParams, run: int) -> list[KinematicFault]:
    """The fault population that takes up ``base_stretch`` of the width, oldest first
    (empty when ``base_stretch`` is 0).

    ``population_faults`` faults, normal for extension and reverse for shortening. Each is
    centred at a uniform x (at mid-depth) and depth (0.2-0.8 of the height), dips
    ``N(dip_deg, POPULATION_DIP_SD_DEG)`` (15-80 degrees), towards ``dip_direction`` with
    probability ``SYNTHETIC_FRACTION`` (else antithetic). Throws follow a power law
    (cumulative number N(> t) ~ t^-c, c = ``population_throw_exponent``; the largest at most
    ``MAX_THROW_RATIO`` times the smallest), scaled so that the heaves (throw / tan dip) add up
    to ``|base_stretch| * width``. Each dies out (taper 1: zero at its tips) over a half-length
    from its throw and a ratio of largest displacement to length drawn log-uniform in
    ``DL_RATIO`` (displacement grows about linearly with length: Clark & Cox 1996), kept within
    ``HALF_LENGTH_RANGE`` of the height, so small faults are short and large ones cross the
    section. Ages are in a random order.
    """
    e = params.base_stretch
    if e == 0.0:
        return []
    W, H = cfg.model.width_m, cfg.model.height_m
    rng = rng_at(cfg, run, SEED_POPULATION)
    n = params.population_faults
    dips = np.clip(rng.normal(params.dip_deg, POPULATION_DIP_SD_DEG, n), 15.0, 80.0)
    main = 1 if params.dip_direction == "right" else -1
    dirs = np.where(rng.random(n) < SYNTHETIC_FRACTION, main, -main)
    x_mid = rng.uniform(0.0, W, n)
    c = params.population_throw_exponent
    size = np.minimum((1.0 - rng.random(n)) ** (-1.0 / c), MAX_THROW_RATIO)
    cot = 1.0 / np.tan(np.radians(dips))
    throws = size * abs(e) * W / float(np.sum(size * cot))
    centres = rng.uniform(0.2, 0.8, n) * H
    ratio = np.exp(rng.uniform(np.log(DL_RATIO[0]), np.log(DL_RATIO[1]), n))
    halves = np.clip(0.5 * throws / ratio, HALF_LENGTH_RANGE[0] * H, HALF_LENGTH_RANGE[1] * H)
    order = rng.permutation(n)
    kind = "normal" if e > 0 else "reverse"
    return [KinematicFault(x_m=float(x_mid[i] + dirs[i] * 0.5 * H * cot[i]),
                           dip_deg=float(dips[i]), throw_m=float(throws[i]),
                           direction=int(dirs[i]), kind=kind, radius_m=None,
                           centre_m=float(centres[i]), half_length_m=float(halves[i]), taper=1.0)
            for i in order]


def kinematic_faults(cfg: Config, params: RunParams, run: int, info: RunInfo,
                     rng: np.random.Generator) -> list[KinematicFault]:
    """Every fault of run ``run``, oldest first: the population (:func:`population`), then the
    basement faults of ``info`` (their centres drawn from ``rng``, the run's SEED_DEM
    stream, whatever the snapshot)."""
    H = cfg.model.height_m
    faults = info.system.faults
    centres = rng.uniform(0.35, 0.65, len(faults)) * H
    taper = params.throw_taper
    basement = [KinematicFault(x_m=f.x_m, dip_deg=f.dip_deg, throw_m=f.throw_m,
                               direction=1 if f.dip_direction == "right" else -1, kind=f.kind,
                               radius_m=f.radius_m if f.kind == "listric" else None,
                               centre_m=float(centres[k]), half_length_m=HALF_LENGTH_FRAC * H,
                               taper=taper)
                for k, f in enumerate(faults)]
    return population(cfg, params, run) + basement


def unfault(cfg: Config, params: RunParams, run: int, info: RunInfo, fraction: float,
            x_m: np.ndarray, depth_m: np.ndarray,
            maps: dict[str, np.ndarray] | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Where the rock at points ``(x_m, depth_m)`` (depth below the grid top) was before it was
    faulted and folded, with ``fraction`` of every throw.

    Returns ``(x0_m, depth0_m)``: the x and the unfolded depth in the layer stack (the depth
    of the point's layering before folding). With ``maps`` (the label maps of the grid, with
    ``x_m, depth_m`` the grid's cell centres), each fault's labels are drawn into them on the way.
    """
    grid = grid_of(cfg)
    H, W = cfg.model.height_m, cfg.model.width_m
    X, D = np.asarray(x_m, dtype=np.float64), np.asarray(depth_m, dtype=np.float64)
    half_m = 0.5 * max(float(cfg.labels.thickness_cells), 1.0) * grid.cell_m
    rng = rng_at(cfg, run, SEED_DEM)
    faults = kinematic_faults(cfg, params, run, info, rng)
    fold_x = np.linspace(-W, 2 * W, 3 * grid.nx + 1)
    fold = fold_field(fold_x, W, params.fold_amplitude_m, params.fold_kind, rng)
    axis = np.linspace(-(ABOVE + 1.0) * H, (2.0 + BELOW) * H, 8 * grid.nz + 1)
    # youngest fault first: map present cells back to where their rock was before it slipped
    for k in range(len(faults) - 1, -1, -1):
        f = faults[k]
        s = f.direction
        xf, dipf = fault_geometry(axis, f.x_m, f.dip_deg, H, s, f.radius_m)
        x_here = np.interp(D, axis, xf)
        dip_here = np.interp(D, axis, dipf)
        u = (D - f.centre_m) / f.half_length_m
        throw = fraction * f.throw_m * np.clip(1.0 - f.taper * u**2, 0.0, None)
        hanging = (X - x_here) * s > 0
        if maps is not None:
            draw_fault_labels(maps, k, f.kind, np.abs(X - x_here) * np.sin(np.radians(dip_here)),
                        throw, dip_here, half_m)
        # hanging wall: normal/listric moved down-dip, reverse up-dip; undo it
        sign = -1.0 if f.kind == "reverse" else 1.0
        heave = throw / np.tan(np.radians(dip_here))
        D = np.where(hanging, D - sign * throw, D)
        X = np.where(hanging, X - sign * s * heave, X)
    return X, D - np.interp(X, fold_x, fold)


def draw_fault_labels(maps: dict[str, np.ndarray], k: int, kind: str, perp: np.ndarray,
                throw: np.ndarray, dip: np.ndarray, half_m: float) -> None:
    """Labels of fault ``k`` (perpendicular distance ``perp`` of every cell, its local throw
    and dip), in present coordinates, on the cells not yet claimed by a younger fault."""
    fault, damage, fid = maps["fault"], maps["damage"], maps["fault_id"]
    active = throw > 0
    on = active & (perp <= half_m) & (fid == 0)
    fault[on] = 1
    damage[active & (perp <= 3 * half_m) & (damage == 0)] = 1
    damage[on] = 2
    fid[on] = k + 1
    maps["slip_m"][on] = (throw / np.sin(np.radians(dip)))[on]
    maps["dip_deg"][on] = dip[on]
    maps["sense"][on] = 2 if kind == "reverse" else 1


def kinematic_state(cfg: Config, params: RunParams, run: int, info: RunInfo,
                    fraction: float) -> tuple[np.ndarray, dict[str, np.ndarray]]:
    """Layer index and label maps of run ``run`` with ``fraction`` of every throw.

    Returns
    -------
    layer : (nz, nx) int64 index into the run's layer stack (0 = deepest).
    maps : the label maps of :mod:`demseis.labels` (``layer`` included).
    """
    grid = grid_of(cfg)
    H = cfg.model.height_m
    cell = grid.cell_m
    zc = (np.arange(grid.nz) + 0.5) * cell  # depth of the cell centres (row 0 at the top)
    xc = (np.arange(grid.nx) + 0.5) * cell
    X, D = np.meshgrid(xc, zc)
    maps = {name: np.zeros(X.shape, sample_array(name).dtype) for name in engine_labels()}
    _, depth0 = unfault(cfg, params, run, info, fraction, X, D, maps)
    tops = layer_tops(params.n_layers, params.layer_thickness_cv, H,
                      rng_at(cfg, run, SEED_LAYERS))
    n_total = tops.size - 1
    # layer 0 is the deepest: count from the bottom of the stack
    from_top = np.clip(np.searchsorted(tops, depth0, side="right") - 1, 0, n_total - 1)
    layer = (n_total - 1 - from_top).astype(np.int64)
    maps["layer"] = layer.astype(maps["layer"].dtype)  # strain stays 0: no strain field
    return layer, maps


def kinematic_strata(cfg: Config, params: RunParams, run: int,
                     props: LayerProperties) -> Strata:
    """The beds of run ``run``: its layer stack (``layer_tops``) as the units, in y."""
    H = cfg.model.height_m
    tops = layer_tops(params.n_layers, params.layer_thickness_cv, H,
                      rng_at(cfg, run, SEED_LAYERS))
    y = H - tops[::-1]                                # unit boundaries in y, bottom first
    return run_strata(cfg, params, run, y[:-1], y[1:], props)


class KinematicEngine:
    """The kinematic engine as an :class:`~demseis.generator.engines.Engine` (no particles)."""

    particles = False
    strata = True

    def check(self, cfg: Config) -> None:
        """Nothing beyond each parameter's range: the geometry has no stability limits."""

    def cost(self, cfg: Config, params: RunParams) -> float:
        """Every run costs the same (one state per snapshot, one grid pass per fault)."""
        return 1.0

    def describe(self, cfg: Config) -> tuple[str, float]:
        """A line for ``--dry-run`` and the seconds of one run on one core (about 0.25 s at
        the ``quick`` size, ``benchmarks/kinematic_speed.py``; scaled by the cells)."""
        grid = grid_of(cfg)
        return (f"geometric, {cfg.model.n_snapshots} states each",
                0.25 * grid.nz * grid.nx / (110 * 250))

    def simulate(self, cfg: Config, spec: RunSpec,
                 progress: Callable[[float], None] | None = None) -> EngineRun:
        """The run's basement faults; the states are computed from them by :meth:`states`."""
        return EngineRun(spec=spec, info=run_info(cfg, spec.params, spec.run))

    def states(self, cfg: Config, run: EngineRun, snapshots: Sequence[int]) -> Iterator[State]:
        """Layer properties and labels of snapshot k, with the fraction k / (n - 1) of every
        throw."""
        p = run.spec.params
        model = property_model_of(cfg, p)
        n_snap = cfg.model.n_snapshots
        props = strata = None
        for k in snapshots:
            fraction = k / (n_snap - 1)
            layer, maps = kinematic_state(cfg, p, run.spec.run, run.info, fraction)
            if props is None:
                n_total = int(np.ceil(p.n_layers * (1.0 + ABOVE + BELOW)))
                props = draw_layer_properties(n_total, model,
                                              rng_at(cfg, run.spec.run, SEED_PROPERTIES))
            vp_g, rho_g = props.vp[layer], props.rho[layer]
            sigma = p.gaussian_sigma_cells
            if sigma > 0:
                vp_g, rho_g = gaussian_filter(vp_g, sigma), gaussian_filter(rho_g, sigma)
            values = {"step": k, "throw_m": fraction * run.info.values["throw_target_m"], "n_elements": 0,
                      **run.info.throws_at(k, n_snap)}
            reference = None
            if RENDERINGS.get(cfg.output.rendering).reference:
                if strata is None:
                    strata = kinematic_strata(cfg, p, run.spec.run, props)
                reference = partial(_reference, cfg, p, run.spec.run, run.info, fraction)
            yield State(snapshot=k, vp_m_s=vp_g, rho_kg_m3=rho_g, labels=maps, values=values,
                        reference=reference, strata=strata)


def _reference(cfg: Config, params: RunParams, run: int, info: RunInfo, fraction: float,
               x_m: np.ndarray, depth_m: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """:attr:`State.reference` of the kinematic engine: :func:`unfault`, every point in the
    pre-kinematic stack."""
    x0, depth0 = unfault(cfg, params, run, info, fraction, x_m, depth_m)
    return x0, cfg.model.height_m - depth0, np.full(np.shape(x0), -1, dtype=np.int64)


ENGINE = KinematicEngine()
