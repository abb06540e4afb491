"""Stratigraphy in the reference (undeformed) frame: beds finer than the elements.

The ``strata`` rendering maps every point of a deformed section back to its reference
coordinates (x0, y0) (y up, m; 0 <= x0 <= width, y0 = 0 the basement top) and reads Vp and
density from a stratigraphy defined in that frame, at a vertical resolution independent of
the element size. This module draws that stratigraphy and looks it up.

Model
-----
*Units* are the mechanical layers: the pre-kinematic layers bottom to top, contiguous in y,
then possibly growth units (syn-tectonic sediment) with their own y ranges, which may overlap
the pre-kinematic ones. Each unit ``[bottom, top]`` is filled from its bottom with *beds*:

- thickness lognormal, median ``bed_thickness_median_m``, log standard deviation
  ``bed_thickness_log_sigma``, clipped to [``bed_thickness_min_m``, ``bed_thickness_max_m``];
  the top bed of a unit takes what is left (merged into the bed below it when thinner than the
  minimum), so every unit boundary is a bed boundary;
- log-impedance ``ln Z_j = ln Z_unit + s_j c / 2 + e_j`` around the unit's own Vp and density
  (``LayerProperties``): a two-state facies ``s_j = +-1`` (a Markov chain in bed index that
  switches with probability ``facies_switch_probability`` from one bed to the next; c =
  ``facies_contrast``) plus an AR(1) fluctuation in bed index, ``e_j = phi e_{j-1} +
  sqrt(1 - phi^2) sigma eps_j`` (phi = ``fluctuation_ar1``, sigma = ``fluctuation_sigma``),
  with Laplace innovations ``eps_j`` of unit variance. Rare facies switches among small
  Laplace steps make the reflection coefficients heavy-tailed (a scale mixture, as Walden &
  Hosken 1986 fit to well logs); blocky beds make their spectrum rise with frequency over the
  seismic band (Walden & Hosken 1985). A change of ln Z goes 0.8 to ln Vp and 0.2 to ln rho
  (Gardner's rho ~ Vp^0.25);
- a burial trend: ``Vp *= 1 + vp_gradient_per_km d``, ``rho *= 1 + rho_gradient_per_km d``
  with d the reference depth (km) of the bed's centre below the top of the highest unit
  (constant within a bed: beds stay blocky);
- lateral variation along each bed: ``Vp(x0) = Vp_j (1 + a f_j(x0))``, ``rho(x0) = rho_j
  (1 + (a/4 + a_rho) f_j(x0))`` with a = ``lateral_amplitude``, a_rho =
  ``lateral_density_amplitude`` and f_j a smooth random field of unit
  variance, independent per bed, of ``N_MODES`` random Fourier modes ``sqrt(2/M) sum_m cos(k_m
  x0 + p_m)``, ``k_m ~ N(0, 1/L^2)`` (a Gaussian covariance ``exp(-r^2 / 2 L^2)``, L =
  ``lateral_correlation_m``), ``p_m`` uniform, tabulated every dx = min(L, L_u) / 8 (at
  least width / 4096) over [0, width] and read by linear interpolation (continuous in x0; x0
  outside [0, width] reads the edge value);
- undulating bed boundaries: the boundary below bed j (not a unit boundary) lies at
  ``y_j + b h_j g_j(x0)`` with b = ``boundary_undulation``, h_j the thinner of the two beds it
  separates and g_j a field like f_j with length ``undulation_correlation_m``. Since
  ``|g| <= sqrt(2 M)`` and ``b sqrt(2 M) < 1/2``, boundaries never cross.

Everything is drawn from the ``rng`` given, unit by unit, so one seed gives the same bytes.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields

import numpy as np

from demseis.errors import ConfigError, InputError
from demseis.parameters import BED_FIELDS, PARAMS
from demseis.seismic import _kernels
from demseis.seismic.properties import LayerProperties

N_MODES = 4
"""Random Fourier modes per bed of each lateral field (lateral variation, undulation)."""

_FIELD_SCALE = math.sqrt(2.0 / N_MODES)
_VP_SHARE = 0.8                           # d ln Vp / d ln Z for rho ~ Vp^0.25 (Gardner)
_RHO_LATERAL = 0.25                       # d ln rho / d ln Vp along a bed (Gardner)


@dataclass(frozen=True)
class BedModel:
    """Parameters of the beds of the ``strata`` rendering (see the module docstring).

    Attributes
    ----------
    bed_thickness_median_m : median bed thickness (m), in [0.1, 100]; default 4 m, so that most
        beds are thinner than the tuning thickness (~20-30 m at 30-40 Hz).
    bed_thickness_log_sigma : standard deviation of ln(thickness), in [0, 3]; default 0.8.
    bed_thickness_min_m : smallest bed (m), in [0.1, 100] and <= the median; default 0.5.
    bed_thickness_max_m : thickest bed (m), >= the median and <= 1000; default 40.
    facies_contrast : difference of ln(impedance) between the two facies, in [0, 1]; default
        0.15 (a reflection coefficient of about +-0.075 where the facies switches).
    facies_switch_probability : probability that a bed's facies differs from the bed's below,
        in [0, 1]; default 0.3.
    fluctuation_sigma : standard deviation of the bed-to-bed ln(impedance) fluctuation, in
        [0, 0.5]; default 0.03.
    fluctuation_ar1 : lag-one (bed index) correlation of that fluctuation, in [0, 0.99];
        default 0.5.
    vp_gradient_per_km : relative increase of Vp per km of reference depth below the top of
        the highest unit, in [0, 1]; default 0.05.
    rho_gradient_per_km : relative increase of density per km of that depth, in [0, 0.5];
        default 0.015.
    lateral_amplitude : relative standard deviation of Vp along a bed, in [0, 0.2] (density
        varies a quarter as much); default 0.03. In the time domain it shifts each trace's
        two-way time from its neighbour's (docs/seismic.md).
    lateral_density_amplitude : relative standard deviation of density along a bed, in
        [0, 0.2], added to the quarter of ``lateral_amplitude`` and following the same field:
        the impedance, and so the reflector's strength, varies along the bed while the travel
        time does not; default 0.
    lateral_correlation_m : correlation length (m) of the variation along a bed, in
        [1, 1e6]; default 27.
    boundary_undulation : standard deviation of a bed boundary's vertical displacement as a
        fraction of the thinner adjacent bed, in [0, 0.17] (below 1 / (2 sqrt(2 N_MODES)), so
        boundaries never cross); default 0.1.
    undulation_correlation_m : correlation length (m) of the undulation, in [1, 1e6];
        default 100. (At 0.1 of a bed the undulation is below seismic resolution: it keeps bed
        boundaries from being perfectly flat; it hardly changes the traces.)
    """

    bed_thickness_median_m: float = PARAMS["bed_thickness_median_m"].default
    bed_thickness_log_sigma: float = PARAMS["bed_thickness_log_sigma"].default
    bed_thickness_min_m: float = PARAMS["bed_thickness_min_m"].default
    bed_thickness_max_m: float = PARAMS["bed_thickness_max_m"].default
    facies_contrast: float = PARAMS["facies_contrast"].default
    facies_switch_probability: float = PARAMS["facies_switch_probability"].default
    fluctuation_sigma: float = PARAMS["fluctuation_sigma"].default
    fluctuation_ar1: float = PARAMS["fluctuation_ar1"].default
    vp_gradient_per_km: float = PARAMS["vp_gradient_per_km"].default
    rho_gradient_per_km: float = PARAMS["rho_gradient_per_km"].default
    lateral_amplitude: float = PARAMS["lateral_amplitude"].default
    lateral_density_amplitude: float = PARAMS["lateral_density_amplitude"].default
    lateral_correlation_m: float = PARAMS["lateral_correlation_m"].default
    boundary_undulation: float = PARAMS["boundary_undulation"].default
    undulation_correlation_m: float = PARAMS["undulation_correlation_m"].default

    def validate(self) -> "BedModel":
        """Check every field; raise :class:`ConfigError` naming field, value and allowed range.

        Returns ``self`` so it can be chained.
        """
        for f in fields(self):
            v = getattr(self, f.name)
            lo, hi = _RANGES[f.name]
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) \
                    or not lo <= v <= hi:
                raise ConfigError(f"strata.{f.name} = {v!r}: allowed is a number in "
                                  f"[{lo}, {hi}]")
        med = self.bed_thickness_median_m
        if self.bed_thickness_min_m > med:
            raise ConfigError(f"strata.bed_thickness_min_m = {self.bed_thickness_min_m!r} m "
                              f"exceeds strata.bed_thickness_median_m = {med!r} m: allowed is "
                              "min <= median")
        if self.bed_thickness_max_m < med:
            raise ConfigError(f"strata.bed_thickness_max_m = {self.bed_thickness_max_m!r} m is "
                              f"below strata.bed_thickness_median_m = {med!r} m: allowed is "
                              "max >= median")
        return self


#: the allowed range of each field: its declaration in :mod:`demseis.parameters`
_RANGES: dict[str, tuple[float, float]] = {name: (float(PARAMS[name].lo), float(PARAMS[name].hi))
                                           for name in BED_FIELDS}


@dataclass(frozen=True)
class Strata:
    """A drawn stratigraphy: plain arrays, beds of unit u at ``unit_first_bed[u] ..
    unit_first_bed[u + 1] - 1``, bottom to top. B beds, U units, M = ``N_MODES``.

    Attributes
    ----------
    unit_bottom_m, unit_top_m : (U,) float64 reference y range of each unit (m).
    n_prekinematic : units 0 .. n_prekinematic - 1 are the contiguous pre-kinematic pile.
    unit_first_bed : (U + 1,) int64 index of each unit's first bed (last entry B).
    bed_bottom_m, bed_top_m : (B,) float64 nominal (undeformed, x-independent) bed limits (m).
    facies : (B,) int8 facies of each bed (-1 or +1).
    vp_m_s, rho_kg_m3 : (B,) float64 Vp (m/s) and density (kg/m^3) of each bed, burial trend
        included, before lateral variation.
    lateral_amplitude_vp, lateral_amplitude_rho : relative amplitudes of the lateral variation.
    lateral : (B, K) float64 each bed's lateral field (unit variance) at x0 = k dx_m.
    undulation : (B, K) float64 displacement (m) of each bed's bottom boundary at x0 = k dx_m
        (zero where it is a unit boundary).
    dx_m : spacing of the tables (m); K = ceil(width / dx) + 1.
    width_m : width of the model (m).
    """

    unit_bottom_m: np.ndarray
    unit_top_m: np.ndarray
    n_prekinematic: int
    unit_first_bed: np.ndarray
    bed_bottom_m: np.ndarray
    bed_top_m: np.ndarray
    facies: np.ndarray
    vp_m_s: np.ndarray
    rho_kg_m3: np.ndarray
    lateral_amplitude_vp: float
    lateral_amplitude_rho: float
    lateral: np.ndarray
    undulation: np.ndarray
    dx_m: float
    width_m: float

    @property
    def n_units(self) -> int:
        return int(self.unit_bottom_m.shape[0])

    @property
    def n_beds(self) -> int:
        return int(self.bed_bottom_m.shape[0])


def _check_units(unit_bottom_m, unit_top_m, n_layers: int, n_prekinematic: int | None,
                 width_m: float) -> tuple[np.ndarray, np.ndarray, int]:
    bottom = np.asarray(unit_bottom_m, dtype=np.float64)
    top = np.asarray(unit_top_m, dtype=np.float64)
    if bottom.ndim != 1 or bottom.shape != top.shape or bottom.size == 0:
        raise InputError(f"unit_bottom_m and unit_top_m must be (U,) arrays with U >= 1, got "
                         f"{bottom.shape} and {top.shape}")
    if not (np.all(np.isfinite(bottom)) and np.all(np.isfinite(top)) and np.all(top > bottom)):
        raise InputError("every unit must have finite limits with unit_top_m > unit_bottom_m")
    if bottom.size > n_layers:
        raise InputError(f"{bottom.size} units but layer_props covers {n_layers} layers: unit u "
                         "takes the properties of layer u")
    n_pre = bottom.size if n_prekinematic is None else n_prekinematic
    if isinstance(n_pre, bool) or not isinstance(n_pre, (int, np.integer)) \
            or not 1 <= n_pre <= bottom.size:
        raise InputError(f"n_prekinematic must be an integer in [1, {bottom.size}], got "
                         f"{n_prekinematic!r}")
    gap = np.abs(bottom[1:n_pre] - top[:n_pre - 1])
    if gap.size and gap.max() > 1e-9 * max(1.0, float(np.abs(top[:n_pre]).max())):
        k = int(np.argmax(gap))
        raise InputError(f"pre-kinematic units must be contiguous bottom to top: unit {k} ends "
                         f"at {top[k]} m, unit {k + 1} starts at {bottom[k + 1]} m")
    if not (isinstance(width_m, (int, float, np.floating)) and math.isfinite(width_m)
            and width_m > 0):
        raise InputError(f"width_m must be finite and > 0 m, got {width_m!r}")
    return bottom, top, int(n_pre)


def bed_thicknesses(height: float, model: BedModel, rng: np.random.Generator) -> np.ndarray:
    """Bed thicknesses filling ``height`` from the bottom (see the module docstring); also
    the bed spacing of the planar engine's reflectivity series."""
    mu = math.log(model.bed_thickness_median_m)
    batch = int(height / model.bed_thickness_median_m) + 8
    parts: list[np.ndarray] = []
    total = 0.0
    while total < height:
        t = np.clip(rng.lognormal(mu, model.bed_thickness_log_sigma, batch),
                    model.bed_thickness_min_m, model.bed_thickness_max_m)
        parts.append(t)
        total += float(t.sum())
    t = np.concatenate(parts)
    bounds = np.cumsum(t)
    n = int(np.searchsorted(bounds, height, side="left")) + 1   # beds reaching the top
    t = t[:n].copy()
    t[-1] = height - (float(bounds[n - 2]) if n > 1 else 0.0)
    if n > 1 and t[-1] < model.bed_thickness_min_m:
        t[-2] += t[-1]
        t = t[:-1]
    return t


def _log_impedance_steps(n: int, model: BedModel, rng: np.random.Generator):
    """Facies (+-1) and AR(1) fluctuation with Laplace innovations for n beds."""
    switch = rng.random(n) < model.facies_switch_probability
    first = 1 if rng.random() < 0.5 else -1
    switch[0] = False
    facies = (first * np.where(np.cumsum(switch) % 2 == 0, 1, -1)).astype(np.int8)
    eps = rng.laplace(0.0, 1.0 / math.sqrt(2.0), n)        # unit variance
    phi = model.fluctuation_ar1
    e = np.empty(n)
    e[0] = eps[0]
    c = math.sqrt(1.0 - phi * phi)
    for j in range(1, n):
        e[j] = phi * e[j - 1] + c * eps[j]
    return facies, model.fluctuation_sigma * e


def _fourier_fields(n: int, correlation_m: float, x: np.ndarray,
                    rng: np.random.Generator) -> np.ndarray:
    """(n, x.size) values of n independent unit-variance fields of N_MODES random Fourier
    modes, wavenumbers (rad/m) ~ N(0, 1/L^2), phases ~ U(0, 2 pi)."""
    k = rng.standard_normal((n, N_MODES)) / correlation_m
    phase = rng.random((n, N_MODES)) * (2.0 * math.pi)
    return _FIELD_SCALE * np.cos(k[:, :, None] * x + phase[:, :, None]).sum(axis=1)


def draw_strata(unit_bottom_m, unit_top_m, layer_props: LayerProperties, width_m: float,
                model: BedModel, rng: np.random.Generator, *,
                n_prekinematic: int | None = None) -> Strata:
    """Draw the beds of every unit (see the module docstring for the model).

    Parameters
    ----------
    unit_bottom_m, unit_top_m : (U,) reference y range (m) of each unit: the pre-kinematic
        layers bottom to top (contiguous), then any growth units (their own ranges).
    layer_props : per-layer Vp, density (and lithology); unit u varies around layer u.
    width_m : model width (m), > 0.
    model : the bed model (validated here).
    rng : random generator; the only source of randomness.
    n_prekinematic : how many of the units are pre-kinematic (default: all of them); lookups
        without a unit search these by y.

    Returns
    -------
    :class:`Strata`.
    """
    model.validate()
    bottom, top, n_pre = _check_units(unit_bottom_m, unit_top_m, layer_props.n_layers,
                                      n_prekinematic, width_m)
    top_ref = float(top.max())
    dx = max(min(model.lateral_correlation_m, model.undulation_correlation_m) / 8.0,
             float(width_m) / 4096.0)
    x_tab = np.arange(int(math.ceil(float(width_m) / dx)) + 1) * dx
    first = [0]
    cols: dict[str, list[np.ndarray]] = {k: [] for k in (
        "bottom", "top", "facies", "vp", "rho", "lat", "und")}
    for u in range(bottom.size):
        t = bed_thicknesses(float(top[u] - bottom[u]), model, rng)
        n = t.size
        b = bottom[u] + np.concatenate(([0.0], np.cumsum(t)[:-1]))
        tp = np.concatenate((b[1:], [top[u]]))
        facies, e = _log_impedance_steps(n, model, rng)
        dlnz = 0.5 * model.facies_contrast * facies + e
        depth_km = np.maximum(top_ref - 0.5 * (b + tp), 0.0) / 1000.0
        vp = layer_props.vp[u] * np.exp(_VP_SHARE * dlnz) * (1.0 + model.vp_gradient_per_km
                                                               * depth_km)
        rho = layer_props.rho[u] * np.exp((1.0 - _VP_SHARE) * dlnz) * (
            1.0 + model.rho_gradient_per_km * depth_km)
        lat = _fourier_fields(n, model.lateral_correlation_m, x_tab, rng)
        amp = np.zeros(n)
        amp[1:] = model.boundary_undulation * np.minimum(t[1:], t[:-1])
        und = amp[:, None] * _fourier_fields(n, model.undulation_correlation_m, x_tab, rng)
        for name, arr in (("bottom", b), ("top", tp), ("facies", facies), ("vp", vp),
                          ("rho", rho), ("lat", lat), ("und", und)):
            cols[name].append(arr)
        first.append(first[-1] + n)
    cat = {k: np.ascontiguousarray(np.concatenate(v)) for k, v in cols.items()}
    return Strata(
        unit_bottom_m=bottom.copy(), unit_top_m=top.copy(), n_prekinematic=n_pre,
        unit_first_bed=np.asarray(first, dtype=np.int64), bed_bottom_m=cat["bottom"],
        bed_top_m=cat["top"], facies=cat["facies"], vp_m_s=cat["vp"], rho_kg_m3=cat["rho"],
        lateral_amplitude_vp=float(model.lateral_amplitude),
        lateral_amplitude_rho=float(_RHO_LATERAL * model.lateral_amplitude
                                    + model.lateral_density_amplitude),
        lateral=cat["lat"], undulation=cat["und"], dx_m=float(dx), width_m=float(width_m),
    )


def strata_properties(strata: Strata, x0_m, y0_m, unit=None) -> tuple[np.ndarray, np.ndarray]:
    """Vp and density at reference points (x0, y0).

    Parameters
    ----------
    strata : from :func:`draw_strata`.
    x0_m, y0_m : reference coordinates (m), arrays of one shape (any shape), finite.
    unit : ``None`` (every point in the pre-kinematic unit containing y0: below the lowest
        unit the lowest, above the top the top one) or an integer array of that shape giving
        each point's unit (-1: found by y0 as for ``None``). Growth units need it.

    Returns
    -------
    vp (m/s), rho (kg/m^3): float64 arrays of the shape of x0_m.
    """
    x = np.asarray(x0_m, dtype=np.float64)
    y = np.asarray(y0_m, dtype=np.float64)
    if x.shape != y.shape:
        raise InputError(f"x0_m and y0_m must have one shape, got {x.shape} and {y.shape}")
    if not (np.all(np.isfinite(x)) and np.all(np.isfinite(y))):
        raise InputError("x0_m and y0_m must be finite")
    if unit is None:
        u = np.full(x.size, -1, dtype=np.int64)
    else:
        ua = np.asarray(unit)
        if ua.shape != x.shape or not np.issubdtype(ua.dtype, np.integer):
            raise InputError(f"unit must be an integer array of shape {x.shape}, got "
                             f"{ua.dtype} {ua.shape}")
        if ua.size and (ua.min() < -1 or ua.max() >= strata.n_units):
            raise InputError(f"unit entries must be -1 or in [0, {strata.n_units - 1}], got "
                             f"[{ua.min()}, {ua.max()}]")
        u = np.ascontiguousarray(ua.reshape(-1), dtype=np.int64)
    vp = np.empty(x.size)
    rho = np.empty(x.size)
    s = strata
    _kernels.strata_lookup(
        np.ascontiguousarray(x.reshape(-1)), np.ascontiguousarray(y.reshape(-1)), u,
        s.unit_top_m, s.n_prekinematic, s.unit_first_bed, s.bed_bottom_m, s.undulation,
        undulation_bound(s), s.vp_m_s, s.rho_kg_m3, s.lateral_amplitude_vp,
        s.lateral_amplitude_rho, s.lateral, s.dx_m, vp, rho)
    return vp.reshape(x.shape), rho.reshape(x.shape)


def undulation_bound(strata: Strata) -> np.ndarray:
    """(B,) the largest |displacement| (m) of each bed's bottom boundary."""
    return np.ascontiguousarray(np.abs(strata.undulation).max(axis=1))
