"""Measures of the ``strata`` stratigraphy and of the sections it gives, against field targets.

- the two section measures of ``../shared/field/README.md`` (F3 at 4 ms: 0.92 and 34) are
  :func:`demseis.evaluation.realism.adjacent_trace_correlation` and ``zero_crossings``;
- :func:`flat_section`: a noise-free time section of an undeformed stratigraphy (reference
  coordinates = section coordinates), traces every ``dx_m``, a fine vertical grid;
- :func:`column_reflectivity`: the reflection coefficients of one densely sampled column, in
  depth and binned in two-way time, and their excess kurtosis and spectral slope;
- :func:`default_setup`: the stratigraphy the docs measure (the generator's default pile:
  48 layers over 1200 m, 5 km wide).
"""

from __future__ import annotations

import numpy as np

from demseis.evaluation.realism import adjacent_trace_correlation, zero_crossings
from demseis.seismic import (BedModel, PropertyModel, Strata, draw_layer_properties, draw_strata,
                             interface_times, reflectivity, strata_properties, synthetic_sections)


def default_setup(seed: int = 0, model: BedModel | None = None, n_layers: int = 48,
                  height_m: float = 1200.0, width_m: float = 5000.0) -> Strata:
    """Strata of ``n_layers`` equal pre-kinematic layers over ``height_m`` (default properties)."""
    rng = np.random.default_rng(seed)
    props = draw_layer_properties(n_layers, PropertyModel(), rng)
    edges = np.linspace(0.0, height_m, n_layers + 1)
    return draw_strata(edges[:-1], edges[1:], props, width_m, model or BedModel(), rng)


def flat_section(strata: Strata, freq_hz: float, dx_m: float = 25.0, dz_m: float = 0.5,
                 dt_s: float = 0.004, top_m: float | None = None,
                 bottom_m: float = 0.0) -> np.ndarray:
    """Time section (nt, nx) of the undeformed stratigraphy between ``bottom_m`` and ``top_m``.

    Traces at x = (j + 1/2) dx_m across the width; cells of ``dz_m`` down from ``top_m``
    (default the top of the highest unit). The time axis keeps only samples at least one
    wavelet half-width (1.35 / f) from t = 0 and from the shallowest column bottom, so no
    sample sees the edges of the grid.
    """
    top = float(strata.unit_top_m.max()) if top_m is None else float(top_m)
    nz = int(round((top - bottom_m) / dz_m))
    nx = int(strata.width_m // dx_m)
    y = top - (np.arange(nz) + 0.5) * dz_m
    x = (np.arange(nx) + 0.5) * dx_m
    vp, rho = strata_properties(strata, np.broadcast_to(x, (nz, nx)),
                                np.broadcast_to(y[:, None], (nz, nx)))
    t_bottom, _ = interface_times(vp, dz_m)
    half = 1.35 / freq_hz
    t_s = np.arange(np.ceil(half / dt_s), np.floor((t_bottom[-1].min() - half) / dt_s)) * dt_s
    return synthetic_sections(vp, rho, dz_m, [freq_hz], domain="time", t_s=t_s)[0]


def _excess_kurtosis(r: np.ndarray) -> float:
    c = r - r.mean()
    return float((c ** 4).mean() / (c ** 2).mean() ** 2 - 3.0)


def column_reflectivity(strata: Strata, x_m: float = 0.0, dz_m: float = 0.25,
                        dt_s: float = 0.001, band_hz: tuple[float, float] = (10.0, 80.0),
                        top_m: float | None = None, bottom_m: float = 0.0) -> dict:
    """Reflectivity of the column at ``x_m``, sampled every ``dz_m`` from ``top_m`` down.

    Returns a dict: ``kurtosis_depth`` (excess kurtosis of all depth samples),
    ``kurtosis_interfaces`` (of the non-zero coefficients only), ``kurtosis_time`` (of the
    coefficients summed into ``dt_s`` bins of two-way time at the column's Vp) and
    ``spectral_slope`` (least-squares slope of log power against log frequency of that time
    series over ``band_hz``, from a periodogram averaged in 64 log-spaced bands), plus
    ``rms_time`` (rms of the time series) and ``n_interfaces``.
    """
    top = float(strata.unit_top_m.max()) if top_m is None else float(top_m)
    nz = int(round((top - bottom_m) / dz_m))
    y = top - (np.arange(nz) + 0.5) * dz_m
    vp, rho = strata_properties(strata, np.full(nz, float(x_m)), y)
    r = reflectivity(vp * rho)[:-1]
    t_bottom, _ = interface_times(vp[:, None], dz_m)
    t_if = t_bottom[:-1, 0]
    nt = int(t_if[-1] / dt_s) + 1
    rt = np.bincount((t_if / dt_s).astype(np.int64), weights=r, minlength=nt)
    spec = np.abs(np.fft.rfft(rt - rt.mean())) ** 2
    f = np.fft.rfftfreq(rt.size, dt_s)
    edges = np.geomspace(band_hz[0], band_hz[1], 65)
    idx = np.digitize(f, edges) - 1
    keep = (idx >= 0) & (idx < 64)
    p = np.bincount(idx[keep], weights=spec[keep], minlength=64)
    c = np.bincount(idx[keep], minlength=64)
    fc = np.bincount(idx[keep], weights=f[keep], minlength=64)
    ok = c > 0
    slope = np.polyfit(np.log(fc[ok] / c[ok]), np.log(p[ok] / c[ok]), 1)[0]
    nonzero = r[r != 0.0]
    return {
        "kurtosis_depth": _excess_kurtosis(r),
        "kurtosis_interfaces": _excess_kurtosis(nonzero),
        "kurtosis_time": _excess_kurtosis(rt),
        "spectral_slope": float(slope),
        "rms_time": float(np.sqrt(np.mean(rt ** 2))),
        "n_interfaces": int(nonzero.size),
    }


__all__ = ["adjacent_trace_correlation", "column_reflectivity", "default_setup", "flat_section",
           "zero_crossings"]
