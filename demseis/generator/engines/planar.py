"""The planar engine (``[model] engine = "planar"``): the published FaultSeg recipe, as a control.

Wu, X., Liang, L., Shi, Y., Fomel, S., 2019, FaultSeg3D: Using synthetic data sets to train an
end-to-end convolutional neural network for 3D seismic fault segmentation, Geophysics 84(3),
IM35-IM45, in 2D as its public re-implementations make it. A run is:

1. **Random reflectivity.** A flat 1D reflectivity series: one reflection coefficient per bed
   boundary, ``r_j = REFLECTIVITY_MAX u_j`` with ``u_j`` uniform in [-1, 1], independent. The
   beds are the strata rendering's (thicknesses lognormal, ``bed_thickness_median_m``,
   ``bed_thickness_log_sigma``, clipped to [``bed_thickness_min_m``,
   ``bed_thickness_max_m``]; ``bed_thickness_log_sigma = 0``: one reflection every
   ``bed_thickness_median_m``, as FaultSeg's one per sample).
   The series is carried by a :class:`~demseis.seismic.Strata` of those beds: Vp is constant
   (the run's rock, one draw of its :class:`~demseis.seismic.PropertyModel`; so the two-way
   time is a linear stretch of depth) and the density of bed j is
   ``rho_0 exp(s_j)``, ``s_{j+1} - s_j = 2 atanh(r_j)``, so that the imaging's
   ``(Z2 - Z1) / (Z2 + Z1) = tanh((s_{j+1} - s_j) / 2)`` is ``r_j``. A sum of independent
   coefficients wanders like a random walk; its smooth part (a Gaussian of ``DETREND_M``
   over the beds) is taken out of ``s`` so that the density stays within a few tens of
   percent of ``rho_0``. That changes each coefficient by a few percent of its spread, at
   wavelengths of hundreds of metres, far below the seismic band.
2. **Folding.** A vertical shift growing with depth, as FaultSeg's
   ``s1(x, z) = a0 + 1.5 z / zmax * sum_k b_k exp(-(x - c_k)^2 / (2 d_k^2))``:
   2-4 Gaussian bumps (``FOLD_BUMPS``), ``b_k`` uniform in +-``fold_amplitude_m``, ``c_k``
   uniform over the width, ``d_k`` uniform in ``FOLD_WIDTH`` of the width; ``a0 = 0`` (a
   constant shift of a stationary series changes nothing); ``zmax`` the model height, z
   below the top (clipped at 0). The folded section at (x, z) is the flat one at
   ``z - s1(x, z)``.
3. **Planar shear.** ``s2(x) = e0 + f x`` with ``f = tan(a)``, ``a`` uniform in
   +-``planar_tilt_deg``, pivoting at an x drawn over the width (``e0 = -f x_pivot``). The
   sheared section at (x, z) is the folded one at ``z - s2(x)``.
4. **Faults.** ``planar_faults`` planar faults, oldest first, each crossing the whole
   section: its trace at mid-depth at x uniform in ``FAULT_X`` of the width, its dip uniform
   in [``planar_dip_min_deg``, ``planar_dip_max_deg``], dipping left or right with equal
   probability, reverse with probability ``planar_reverse_fraction`` (else normal), its throw
   uniform in [``planar_throw_min_m``, ``planar_throw_max_m``] and constant along the fault.
   The hanging wall moves along the fault by the throw (down for normal faults, up for
   reverse), so younger faults offset older ones.

The run-level parameters ``dip_deg``, ``throw_m``, ``n_faults``, ``structure`` (the DEM's
basement) are not used; the parameters ``fault<k>_*`` hold the first five faults by x (where they
meet the base of the model), ``n_basement_faults`` the number of faults and
``fault_x_m``, ``throw_target_m`` and ``dip_deg`` the fault of largest throw's.

Snapshot ``k`` of ``n_snapshots`` holds the fraction ``k / (n - 1)`` of every throw (snapshot 0
folded and sheared, unfaulted), as in the kinematic engine. A sample is computed backwards,
youngest fault first, by mapping every present point to where its rock was
(:meth:`PlanarModel.unfault`); that map is the state's ``reference`` for the ``strata``
rendering (every point in the one unit of the series). The labels are the kinematic engine's
(:func:`~demseis.generator.engines.kinematic.draw_fault_labels`): ``fault`` cells within
``max(thickness_cells, 1) / 2`` cells of a fault (then picked as one-pixel lines on the output
grid by :mod:`demseis.labels.picks` with ``fault_style = "picks"``), ``fault_id`` the fault's
age (1 the oldest), ``slip_m`` throw / sin dip, ``dip_deg``, ``sense`` 1 normal / 2 reverse,
``damage`` 2 on and 1 near a fault, ``layer`` the bed index (0 the deepest of the series) and
``strain`` 0. With ``rendering = "elements"`` the property grids are the series looked up at
the cell centres.

Every draw comes from the run's seed tree (``SEED_DEM``: faults, then folds and shear;
``SEED_STRATA``: the series; ``SEED_PROPERTIES``: the rock), so one config gives the same
bytes. There are no particles.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass

import numpy as np
from scipy.ndimage import gaussian_filter1d

from demseis.dem import FaultSystem
from demseis.errors import ConfigError
from demseis.generator.config.layout import grid_of, param_codes
from demseis.generator.config.params import spec_values_hint
from demseis.generator.config.sampling import (SEED_DEM, SEED_PROPERTIES, SEED_STRATA, RunParams,
                                               RunSpec, rng_at)
from demseis.generator.config.settings import Config
from demseis.generator.engines import EngineRun, State
from demseis.generator.engines.kinematic import draw_fault_labels
from demseis.generator.engines.runsetup import ABSENT, RunInfo, bed_model_of, property_model_of
from demseis.parameters import MAX_BASEMENT_FAULTS
from demseis.schema import engine_labels, sample_array
from demseis.seismic import Strata, draw_layer_properties, strata_properties
from demseis.seismic.strata import bed_thicknesses

#: reflection coefficients are uniform in [-REFLECTIVITY_MAX, REFLECTIVITY_MAX]
REFLECTIVITY_MAX = 0.02
#: Gaussian sigma (m) of the smooth part taken out of the series' log-impedance
DETREND_M = 50.0
#: fewest and most Gaussian bumps of the folding
FOLD_BUMPS = (2, 4)
#: range of a bump's width d_k, as fractions of the model width
FOLD_WIDTH = (0.05, 0.25)
#: range of a fault's x at mid-depth, as fractions of the model width
FAULT_X = (0.1, 0.9)


@dataclass(frozen=True)
class PlanarFault:
    """One fault of the planar engine.

    Attributes
    ----------
    x_m : x where the fault meets the base of the model (depth = height).
    dip_deg : dip.
    throw_m : final throw, constant along the fault.
    direction : +1 dips right (the trace moves to larger x with depth; hanging wall at larger
        x), -1 left.
    reverse : a reverse fault (hanging wall up); else normal (down).
    """

    x_m: float
    dip_deg: float
    throw_m: float
    direction: int
    reverse: bool

    def x_at(self, depth_m: np.ndarray, height_m: float) -> np.ndarray:
        """x of the fault at depths ``depth_m`` (below the top of the model)."""
        return self.x_m - self.direction * (height_m - np.asarray(depth_m)) / np.tan(
            np.radians(self.dip_deg))


@dataclass(frozen=True)
class PlanarModel:
    """The drawn geometry of a run (module docstring).

    Attributes
    ----------
    width_m, height_m : the model box.
    faults : the faults, oldest first.
    bump_amplitude_m, bump_centre_m, bump_width_m : (K,) b_k, c_k, d_k of the folding.
    shear_slope : f of the planar shear; shear_offset_m : e0.
    """

    width_m: float
    height_m: float
    faults: tuple[PlanarFault, ...]
    bump_amplitude_m: np.ndarray
    bump_centre_m: np.ndarray
    bump_width_m: np.ndarray
    shear_slope: float
    shear_offset_m: float

    def fold_shift(self, x_m: np.ndarray, depth_m: np.ndarray) -> np.ndarray:
        """s1(x, z) = 1.5 max(z, 0) / H sum_k b_k exp(-(x - c_k)^2 / (2 d_k^2)) (m, down)."""
        x = np.asarray(x_m, dtype=np.float64)
        g = np.zeros_like(x)
        for b, c, d in zip(self.bump_amplitude_m, self.bump_centre_m, self.bump_width_m):
            g += b * np.exp(-0.5 * ((x - c) / d) ** 2)
        return 1.5 * np.clip(depth_m, 0.0, None) / self.height_m * g

    def shear_shift(self, x_m: np.ndarray) -> np.ndarray:
        """s2(x) = e0 + f x (m, down)."""
        return self.shear_offset_m + self.shear_slope * np.asarray(x_m, dtype=np.float64)

    def unfault(self, fraction: float, x_m: np.ndarray, depth_m: np.ndarray,
                maps: dict[str, np.ndarray] | None = None,
                half_m: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
        """Where the rock at ``(x_m, depth_m)`` (depth below the top) was in the flat series,
        with ``fraction`` of every throw: ``(x0_m, depth0_m)``.

        Youngest fault first, each hanging-wall point is moved back along its fault by the
        throw; then the shear and the folds are undone (``z1 = z - s2(x)``, ``z0 = z1 -
        s1(x, z1)``). With ``maps`` (label maps of the grid, the points its cell centres), the
        cells within ``half_m`` (perpendicular) of each fault are labelled on the way, in the
        coordinates of that fault's time, so an older fault's label follows the offsets of the
        younger ones.
        """
        X = np.asarray(x_m, dtype=np.float64)
        D = np.asarray(depth_m, dtype=np.float64)
        H = self.height_m
        for k in range(len(self.faults) - 1, -1, -1):
            f = self.faults[k]
            throw = fraction * f.throw_m
            if throw <= 0.0:
                continue
            sin, tan = np.sin(np.radians(f.dip_deg)), np.tan(np.radians(f.dip_deg))
            offset = X - f.x_at(D, H)
            if maps is not None:
                draw_fault_labels(maps, k, "reverse" if f.reverse else "normal",
                                  np.abs(offset) * sin, np.full(X.shape, throw),
                                  np.full(X.shape, f.dip_deg), half_m)
            hanging = offset * f.direction > 0
            sign = -1.0 if f.reverse else 1.0  # normal: the hanging wall went down-dip
            D = np.where(hanging, D - sign * throw, D)
            X = np.where(hanging, X - sign * f.direction * throw / tan, X)
        z1 = D - self.shear_shift(X)
        return X, z1 - self.fold_shift(X, z1)

    def depth_margin_m(self) -> float:
        """How far (m) above the top or below the base of the model a point's flat depth can
        lie: the throws, the shear over the width and the heaves, and the folds."""
        throws = sum(f.throw_m for f in self.faults)
        heaves = sum(f.throw_m / np.tan(np.radians(f.dip_deg)) for f in self.faults)
        shear = abs(self.shear_offset_m) + abs(self.shear_slope) * (self.width_m + heaves)
        deepest = self.height_m + throws + shear
        fold = 1.5 * deepest / self.height_m * float(np.abs(self.bump_amplitude_m).sum())
        return float(throws + shear + fold)


def planar_model(cfg: Config, params: RunParams, run: int) -> PlanarModel:
    """The geometry of run ``run`` (module docstring), from its ``SEED_DEM`` stream: the
    faults (n x [x, dip, direction, sense, throw] uniforms), then the folds and the shear."""
    W, H = cfg.model.width_m, cfg.model.height_m
    rng = rng_at(cfg, run, SEED_DEM)
    n = params.planar_faults
    u = rng.random((n, 5))
    dip_lo, dip_hi = params.planar_dip_min_deg, params.planar_dip_max_deg
    t_lo, t_hi = params.planar_throw_min_m, params.planar_throw_max_m
    faults = []
    for x_u, dip_u, dir_u, sense_u, throw_u in u:
        dip = dip_lo + dip_u * (dip_hi - dip_lo)
        direction = 1 if dir_u < 0.5 else -1
        x_mid = (FAULT_X[0] + x_u * (FAULT_X[1] - FAULT_X[0])) * W
        faults.append(PlanarFault(
            x_m=float(x_mid + direction * 0.5 * H / np.tan(np.radians(dip))),
            dip_deg=float(dip), throw_m=float(t_lo + throw_u * (t_hi - t_lo)),
            direction=direction, reverse=bool(sense_u < params.planar_reverse_fraction)))
    k = int(rng.integers(FOLD_BUMPS[0], FOLD_BUMPS[1] + 1))
    amp = params.fold_amplitude_m
    b = rng.uniform(-amp, amp, k)
    c = rng.uniform(0.0, W, k)
    d = rng.uniform(FOLD_WIDTH[0], FOLD_WIDTH[1], k) * W
    tilt = params.planar_tilt_deg
    slope = float(np.tan(np.radians(rng.uniform(-tilt, tilt))))
    pivot = float(rng.uniform(0.0, W))
    return PlanarModel(width_m=W, height_m=H, faults=tuple(faults), bump_amplitude_m=b,
                       bump_centre_m=c, bump_width_m=d, shear_slope=slope,
                       shear_offset_m=-slope * pivot)


def reflectivity_strata(cfg: Config, params: RunParams, run: int,
                        model: PlanarModel) -> Strata:
    """The random reflectivity series of run ``run`` as a :class:`Strata` of one unit (module
    docstring), covering the flat depths ``[-m, H + m]`` with ``m`` the model's
    :meth:`~PlanarModel.depth_margin_m` (y up, 0 at the base of the model)."""
    H, W = cfg.model.height_m, cfg.model.width_m
    margin = model.depth_margin_m() + 2.0 * cfg.grid.cell_m
    y_bottom, y_top = -margin, H + margin
    rng = rng_at(cfg, run, SEED_STRATA)
    beds = bed_model_of(dict(params))
    t = bed_thicknesses(y_top - y_bottom, beds, rng)
    bottom = y_bottom + np.concatenate(([0.0], np.cumsum(t)[:-1]))
    top = np.concatenate((bottom[1:], [y_top]))
    r = REFLECTIVITY_MAX * rng.uniform(-1.0, 1.0, t.size - 1)
    s = np.concatenate(([0.0], np.cumsum(2.0 * np.arctanh(r))))
    s = s - gaussian_filter1d(s, DETREND_M / float(np.mean(t)), mode="nearest")
    rock = draw_layer_properties(1, property_model_of(cfg, dict(params)),
                                 rng_at(cfg, run, SEED_PROPERTIES))
    B = t.size
    flat = np.zeros((B, 2))
    return Strata(unit_bottom_m=np.array([y_bottom]), unit_top_m=np.array([y_top]),
                  n_prekinematic=1, unit_first_bed=np.array([0, B], dtype=np.int64),
                  bed_bottom_m=bottom, bed_top_m=top, facies=np.ones(B, dtype=np.int8),
                  vp_m_s=np.full(B, float(rock.vp[0])),
                  rho_kg_m3=float(rock.rho[0]) * np.exp(s),
                  lateral_amplitude_vp=0.0, lateral_amplitude_rho=0.0, lateral=flat,
                  undulation=flat.copy(), dx_m=float(W), width_m=float(W))


def planar_info(cfg: Config, model: PlanarModel) -> RunInfo:
    """The stored per-run values of a planar run (module docstring); its ``system`` is empty
    (the faults are not the DEM's basement)."""
    codes = param_codes()
    faults = model.faults
    master = max(faults, key=lambda f: f.throw_m) if faults else None
    values: dict[str, float] = {"fault_x_m": master.x_m if master else ABSENT,
                                "throw_target_m": master.throw_m if master else 0.0,
                                "n_basement_faults": len(faults)}
    if master:  # the drawn dip_deg is not used: store the fault of largest throw's
        values["dip_deg"] = master.dip_deg
    by_x = sorted(faults, key=lambda f: f.x_m)[:MAX_BASEMENT_FAULTS]
    for k in range(MAX_BASEMENT_FAULTS):
        f = by_x[k] if k < len(by_x) else None
        values[f"fault{k}_kind"] = (codes["fault_kind"].index("reverse" if f.reverse else "normal")
                                    if f else -1)
        values[f"fault{k}_dip_direction"] = (codes["dip_direction"].index(
            "right" if f.direction == 1 else "left") if f else -1)
        values[f"fault{k}_x_m"] = f.x_m if f else ABSENT
        values[f"fault{k}_dip_deg"] = f.dip_deg if f else ABSENT
        values[f"fault{k}_throw_target_m"] = f.throw_m if f else ABSENT
        values[f"fault{k}_throw_m"] = ABSENT
    return RunInfo(system=FaultSystem((), speed_m_s=cfg.model.wall_speed_m_s, structure="none"),
                   values=values)


def planar_state(cfg: Config, model: PlanarModel, strata: Strata,
                 fraction: float) -> dict[str, np.ndarray]:
    """The label maps of the grid (``layer`` included) with ``fraction`` of every throw."""
    grid = grid_of(cfg)
    zc = (np.arange(grid.nz) + 0.5) * grid.cell_m
    xc = (np.arange(grid.nx) + 0.5) * grid.cell_m
    X, D = np.meshgrid(xc, zc)
    maps = {name: np.zeros(X.shape, sample_array(name).dtype) for name in engine_labels()}
    half_m = 0.5 * max(float(cfg.labels.thickness_cells), 1.0) * grid.cell_m
    _, depth0 = model.unfault(fraction, X, D, maps, half_m)
    y0 = cfg.model.height_m - depth0
    bed = np.clip(np.searchsorted(strata.bed_bottom_m, y0, side="right") - 1, 0,
                  strata.n_beds - 1)
    maps["layer"] = bed.astype(maps["layer"].dtype)  # strain stays 0: no strain field
    return maps


class PlanarEngine:
    """The planar engine as an :class:`~demseis.generator.engines.Engine` (no particles)."""

    particles = False
    strata = True

    def check(self, cfg: Config) -> None:
        """The ranges' lower ends are at most their upper ends, the throws at most 0.6 model
        height and the folds at most height / 6 (four bumps of 1.5 x that amplitude at the
        base would overturn the series)."""
        p = cfg.sweep.params
        H = cfg.model.height_m
        for low, high in (("planar_dip_min_deg", "planar_dip_max_deg"),
                          ("planar_throw_min_m", "planar_throw_max_m")):
            lo_hi, hi_lo = spec_values_hint(p[low])[1], spec_values_hint(p[high])[0]
            if lo_hi > hi_lo:
                raise ConfigError(f"sweep.{low} up to {lo_hi:g} exceeds sweep.{high} from "
                                  f"{hi_lo:g}: the planar engine needs {low} <= {high}")
        throw_hi = spec_values_hint(p["planar_throw_max_m"])[1]
        if throw_hi > 0.6 * H:
            raise ConfigError(f"sweep.planar_throw_max_m up to {throw_hi:g} m is too large for "
                              f"model.height_m = {H:g}: at most 0.6 * height_m = {0.6 * H:g} m")
        fold_hi = spec_values_hint(p["fold_amplitude_m"])[1]
        if 1.5 * FOLD_BUMPS[1] * fold_hi > H:
            raise ConfigError(f"sweep.fold_amplitude_m up to {fold_hi:g} m is too large for the "
                              f"planar engine with model.height_m = {H:g}: at most height_m / "
                              f"{1.5 * FOLD_BUMPS[1]:g} = {H / (1.5 * FOLD_BUMPS[1]):g} m, or "
                              "the folds overturn")

    def cost(self, cfg: Config, params: RunParams) -> float:
        """Every run costs about the same (one grid pass per fault and state)."""
        return 1.0 + params.planar_faults

    def describe(self, cfg: Config) -> tuple[str, float]:
        """A line for ``--dry-run`` and the seconds of one run on one core at most (the
        kinematic engine's figure, ``benchmarks/kinematic_speed.py``: the planar engine does
        less per state)."""
        grid = grid_of(cfg)
        return (f"planar (FaultSeg), {cfg.model.n_snapshots} states each",
                0.25 * grid.nz * grid.nx / (110 * 250))

    def simulate(self, cfg: Config, spec: RunSpec,
                 progress: Callable[[float], None] | None = None) -> EngineRun:
        """The run's stored values; the states are drawn from its geometry by :meth:`states`."""
        return EngineRun(spec=spec, info=planar_info(cfg, planar_model(cfg, spec.params,
                                                                        spec.run)))

    def states(self, cfg: Config, run: EngineRun, snapshots: Sequence[int]) -> Iterator[State]:
        """The series folded, sheared and cut by the fraction k / (n - 1) of every throw, for
        each snapshot k."""
        p = run.spec.params
        model = planar_model(cfg, p, run.spec.run)
        strata = reflectivity_strata(cfg, p, run.spec.run, model)
        n_snap = cfg.model.n_snapshots
        master = max((f.throw_m for f in model.faults), default=0.0)
        by_x = sorted(model.faults, key=lambda f: f.x_m)[:MAX_BASEMENT_FAULTS]
        grid = grid_of(cfg)
        X, D = np.meshgrid((np.arange(grid.nx) + 0.5) * grid.cell_m,
                           (np.arange(grid.nz) + 0.5) * grid.cell_m)
        for k in snapshots:
            fraction = k / (n_snap - 1)
            maps = planar_state(cfg, model, strata, fraction)
            x0, y0, _ = _reference(model, cfg.model.height_m, fraction, X, D)
            vp, rho = strata_properties(strata, x0, y0)   # the cell centres (elements)
            values = {"step": k, "throw_m": fraction * master, "n_elements": 0,
                      **{f"fault{i}_throw_m": (fraction * by_x[i].throw_m if i < len(by_x)
                                               else ABSENT) for i in range(MAX_BASEMENT_FAULTS)}}
            yield State(snapshot=k, vp_m_s=vp, rho_kg_m3=rho, labels=maps, values=values,
                        reference=_Reference(model, cfg.model.height_m, fraction),
                        strata=strata)


def _reference(model: PlanarModel, height_m: float, fraction: float, x_m: np.ndarray,
               depth_m: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """:attr:`State.reference` of the planar engine: :meth:`PlanarModel.unfault`, every point
    in the series' one unit."""
    x0, depth0 = model.unfault(fraction, x_m, depth_m)
    return x0, height_m - depth0, np.zeros(np.shape(x0), dtype=np.int64)


@dataclass(frozen=True)
class _Reference:
    """The reference map of one state (a picklable callable)."""

    model: PlanarModel
    height_m: float
    fraction: float

    def __call__(self, x_m: np.ndarray, depth_m: np.ndarray
                 ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        return _reference(self.model, self.height_m, self.fraction, x_m, depth_m)


ENGINE = PlanarEngine()
