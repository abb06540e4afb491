"""Imaging modes: how property grids become seismic sections, as a table.

An :class:`ImagingMode` is a function from depth-domain Vp and density grids to one section per
frequency, and the names of the per-sample parameters it reads (its options). The table
:data:`demseis.registry.IMAGING` maps the ``imaging`` parameter's values to modes; the
dispatcher :func:`imaged_sections` looks a mode up and calls it. A sweep groups the samples of
a snapshot by :meth:`ImagingMode.key` and images each group once for all its frequencies.

Built in: ``"1d"``, trace-by-trace convolution (:func:`demseis.seismic.synthetic_sections`),
and ``"psf"``, the dip-limited 2-D point-spread function (:func:`demseis.seismic.psf_sections`,
options ``psf_max_angle_deg`` and ``psf_aperture_m``). A new mode is one registration::

    from demseis.registry import IMAGING
    from demseis.seismic.imaging import ImagingMode

    def smeared(vp_g, rho_g, cell_m, freqs_hz, domain, *, t_s=None):
        ...  # (nf, H, W) float32
    IMAGING.register("smeared", ImagingMode(smeared))

after which ``imaging = "smeared"`` is a valid ``[sweep]`` value.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from demseis.registry import IMAGING
from demseis.seismic.forward import synthetic_sections
from demseis.seismic.psf import psf_sections


def _title(name: str) -> Callable[[Mapping[str, Any]], str]:
    return lambda values: name


@dataclass(frozen=True)
class ImagingMode:
    """One imaging mode.

    Attributes
    ----------
    image : ``image(vp_g, rho_g, cell_m, freqs_hz, domain, *, t_s=None, **options)`` ->
        (nf, H, W) float32 sections, with the signature of
        :func:`demseis.seismic.synthetic_sections` plus the mode's options as keywords.
    options : names of the per-sample parameters the mode reads (declared in
        :mod:`demseis.parameters`); passed to ``image`` by name.
    key : the options' values normalised, so that samples with equal keys share one ``image``
        call (default: the option values as given).
    title : a short description of a sample's imaging for figure titles.
    """

    image: Callable[..., np.ndarray]
    options: tuple[str, ...] = ()
    key: Callable[[Mapping[str, Any]], tuple] | None = None
    title: Callable[[Mapping[str, Any]], str] = field(default=_title("imaged"))

    def key_of(self, values: Mapping[str, Any]) -> tuple:
        """The grouping key of a sample whose per-sample parameters are ``values``."""
        if self.key is not None:
            return self.key(values)
        return tuple(values[name] for name in self.options)


def _psf_aperture(aperture_m: float) -> float:
    """The PSF's half-aperture: the parameter's 0 means no limit."""
    return aperture_m if aperture_m > 0 else math.inf


def _psf_image(vp_g: np.ndarray, rho_g: np.ndarray, cell_m: float, freqs_hz: Sequence[float],
               domain: str = "depth", *, t_s: np.ndarray | None = None,
               psf_max_angle_deg: float = 30.0, psf_aperture_m: float = 0.0,
               col_step_m: float | None = None, rows_per_cell: int = 1) -> np.ndarray:
    return psf_sections(vp_g, rho_g, cell_m, freqs_hz, psf_max_angle_deg, domain, t_s=t_s,
                        aperture_m=_psf_aperture(psf_aperture_m), col_step_m=col_step_m,
                        rows_per_cell=rows_per_cell)


ONE_D = ImagingMode(synthetic_sections, title=_title("1-D"))
PSF = ImagingMode(
    _psf_image, options=("psf_max_angle_deg", "psf_aperture_m"),
    key=lambda v: (float(v["psf_max_angle_deg"]), _psf_aperture(float(v["psf_aperture_m"]))),
    title=lambda v: f"PSF {float(v['psf_max_angle_deg']):g}°")


def imaging_mode(name: str) -> ImagingMode:
    """The mode registered as ``name`` (an InputError listing the modes if there is none)."""
    return IMAGING.get(name)


def imaged_sections(imaging: str, vp_g: np.ndarray, rho_g: np.ndarray, cell_m: float,
                    freqs_hz: float | Sequence[float], domain: str = "depth", /, *,
                    t_s: np.ndarray | None = None, col_step_m: float | None = None,
                    rows_per_cell: int = 1, **options: Any) -> np.ndarray:
    """Sections of the property grids by the mode named ``imaging``, one per frequency.

    ``options`` are the mode's per-sample parameters (e.g. ``psf_max_angle_deg``); those it
    does not declare are ignored (so a sample's whole parameter dict may be passed), those it
    declares and are absent take the mode's defaults. ``col_step_m``: the distance between
    the grids' columns where it is not ``cell_m`` (rows finer than the traces: the ``strata``
    rendering); passed only then, so a mode used only on square cells need not accept it.
    ``rows_per_cell`` (passed only when not 1): in depth, the grids' rows split the output
    cells in this odd number and the section is wanted at the cells' centres only.
    """
    mode = imaging_mode(imaging)
    kw = {k: options[k] for k in mode.options if k in options}
    if col_step_m is not None:
        kw["col_step_m"] = col_step_m
    if rows_per_cell != 1:
        kw["rows_per_cell"] = rows_per_cell
    return mode.image(vp_g, rho_g, cell_m, freqs_hz, domain, t_s=t_s, **kw)
