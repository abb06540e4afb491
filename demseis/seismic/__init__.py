"""demseis.seismic: properties, rasterisation, impedance, reflectivity, wavelets, noise.

The per-snapshot render the generator does::

    layer_props = draw_layer_properties(n_layers_total, model, rng)
    vp_e, rho_e = element_properties(snap.ids, snap.layer, layer_props, model, seed)
    vp_g, rho_g = property_grids(snap.xy, snap.radius, vp_e, rho_e, snap.layer, grid, model)
    sections = synthetic_sections(vp_g, rho_g, grid.cell_m, freqs_hz)        # (nf, nz, nx)
    # or, imaged through a dip-limited 2-D point-spread function:
    sections = psf_sections(vp_g, rho_g, grid.cell_m, freqs_hz, max_angle_deg=30.0)
    # or, with beds finer than the elements (the ``strata`` rendering), looked up at the
    # reference coordinates (x0, y0) of each cell:
    strata = draw_strata(unit_bottom_m, unit_top_m, layer_props, width_m, BedModel(), rng)
    vp_g, rho_g = strata_properties(strata, x0, y0, unit)
    noisy = add_noise(sections[k], snr_db, "band", rng)

See ``docs/seismic.md`` for the physics, conventions and measured accuracy and speed.
"""

from demseis.seismic.forward import (
    coarse_velocity,
    convolve,
    depth_to_time,
    impedance,
    interface_times,
    reflectivity,
    synthetic_sections,
    time_axis,
)
from demseis.seismic.noise import add_noise, rms, snr_db
from demseis.seismic.properties import (
    LayerProperties,
    PropertyModel,
    draw_layer_properties,
    element_properties,
    property_grids,
    smooth,
)
from demseis.seismic.imaging import ImagingMode, imaged_sections, imaging_mode
from demseis.seismic.psf import psf_sections
from demseis.seismic.raster import rasterise
from demseis.seismic.strata import BedModel, Strata, draw_strata, strata_properties
from demseis.seismic.processing import Processing, process
from demseis.seismic.wavelet import Wavelet, estimate_wavelet, ricker

__all__ = [
    "rasterise", "ricker", "reflectivity", "impedance", "convolve", "PropertyModel",
    "LayerProperties", "draw_layer_properties", "element_properties", "property_grids", "smooth",
    "synthetic_sections", "interface_times", "coarse_velocity", "time_axis", "depth_to_time",
    "add_noise", "rms", "snr_db", "psf_sections", "imaged_sections", "ImagingMode", "imaging_mode", "BedModel",
    "Strata", "draw_strata", "strata_properties", "Wavelet", "estimate_wavelet", "Processing",
    "process",
]
