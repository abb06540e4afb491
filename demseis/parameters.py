"""Every parameter of demseis, declared once: name, unit, range, default, doc and level.

Config validation (:mod:`demseis.generator.config.settings`), the stage checks (the DEM's
:func:`~demseis.dem.integrator.validate_material` and :func:`~demseis.dem.fault.validate_fault`, the
rock-property model's :meth:`~demseis.seismic.PropertyModel.validate`, the wavelet and noise
checks), the defaults of :class:`~demseis.dem.Material` and
:class:`~demseis.seismic.PropertyModel`, ``demseis params`` and the table in
``docs/parameters.md`` all read :data:`PARAMS`. So a config a stage would refuse is refused when
it is loaded, before any work starts.

Levels say where a value is drawn:

- ``sweep``: one value for the whole sweep (``[model]``, ``[grid]``, ``[output]`` and the
  ``seed``, ``n_runs``, ``renders_per_snapshot`` keys of ``[sweep]``);
- ``run``: one value per DEM run (a ``[sweep]`` key: fixed, a list or a distribution);
- ``sample``: one value per rendered sample (a ``[sweep]`` key).

:data:`STORED` declares the per-sample values a store holds besides the ``run`` and ``sample``
parameters: the ones derived per snapshot (the throw reached, the integrator step) or per sample.

This module imports only the standard library and :mod:`demseis.errors`; every stage may import it.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from typing import Any

from demseis.errors import ConfigError, DemseisError, InputError
from demseis.registry import ENGINES, FAULT_STYLES, IMAGING, LABEL_METHODS, RENDERINGS, Registry

INF = math.inf
LEVELS = ("sweep", "run", "sample")
#: most basement faults of a fault system (demseis.dem.basement)
MAX_BASEMENT_FAULTS = 5


@dataclass(frozen=True)
class Param:
    """What one parameter may be.

    Attributes
    ----------
    name : the key in its config section.
    kind : ``float``, ``int``, ``str`` or ``bool``.
    level : ``"sweep"``, ``"run"`` or ``"sample"`` (see the module docstring).
    default : the value used when the key is absent.
    lo, hi : numeric bounds (None = unbounded); ``hi = inf`` admits inf.
    choices : allowed values of a ``str`` parameter: a tuple, or a :class:`~demseis.registry.Registry`
        whose names are the values (engines, imaging modes: a name registered later is valid).
        A stored ``str`` parameter holds the index of its value among the choices.
    doc : one line for ``demseis params`` and the docs.
    unit : SI unit ("" for dimensionless).
    section : the config table that holds it (``sweep``, ``model``, ``grid``, ``output``,
        ``labels``).
    lo_open, hi_open : the bound itself is excluded.
    stage_lo, stage_hi, stage_lo_open, stage_hi_open : the wider physical domain the consuming
        stage accepts when it is called directly (analytic tests, derived per-layer materials);
        None = the config range above. A config is held to ``lo``..``hi``.
    optional : None is a value too (the key unset: its consumer picks a value, e.g. ``[labels]
        min_slip_m``, one grid cell); a TOML config cannot write it, a stored config can.
    """

    name: str
    kind: type
    level: str
    default: Any
    lo: float | None = None
    hi: float | None = None
    choices: tuple[str, ...] | Registry | None = None
    doc: str = ""
    unit: str = ""
    section: str = "sweep"
    lo_open: bool = False
    hi_open: bool = False
    stage_lo: float | None = None
    stage_hi: float | None = None
    stage_lo_open: bool = False
    stage_hi_open: bool = False
    optional: bool = False

    def stage(self) -> Param:
        """This parameter with the bounds its consuming stage accepts (itself if no wider ones)."""
        if self.stage_lo is None and self.stage_hi is None:
            return self
        return dataclasses.replace(self, lo=self.stage_lo, hi=self.stage_hi,
                                   lo_open=self.stage_lo_open, hi_open=self.stage_hi_open,
                                   stage_lo=None, stage_hi=None, stage_lo_open=False,
                                   stage_hi_open=False)

    def allowed(self) -> str:
        """Human description of the admissible values, e.g. ``a number in [10, 80]``."""
        if self.optional:
            return dataclasses.replace(self, optional=False).allowed() + " (or unset)"
        if self.choices is not None:
            return "one of " + ", ".join(repr(c) for c in self.choices)
        if self.kind is bool:
            return "true or false"
        kind = "an integer" if self.kind is int else "a number"
        lo = None if self.lo is None else ("(" if self.lo_open else "[") + _fmt(self.lo)
        hi = None if self.hi is None else _fmt(self.hi) + (")" if self.hi_open else "]")
        if lo is not None and hi is not None:
            return f"{kind} in {lo}, {hi}"
        if lo is not None:
            return f"{kind} {'>' if self.lo_open else '>='} {_fmt(self.lo)}"
        if hi is not None:
            return f"{kind} {'<' if self.hi_open else '<='} {_fmt(self.hi)}"
        return kind

    def range_text(self) -> str:
        """The range column of the parameter table."""
        if self.choices is not None:
            return ", ".join(self.choices)
        if self.kind is bool:
            return "true, false"
        return self.allowed().split(" ", 2)[-1].removeprefix("in ")

    def in_range(self, value: float) -> bool:
        """Whether a number lies within the bounds."""
        if self.lo is not None and (value < self.lo or (self.lo_open and value == self.lo)):
            return False
        if self.hi is not None and (value > self.hi or (self.hi_open and value == self.hi)):
            return False
        return True

    def check_value(self, value: Any, where: str,
                    error: type[DemseisError] = ConfigError) -> Any:
        """Coerce and check one value; raise ``error`` naming ``where``, the value and the range.

        Integers are accepted for floats, ``"inf"`` for a float whose range admits inf.
        """
        if value is None and self.optional:
            return None
        try:
            coerced, ok = self._coerce(value)
        except InputError as exc:  # a "module:attribute" choice that does not import
            raise error(f"{where} = {value!r} is not allowed: {exc}") from None
        if not ok:
            raise error(f"{where} = {value!r} is not allowed: expected {self.allowed()}")
        return coerced

    def _coerce(self, value: Any) -> tuple[Any, bool]:
        """(coerced value, whether it is allowed); the error is only formatted on failure."""
        if self.kind is bool:
            return value, isinstance(value, bool)
        if self.kind is str:
            return value, isinstance(value, str) and not (self.choices and value not in self.choices)
        if isinstance(value, str) and self.kind is float and value.strip().lower() in ("inf", "+inf"):
            value = math.inf
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            try:  # numpy scalars
                value = value.item()
            except AttributeError:
                return value, False
            if isinstance(value, bool) or not isinstance(value, (int, float)):
                return value, False
        if self.kind is int:
            if isinstance(value, float) and not value.is_integer():
                return value, False
            value = int(value)
        else:
            value = float(value)
            if math.isnan(value):
                return value, False
        if not self.in_range(value):
            return value, False
        if self.kind is float and math.isinf(value) and self.hi != math.inf:
            return value, False
        return value, True

def _fmt(x: float) -> str:
    if x == math.inf:
        return "inf"
    return f"{x:g}"


def _p(name: str, kind: type, level: str, default: Any, lo: float | None = None,
       hi: float | None = None, *, unit: str = "", doc: str = "", section: str = "sweep",
       choices: tuple[str, ...] | Registry | None = None, lo_open: bool = False,
       hi_open: bool = False, stage: tuple[float, float, bool, bool] | None = None,
       optional: bool = False) -> Param:
    """A declaration; ``stage`` = (lo, hi, lo_open, hi_open) of the wider stage domain."""
    st = stage if stage is not None else (None, None, False, False)
    return Param(name, kind, level, default, lo, hi, choices, doc, unit, section, lo_open, hi_open,
                 *st, optional)


def _label(name: str, kind: type, default: Any, lo: float | None = None, hi: float | None = None,
           *, doc: str, unit: str = "", choices: tuple[str, ...] | Registry | None = None,
           lo_open: bool = False, optional: bool = False) -> Param:
    """A ``[labels]`` key: one value for the whole sweep, the field of the same name of
    :class:`demseis.labels.LabelConfig`."""
    return _p(name, kind, "sweep", default, lo, hi, unit=unit, doc=doc, section="labels",
              choices=choices, lo_open=lo_open, optional=optional)


_DECLARED: tuple[Param, ...] = (
    # ---- [sweep]: how many runs, the root seed -------------------------------------------
    _p("seed", int, "sweep", 0, 0, 2**63 - 1, doc="root seed of the sweep's SeedSequence tree"),
    _p("n_runs", int, "sweep", 4, 1, 10**7, doc="number of DEM runs (one store shard each)"),
    _p("renders_per_snapshot", int, "sweep", 1, 1, 10**4,
       doc="extra draws of the sample-level distributions per snapshot and grid combination"),
    # ---- [sweep], per run: the basement fault -------------------------------------------
    _p("dip_deg", float, "run", 45.0, 10.0, 80.0, unit="deg", doc="basement fault dip"),
    _p("throw_m", float, "run", 450.0, 1.0, 1.0e5, unit="m",
       doc="final vertical throw of the basement fault (at most 0.6 model height)"),
    _p("fault_x_frac", float, "run", 0.5, 0.05, 0.95,
       doc="x where the basement fault meets the model base, as a fraction of the width"),
    _p("dip_direction", str, "run", "right", choices=("right", "left"),
       doc="side of the hanging wall"),
    # ---- per run: fault systems (demseis.dem.basement; "single" + "normal" is the fault above)
    _p("structure", str, "run", "single",
       choices=("single", "domino", "graben", "horst", "half_graben", "none"),
       doc="basement structure: one fault, a domino (synthetic) set, graben, horst, "
           "half-graben (one listric fault), or none (no basement fault: only the stretching "
           "base, needs base_stretch != 0); dip_deg and throw_m apply to every fault"),
    _p("n_faults", int, "run", 1, 1, MAX_BASEMENT_FAULTS,
       doc="faults of a domino set (graben and horst have 2, the others 1)"),
    _p("fault_kind", str, "run", "normal", choices=("normal", "reverse", "listric"),
       doc="kind of the faults of single/domino/graben/horst (a half-graben is listric; a "
           "listric fault must bound an end block, so a listric domino/graben/horst is normal)"),
    _p("fault_spacing_frac", float, "run", 0.2, 0.08, 0.4,
       doc="domino fault spacing, or graben/horst width, as a fraction of the model width"),
    _p("listric_radius_m", float, "run", 5000.0, 1500.0, 20000.0, unit="m",
       doc="radius of curvature of a listric fault (its throw is capped at 80% of the arc's "
           "depth)"),
    _p("strength_contrast", float, "run", 1.0, 1.0, 16.0,
       doc="mechanical stratigraphy: cohesion ratio of strong (sandstone, limestone) to weak "
           "(shale) layers, which are also up to 4x softer and have up to half the friction; "
           "1 = uniform mechanics (demseis.dem.strata)"),
    _p("base_stretch", float, "run", 0.0, -0.3, 0.3,
       doc="distributed extension (> 0) or shortening (< 0) of the model base, as a fraction of "
           "the width: the base stretches like a rubber sheet under the cover (0 = off); the "
           "DEM grows a fault population above it, the kinematic engine draws one that takes up "
           "the same extension"),
    # ---- per run: the kinematic engine only ([model] engine = "kinematic"; fold_amplitude_m
    # also the planar engine's) ---------------------------------------------------------------
    _p("fold_amplitude_m", float, "run", 0.0, 0.0, 1.0e4, unit="m",
       doc="kinematic engine: amplitude of the folding of the layers before faulting (0 = "
           "flat); planar engine: the Gaussian bumps' amplitudes are uniform in [-this, this] "
           "(at most model height / 6)"),
    _p("fold_kind", str, "run", "gaussian", choices=("gaussian", "sinusoidal"),
       doc="kinematic engine: folds as a sum of 1-4 Gaussian bumps, or one sinusoid"),
    _p("throw_taper", float, "run", 0.5, 0.0, 1.0,
       doc="kinematic engine: how far the throw dies out along the fault: throw(s) = throw_m "
           "(1 - taper (s/L)^2) at distance s from the fault's centre of half-length L "
           "(0 = constant throw, 1 = zero at the tips)"),
    _p("population_faults", int, "run", 12, 1, 100,
       doc="kinematic engine: faults of the population that takes up base_stretch (the DEM "
           "grows its own)"),
    _p("population_throw_exponent", float, "run", 1.0, 0.3, 3.0,
       doc="kinematic engine: the population's throws follow a power law, cumulative number "
           "N(> t) ~ t^-c with c this exponent (larger: more small faults)"),
    # ---- per run: the planar engine only ([model] engine = "planar") ------------------------
    _p("planar_faults", int, "run", 2, 0, 20,
       doc="planar engine: number of faults of a run (each crosses the whole section)"),
    _p("planar_dip_min_deg", float, "run", 40.0, 10.0, 89.0, unit="deg",
       doc="planar engine: smallest fault dip; each fault's dip is uniform in "
           "[planar_dip_min_deg, planar_dip_max_deg]"),
    _p("planar_dip_max_deg", float, "run", 80.0, 10.0, 89.0, unit="deg",
       doc="planar engine: largest fault dip (at least planar_dip_min_deg)"),
    _p("planar_throw_min_m", float, "run", 10.0, 0.0, 1.0e4, unit="m",
       doc="planar engine: smallest fault throw (constant along a fault); each fault's throw "
           "is uniform in [planar_throw_min_m, planar_throw_max_m]"),
    _p("planar_throw_max_m", float, "run", 60.0, 0.0, 1.0e4, unit="m",
       doc="planar engine: largest fault throw (at least planar_throw_min_m, at most 0.6 "
           "model height)"),
    _p("planar_reverse_fraction", float, "run", 0.5, 0.0, 1.0,
       doc="planar engine: probability that a fault is reverse (else normal)"),
    _p("planar_tilt_deg", float, "run", 2.0, 0.0, 30.0, unit="deg",
       doc="planar engine: largest dip of the planar shear s2(x) = e0 + f x applied after the "
           "folds: f = tan(a), a uniform in [-planar_tilt_deg, planar_tilt_deg]"),
    # ---- per run: layering ---------------------------------------------------------------
    _p("n_layers", int, "run", 48, 1, 250, doc="number of pre-kinematic layers"),
    _p("layer_thickness_cv", float, "run", 0.0, 0.0, 0.9,
       doc="coefficient of variation of layer thicknesses (0 = equal thicknesses)"),
    # ---- per run: mechanics (demseis.dem.Material) ---------------------------------------
    # Config ranges: physical for sedimentary rock, affordable (a seed-scale run takes at most
    # 2x the default's steps) and stable (benchmarks/ranges_sweep.py; docs/dem.md, "Stability
    # over the declared ranges"). ``stage``: the wider domain the DEM accepts when called
    # directly (analytic tests at zero gravity or damping, derived softer weak layers).
    _p("density_kg_m3", float, "run", 2500.0, 2000.0, 3000.0, unit="kg/m^3",
       stage=(500.0, 6000.0, False, False),
       doc="element density; mass = density * pi r^2 (unit thickness); sedimentary rocks"),
    _p("kn_n_m", float, "run", 1.0e10, 5.0e9, 3.0e10, unit="N/m", stage=(1.0e6, 1.0e13, False, False),
       doc="normal contact stiffness Kn (dt ~ sqrt(density / Kn): 3e10 at density 2000 is 1.9x "
           "the default's steps)"),
    _p("ks_ratio", float, "run", 0.5, 0.2, 1.0, stage=(0.0, 2.0, True, False),
       doc="shear stiffness Ks / Kn"),
    _p("friction", float, "run", 0.4, 0.2, 0.8, stage=(0.0, 2.0, False, False),
       doc="contact friction coefficient mu (slider |Fs| <= C0 + mu Fn): clay-rich shale 0.2 "
           "to Byerlee's 0.6-0.85"),
    _p("cohesion_n", float, "run", 5.0e7, 0.0, 1.4e9, unit="N", stage=(0.0, 1.0e12, False, False),
       doc="contact cohesion C0, from the ductile drape (5e7) to the calibrated brittle cover "
           "(1.4e9; 2e9 breaks in near-vertical fissures, and a bonded cover at the strong "
           "corner of the other ranges blew up)"),
    _p("bond_strain", float, "run", 0.005, 0.001, 0.005, stage=(1.0e-5, 1.0, False, True),
       doc="bond-breaking strain r0 of the bonded and brittle models: a bond breaks when "
           "d - R > r0 R (unused by the frictional model)"),
    _p("contact_model", str, "run", "frictional", choices=("frictional", "bonded", "brittle"),
       doc="frictional-cohesive (cohesion heals: ductile), bonded (tensile bonds), or brittle "
           "(bonds broken by tension or shear, cohesion lost with them: faults localise)"),
    _p("damping_scale", float, "run", 3.0e8, 3.0e8, 5.0e8, unit="N s/m per s",
       stage=(0.0, 1.0e13, False, False),
       doc="global viscous damping eta = dt * damping_scale (1e8 let the strongest, most "
           "cohesive corner of the ranges blow up; up to 5e8 the smallest element sinks faster "
           "than the basement at every corner and dip 80 deg; the paper's 3e9 detaches the "
           "hanging wall)"),
    _p("gravity_m_s2", float, "run", 9.81, 9.78, 9.83, unit="m/s^2",
       stage=(0.0, 100.0, False, False), doc="gravity (Earth's, equator to pole)"),
    # ---- per run: rock properties (demseis.seismic.PropertyModel scalars) ---------------
    _p("gardner_a", float, "run", 310.0, 100.0, 1000.0,
       doc="Gardner coefficient: rho = a Vp^b (rho in kg/m^3, Vp in m/s)"),
    _p("gardner_b", float, "run", 0.25, 0.1, 0.5, doc="Gardner exponent b"),
    _p("vp_scatter", float, "run", 0.03, 0.0, 0.2,
       doc="relative std of per-element Vp around the layer Vp"),
    _p("rho_scatter", float, "run", 0.01, 0.0, 0.2, doc="relative std of per-element density"),
    _p("gaussian_sigma_cells", float, "run", 0.7, 0.0, 5.0, unit="cells",
       doc="std of the Gaussian smoothing of the property grids (0 = off)"),
    _p("median_size_cells", int, "run", 3, 1, 9, unit="cells",
       doc="width of the square median filter, odd (1 = off)"),
    # ---- per run: the beds of the strata rendering (demseis.seismic.BedModel) -------------
    _p("bed_thickness_median_m", float, "run", 4.0, 0.1, 100.0, unit="m",
       doc="strata: median bed thickness (lognormal); most beds below the tuning thickness"),
    _p("bed_thickness_log_sigma", float, "run", 0.8, 0.0, 3.0,
       doc="strata: standard deviation of ln(bed thickness)"),
    _p("bed_thickness_min_m", float, "run", 0.5, 0.1, 100.0, unit="m",
       doc="strata: thinnest bed (at most the median)"),
    _p("bed_thickness_max_m", float, "run", 40.0, 0.1, 1000.0, unit="m",
       doc="strata: thickest bed (at least the median)"),
    _p("facies_contrast", float, "run", 0.15, 0.0, 1.0,
       doc="strata: difference of ln(impedance) between the two facies of a layer's beds"),
    _p("facies_switch_probability", float, "run", 0.3, 0.0, 1.0,
       doc="strata: probability that a bed's facies differs from the one below"),
    _p("fluctuation_sigma", float, "run", 0.03, 0.0, 0.5,
       doc="strata: std of the bed-to-bed ln(impedance) fluctuation (Laplace, AR(1))"),
    _p("fluctuation_ar1", float, "run", 0.5, 0.0, 0.99,
       doc="strata: lag-one correlation (bed index) of that fluctuation"),
    _p("vp_gradient_per_km", float, "run", 0.05, 0.0, 1.0,
       doc="strata: relative increase of Vp per km of burial (reference depth)"),
    _p("rho_gradient_per_km", float, "run", 0.015, 0.0, 0.5,
       doc="strata: relative increase of density per km of burial"),
    _p("lateral_amplitude", float, "run", 0.03, 0.0, 0.2,
       doc="strata: relative std of Vp along a bed (density a quarter of it)"),
    _p("lateral_density_amplitude", float, "run", 0.0, 0.0, 0.2,
       doc="strata: relative std of density along a bed, added to the quarter of "
           "lateral_amplitude: reflector strength varies along a bed with no time shift"),
    _p("lateral_correlation_m", float, "run", 27.0, 1.0, 1.0e6, unit="m",
       doc="strata: correlation length of the variation along a bed"),
    _p("boundary_undulation", float, "run", 0.1, 0.0, 0.17,
       doc="strata: std of a bed boundary's vertical wobble, as a fraction of the thinner bed"),
    _p("undulation_correlation_m", float, "run", 100.0, 1.0, 1.0e6, unit="m",
       doc="strata: correlation length of that wobble"),
    _p("fault_zone_impedance", float, "run", 0.0, -0.5, 0.5,
       doc="strata rendering: relative change of the impedance in a fault core (damage 2; "
           "half of it in the damage zone, damage 1): negative dims the fault zone"),
    # ---- per sample: rendering -----------------------------------------------------------
    _p("freq_hz", float, "sample", 40.0, 1.0, 500.0, unit="Hz", doc="Ricker peak frequency"),
    _p("snr_db", float, "sample", INF, -40.0, INF, unit="dB",
       doc="signal-to-noise ratio 20 log10(rms signal / rms noise); inf = no noise"),
    _p("noise_kind", str, "sample", "white", choices=("white", "band", "coloured"),
       doc="white, band-limited (the signal's band) or coloured (noise_slope) noise"),
    _p("imaging", str, "sample", "1d", choices=IMAGING,
       doc="1-D convolution, or the 2-D dip-limited point-spread function (docs/seismic.md)"),
    _p("psf_max_angle_deg", float, "sample", 30.0, 1.0, 90.0, unit="deg",
       doc="maximum illumination angle of the PSF; 90 = no dip limit"),
    _p("psf_aperture_m", float, "sample", 0.0, 0.0, 1.0e6, unit="m",
       doc="survey half-aperture L of the PSF: angle <= arctan(L / depth); 0 = no limit"),
    # ---- per sample: wavelet (demseis.seismic.Wavelet) -------------------------------------
    _p("wavelet", str, "sample", "ricker", choices=("ricker", "ormsby", "butterworth"),
       doc="source wavelet family: ricker (peak freq_hz), or the ormsby or butterworth "
           "band-pass of band_octaves centred on freq_hz"),
    _p("band_octaves", float, "sample", 2.0, 0.5, 5.0, unit="octave",
       doc="pass band of the ormsby and butterworth wavelets (unused by the ricker)"),
    _p("wavelet_phase", str, "sample", "zero", choices=("zero", "minimum"),
       doc="zero: the family's amplitude spectrum at zero phase; minimum: its minimum-phase "
           "wavelet (causal)"),
    _p("wavelet_phase_deg", float, "sample", 0.0, -180.0, 180.0, unit="deg",
       doc="constant-phase rotation of the wavelet (w cos phi - H[w] sin phi)"),
    # ---- per sample: noise and processing (demseis.seismic.processing) -----------------------
    _p("noise_slope", float, "sample", 1.0, 0.0, 4.0,
       doc="coloured noise: power spectral density proportional to f^-noise_slope along the "
           "vertical axis (1 pink, 2 brown)"),
    _p("linear_noise_snr_db", float, "sample", INF, -40.0, INF, unit="dB",
       doc="coherent linear noise: SNR against the clean section; inf = none"),
    _p("linear_noise_slope", float, "sample", 2.0, -50.0, 50.0, unit="samples/trace",
       doc="time shift per trace of the coherent linear noise (its apparent dip)"),
    _p("trace_gain_jitter", float, "sample", 0.0, 0.0, 2.0,
       doc="standard deviation of the natural log of each trace's gain; 0 = none"),
    _p("time_gain_jitter", float, "sample", 0.0, 0.0, 2.0,
       doc="standard deviation of the natural log of a gain varying smoothly down the section "
           "(bright and dim intervals, heavier-tailed amplitudes); 0 = none"),
    _p("footprint_amplitude", float, "sample", 0.0, 0.0, 1.0,
       doc="relative amplitude of acquisition-footprint stripes along the traces; 0 = none"),
    _p("footprint_period_traces", float, "sample", 10.0, 2.0, 1000.0, unit="traces",
       doc="period of the footprint stripes"),
    _p("agc_window_samples", int, "sample", 0, 0, 10000, unit="samples",
       doc="automatic gain control window (centred, per trace); 0 = off"),
    _p("clip_percentile", float, "sample", 100.0, 50.0, 100.0, unit="percent",
       doc="amplitudes clipped at this percentile of |amplitude|; 100 = off"),
    _p("quantise_bits", int, "sample", 0, 0, 16, unit="bits",
       doc="quantise the section to 2^bits levels (8: a display image); 0 = off"),
    # ---- [model]: the DEM box and run control -------------------------------------------
    _p("width_m", float, "sweep", 2400.0, 100.0, 1.0e5, unit="m", section="model",
       doc="model box width"),
    _p("height_m", float, "sweep", 1200.0, 50.0, 1.0e5, unit="m", section="model",
       doc="model box height"),
    _p("radius_min_m", float, "sweep", 12.5, 0.1, 1.0e3, unit="m", section="model",
       doc="smallest element radius (radii log-uniform in [min, max])"),
    _p("radius_max_m", float, "sweep", 25.0, 0.1, 1.0e3, unit="m", section="model",
       doc="largest element radius"),
    _p("engine", str, "sweep", "dem", choices=ENGINES, section="model",
       doc="dem: grow faults in the DEM; kinematic: a FaultSeg-style generator (random "
           "layered reflectivity, optional folds, planar or listric faults displaced "
           "geometrically; no particles, >= 20x faster; demseis.generator.engines.kinematic); "
           "planar: the published FaultSeg recipe as a control (random reflectivity, Gaussian "
           "folds growing with depth, planar shear, planar faults of constant throw; "
           "demseis.generator.engines.planar)"),
    _p("n_snapshots", int, "sweep", 4, 2, 1000, section="model",
       doc="snapshots per run, equally spaced in throw; the first is the undeformed reference"),
    _p("sedimentation", bool, "sweep", True, section="model",
       doc="fill hanging-wall accommodation with growth layers"),
    _p("wall_speed_m_s", float, "sweep", 5.0, 1.0e-3, 100.0, unit="m/s", section="model",
       doc="speed of the moving basement along dip (model time)"),
    _p("pack_library", int, "sweep", 0, 0, 100000, section="model",
       doc="dem engine: settled packs the runs draw from, each settled once per box, radii and "
           "settling material and cached on disk (DEMSEIS_PACK_CACHE, default "
           "~/.cache/demseis/packs); every run still draws its own layering, rock and faults; "
           "0 = every run settles its own pack"),
    # ---- [grid] ----------------------------------------------------------------------------
    _p("cell_m", float, "sweep", 10.0, 0.5, 1000.0, unit="m", section="grid",
       doc="raster cell size (seismic and labels share the grid)"),
    # ---- [output] --------------------------------------------------------------------------
    _p("impedance", bool, "sweep", False, section="output",
       doc="also store the smoothed impedance grid"),
    _p("domain", str, "sweep", "depth", choices=("depth", "time"), section="output",
       doc="sections and labels in depth cells, or on a two-way-time axis (a list or a "
           "choice: each run its own, docs/seismic.md)"),
    _p("dt_s", float, "sweep", 0.002, 1.0e-4, 0.02, unit="s", section="output",
       doc="time-domain sample interval"),
    _p("time_window", str, "sweep", "model", choices=("model", "rock"), section="output",
       doc="time-domain record length: model (the whole model fits at the slowest Vp the "
           "sweep allows, deep samples past a fast column's rock are empty) or rock (what every "
           "column fills at the fastest Vp, as a survey's fixed record: rock below it is cut)"),
    _p("trace_spacing_m", float, "sweep", 0.0, 0.0, 1000.0, unit="m", section="output",
       doc="distance between the output traces (columns), independent of the model and its "
           "elements, as a survey's trace spacing (12.5-25 m); 0 = the grid cell (grid.cell_m)"),
    _p("rendering", str, "sweep", "strata", choices=RENDERINGS, section="output",
       doc="elements: rock properties per DEM element, rasterised on the grid (the paper's "
           "mode); strata: a fine stratigraphy (beds below 1 m to tens of metres) looked up at "
           "each point's reference coordinates (demseis.generator.render.survey, docs/seismic.md)"),
    _p("block_smoothing_m", float, "sweep", 0.0, 0.0, 1000.0, unit="m", section="output",
       doc="dem engine, strata rendering: 0 = each point follows its own element's map (every "
           "element's motion, granular rearrangement and slip between small blocks included; "
           "docs/dem.md, \"Reference coordinates\"); > 0 = the elements' displacement smoothed "
           "over this radius within the blocks the fault label bounds, so that the beds break "
           "only at labelled faults (demseis.dem.reference.block_reference_map)"),
    _p("surface_median_m", float, "sweep", 0.0, 0.0, 1.0e4, unit="m", section="output",
       doc="strata rendering: the top of the rock levelled by a running median over this "
           "width before the space above it is filled (demseis.generator.render.survey."
           "level_surface): the bumps and pits of a few elements would otherwise make the "
           "surface a rough, broken reflector; a fault scarp wider than half of it is kept; "
           "0 = the surface as the elements leave it"),
    _p("velocity_median_m", float, "sweep", 0.0, 0.0, 1.0e4, unit="m", section="output",
       doc="strata rendering: two-way times from the running median of Vp over this width "
           "along the section, the impedance kept (demseis.generator.render.survey."
           "smooth_velocity): pits and bumps of a few elements at the surface and narrow "
           "columns of slow sediment between elements would otherwise shift single traces "
           "by up to a few samples against their neighbours (statics that break every "
           "reflector below them); 0 = every trace's own velocity"),
    _p("strata_dz_m", float, "sweep", 1.0, 0.05, 1.0, unit="m", section="output",
       doc="strata rendering: vertical step of the stratigraphy lookup, at most (the grid cell "
           "is split into an odd number of steps no larger)"),
    # ---- [labels]: how the strain and displacement of the elements become labels -----------
    # (demseis.labels.LabelConfig; strains are the dimensionless maximum shear strain gamma_max,
    # lengths in cells are cells of the grid the labels are drawn on; docs/labels.md)
    _label("strain_measure", str, "cumulative", choices=("total", "cumulative"),
           doc="total (finite strain against the element's first appearance) or cumulative (sum "
               "of the incremental gamma_max between snapshots: keeps strain later deformation "
               "undid); which one drives the masks"),
    _label("neighbour_method", str, "radius", choices=("radius", "knn"),
           doc="neighbours of an element in the reference state: within neighbour_radius_factor "
               "(r_i + r_j), or the neighbour_k nearest centres"),
    _label("neighbour_radius_factor", float, 1.5, 0.5, 5.0, lo_open=True,
           doc="radius method: multiple of the summed radii (1 catches touching disks only)"),
    _label("neighbour_k", int, 10, 3, 64, doc="knn method: number of neighbours"),
    _label("min_neighbours", int, 3, 2, 64,
           doc="elements with fewer neighbours are invalid (strain NaN); at most neighbour_k "
               "for knn"),
    _label("fault_threshold", float, 0.5, 0.0, 100.0, lo_open=True,
           doc="strain_band method: gamma_max at or above which a cell is fault"),
    _label("damage_threshold", float, 0.3, 0.0, 100.0, lo_open=True,
           doc="strain_band method: gamma_max at or above which a cell is damage zone (at most "
               "fault_threshold)"),
    _label("min_component_cells", int, 30, 0, 1_000_000, unit="cells",
           doc="strain_band method: smaller 8-connected fault and damage components are dropped"),
    _label("smooth_sigma_cells", float, 1.0, 0.0, 20.0, unit="cells",
           doc="strain_band method: Gaussian sigma of the strain before thresholding (0 = none)"),
    _label("thickness_cells", float, 1.0, 0.0, 50.0, unit="cells",
           doc="0 keeps the thresholded band; t >= 1 thins the mask to its centre line and grows "
               "it to a band of about t cells"),
    _label("centreline_window_cells", int, 15, 1, 201, unit="cells",
           doc="the centre line's branches are moving-averaged over this many cells and side "
               "branches up to this long pruned (1 = raw skeleton); both methods"),
    _label("method", str, "slip_trace", choices=LABEL_METHODS,
           doc="slip_trace: crests of localised shear kept where the displacement jumps across "
               "them (instance ids, slip, dip, sense); strain_band: the thresholded strain "
               "band's centre line (the labels of demseis <= 0.1)"),
    _label("min_slip_m", float, None, 0.0, 1.0e4, lo_open=True, unit="m", optional=True,
           doc="slip_trace: smallest displacement jump across a crest cell for it to be fault; "
               "unset = one grid cell"),
    _label("ridge_threshold", float, 0.15, 0.0, 100.0, lo_open=True,
           doc="slip_trace: smallest shear strain of a crest cell (of the smoothed displacement "
               "on the grid)"),
    _label("ridge_sigma_cells", float, 2.0, 0.0, 20.0, unit="cells",
           doc="slip_trace: Gaussian sigma of the displacement smoothing before its shear"),
    _label("strand_sigma_cells", float, 0.7, 0.0, 20.0, unit="cells",
           doc="slip_trace: sigma of a finer crest search for the other slip surfaces of a wide "
               "shear zone (strands: more than 2 cells from a trace, jump >= min_slip_m); 0 = "
               "none"),
    _label("slip_offset_cells", int, 3, 2, 20, unit="cells",
           doc="slip_trace: the jump is the largest u(+k) - u(-k) along the normal for k = 2 to "
               "this"),
    _label("min_trace_cells", int, 15, 1, 1_000_000, unit="cells",
           doc="slip_trace: shorter crest and trace pieces are dropped"),
    _label("link_angle_deg", float, 35.0, 0.0, 90.0, unit="deg",
           doc="slip_trace: branches meeting at a junction within this angle of a straight line "
               "are one fault"),
    _label("link_gap_cells", int, 0, 0, 50, unit="cells",
           doc="slip_trace: crest gaps up to about this many cells are bridged before thinning"),
    _label("min_dip_deg", float, 15.0, 0.0, 90.0, unit="deg",
           doc="slip_trace: crest cells dipping less (direction fitted over 9 x 9 cells) are not "
               "fault (bedding-parallel slip); 0 keeps every dip"),
    _label("core_halfwidth_cells", int, 5, 0, 10, unit="cells",
           doc="slip_trace: the fault core (damage class 2) is the fault mask and the shear "
               "band's width at half maximum around each trace, up to this many cells either "
               "side; 0 = the fault mask alone"),
    _label("damage_width_ratio", float, 1.0, 0.0, 100.0,
           doc="slip_trace: damage-zone total width as a multiple of the local slip"),
    _label("damage_max_width_m", float, 200.0, 0.0, 1.0e5, unit="m",
           doc="slip_trace: largest damage-zone total width"),
    _label("fault_style", str, "picks", choices=FAULT_STYLES,
           doc="the stored fault target: picks (one smooth one-pixel line per fault on the "
               "output grid where its throw is at least min_throw_samples, as an interpreter "
               "picks) or traces (the method's traces on the output grid, grown to "
               "thickness_cells)"),
    _label("min_throw_samples", float, 1.0, 0.0, 100.0, unit="samples",
           doc="picks: smallest throw, in output samples, where a fault is drawn"),
    _label("pick_smooth_px", float, 2.0, 0.0, 20.0, unit="px",
           doc="picks: Gaussian sigma of the line along the fault"),
    _label("pick_max_gap_px", int, 4, 0, 100, unit="px",
           doc="picks: gaps of a fault's pixels up to this long are bridged"),
    _label("pick_min_length_px", int, 5, 1, 10_000, unit="px",
           doc="picks: shorter pieces of a line are dropped"),
    _label("throw_from", str, "slip", choices=("slip", "offset"),
           doc="picks: a pixel's throw is the slip's (slip sin(dip) at the output sampling) or "
               "the reflectors' offset across it on the reference map (needs [output] "
               "rendering = strata)"),
    _label("offset_window_traces", int, 3, 1, 9, unit="traces",
           doc="picks with throw_from = offset: the odd number of neighbouring trace pairs an "
               "offset is measured over"),
    _label("offset_faults", bool, False,
           doc="picks with throw_from = offset: visible offsets no fault label explains become "
               "faults, so every offset the section shows has a label"),
    _label("offset_min_rows", int, 10, 2, 1000, unit="rows",
           doc="with offset_faults: the fewest output rows such a fault spans"),
    _label("fault_uncertain", bool, False,
           doc="also store fault_uncertain: where the fault label and the reflectors' visible "
               "offsets disagree (1: a labelled pixel offset less than min_throw_samples, 2: an "
               "offset of at least that with no label within 2 px), for training that leaves "
               "them out of the loss (demseis train --ignore); needs rendering = strata"),
)

#: every declared parameter by name
PARAMS: dict[str, Param] = {p.name: p for p in _DECLARED}
if len(PARAMS) != len(_DECLARED):  # pragma: no cover - a declaration error
    raise RuntimeError("a parameter is declared twice in demseis.parameters")

#: the ``[sweep]`` parameters that take a fixed value, a list or a distribution
SCENARIO: dict[str, Param] = {k: p for k, p in PARAMS.items() if p.level in ("run", "sample")}

#: :class:`demseis.dem.Material` field -> parameter name
MATERIAL_FIELDS: dict[str, str] = {
    "density_kg_m3": "density_kg_m3", "kn_n_m": "kn_n_m", "ks_ratio": "ks_ratio",
    "friction": "friction", "cohesion_n": "cohesion_n", "bond_strain": "bond_strain",
    "model": "contact_model", "damping_scale": "damping_scale", "gravity_m_s2": "gravity_m_s2",
}

#: fields of :class:`demseis.seismic.BedModel` (the same names)
BED_FIELDS: tuple[str, ...] = (
    "bed_thickness_median_m", "bed_thickness_log_sigma", "bed_thickness_min_m",
    "bed_thickness_max_m", "facies_contrast", "facies_switch_probability", "fluctuation_sigma",
    "fluctuation_ar1", "vp_gradient_per_km", "rho_gradient_per_km", "lateral_amplitude",
    "lateral_density_amplitude", "lateral_correlation_m", "boundary_undulation",
    "undulation_correlation_m")

#: scalar fields of :class:`demseis.seismic.PropertyModel` (the same names)
PROPERTY_FIELDS: tuple[str, ...] = ("gardner_a", "gardner_b", "vp_scatter", "rho_scatter",
                                    "gaussian_sigma_cells", "median_size_cells")


@dataclass(frozen=True)
class Stored:
    """A per-sample value a store holds that is derived, not drawn (a column of its ``params`` table)."""

    name: str
    dtype: str
    level: str
    unit: str
    doc: str


#: derived per-sample values in a store's ``params`` table (besides the run and sample parameters)
STORED: tuple[Stored, ...] = (
    Stored("run_id", "int32", "run", "", "DEM run index (the store shard)"),
    Stored("sample_in_run", "int32", "sample", "", "sample index within its run"),
    Stored("snapshot", "int16", "snapshot", "", "snapshot index (0 = undeformed reference)"),
    Stored("step", "int64", "snapshot", "", "integrator step at which the snapshot was taken"),
    Stored("throw_m", "float32", "snapshot", "m", "basement throw reached at the snapshot"),
    Stored("throw_target_m", "float32", "run", "m", "final basement throw of the run (0 without "
           "a basement fault)"),
    Stored("fault_x_m", "float32", "run", "m", "x where the basement fault meets the base; "
           "-1 if the run has none"),
    Stored("n_elements", "int32", "snapshot", "", "elements in the snapshot (deposits included)"),
    Stored("noise_seed", "uint64", "sample", "", "seed of the sample's noise Generator"),
    Stored("n_basement_faults", "int8", "run", "", "basement faults of the run (0-5; 0 for structure none; "
           "the planar engine: its faults, 0-20)"),
    Stored("has_fault", "uint8", "snapshot", "", "1 if the fault label has any fault cell"),
    Stored("n_faults", "int16", "snapshot", "", "fault instances in the label"),
    Stored("max_slip_m", "float32", "snapshot", "m", "largest slip on the labelled traces"),
    Stored("dem_attempt", "int8", "run", "", "0: the DEM run as configured (always 0 for the "
           "kinematic engine); k >= 1: the earlier tries went unstable and stabilised try k "
           "finished: tries 1-2 with the basement at wall_speed_m_s / 2^k, tries 3-5 as 0-2 "
           "with relaxed deposits"),
) + tuple(
    Stored(f"fault{k}_{field}", dtype, level, unit, f"basement fault {k} (by x): {doc}; -1 if "
           "the run has fewer faults")
    for k in range(MAX_BASEMENT_FAULTS)
    for field, dtype, level, unit, doc in (
        ("kind", "int8", "run", "", "kind code (0 normal, 1 reverse, 2 listric)"),
        ("x_m", "float32", "run", "m", "x where it meets the top of the basement"),
        ("dip_deg", "float32", "run", "deg", "dip at the top of the basement"),
        ("dip_direction", "int8", "run", "", "dip direction code (0 right, 1 left)"),
        ("throw_target_m", "float32", "run", "m", "final throw"),
        ("throw_m", "float32", "snapshot", "m", "throw reached at the snapshot"),
    )
)


#: per-sample columns of a store whose ``[output]`` sampling varies from run to run (only then:
#: a store of one sampling keeps the table it had)
SAMPLING_STORED: tuple[Stored, ...] = (
    Stored("dt_s", "float32", "run", "s", "sample interval of the section (0: a depth section)"),
    Stored("trace_spacing_m", "float32", "run", "m", "distance between the section's traces"),
)


def declared_dataclass(name: str, params: Iterable[Param], *, module: str, doc: str,
                       bases: tuple[type, ...] = (),
                       extra: Sequence[tuple[str, type, Any]] = ()) -> type:
    """A frozen dataclass ``name`` with one field per declaration of ``params`` (its kind, or
    ``kind | None`` where it is optional, and its default), then the ``extra`` fields, made in
    ``module`` (so that it pickles by reference: configs and run parameters travel to the
    dask workers)."""
    fields = [(p.name, p.kind | None if p.optional else p.kind, dataclasses.field(default=p.default))
              for p in params]
    cls = dataclasses.make_dataclass(name, [*fields, *extra], bases=bases, frozen=True)
    cls.__module__ = module
    cls.__doc__ = doc
    return cls


def param(name: str) -> Param:
    """The declaration of ``name``; :class:`KeyError` naming the known ones."""
    try:
        return PARAMS[name]
    except KeyError:
        raise KeyError(f"no parameter {name!r}; declared: {', '.join(sorted(PARAMS))}") from None


def check(name: str, value: Any, where: str, error: type[DemseisError]) -> Any:
    """Check ``value`` against the declaration of ``name`` (see :meth:`Param.check_value`)."""
    return PARAMS[name].check_value(value, where, error)


def table_rows() -> list[tuple[str, str, str, str, str, str, str]]:
    """(name, section, level, unit, range, default, doc) of every parameter, then the stored ones."""
    rows = []
    for p in _DECLARED:
        default = p.default
        if default is None:
            text = "unset"
        elif isinstance(default, bool):
            text = "true" if default else "false"
        elif isinstance(default, float):
            text = _fmt(default)
        else:
            text = str(default)
        doc = p.doc
        if p.stage() is not p:
            doc += f" (engine-level calls accept {p.stage().range_text()})"
        rows.append((p.name, p.section, p.level, p.unit, p.range_text(), text, doc))
    return rows


def markdown_table() -> str:
    """The parameter tables of ``docs/parameters.md`` (generated; a test compares them)."""
    lines = ["| name | section | level | unit | range | default | description |",
             "| --- | --- | --- | --- | --- | --- | --- |"]
    for row in table_rows():
        lines.append("| " + " | ".join(f"`{row[0]}`" if i == 0 else c.replace("|", "\\|")
                                        for i, c in enumerate(row)) + " |")
    lines += ["", "Stored per sample in the store's `params` table besides the run and sample parameters above:", "",
              "| name | dtype | level | unit | description |", "| --- | --- | --- | --- | --- |"]
    for s in STORED:
        lines.append(f"| `{s.name}` | {s.dtype} | {s.level} | {s.unit} | {s.doc} |")
    lines += ["", "Stored too where `[output] dt_s` or `trace_spacing_m` is given several values "
              "(each run draws its own):", "",
              "| name | dtype | level | unit | description |", "| --- | --- | --- | --- | --- |"]
    for s in SAMPLING_STORED:
        lines.append(f"| `{s.name}` | {s.dtype} | {s.level} | {s.unit} | {s.doc} |")
    return "\n".join(lines) + "\n"


def text_table() -> str:
    """The table ``demseis params`` prints."""
    rows = [("name", "section", "level", "unit", "range", "default", "description")]
    rows += table_rows()
    widths = [max(len(r[i]) for r in rows) for i in range(6)]
    return "\n".join("  ".join(c.ljust(w) for c, w in zip(r[:6], widths)) + "  " + r[6]
                     for r in rows) + "\n"
