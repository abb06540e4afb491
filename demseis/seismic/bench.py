"""Speed of the whole per-snapshot seismic render (``demseis bench seismic``)."""

from __future__ import annotations

import os
import time

import numpy as np

from demseis.seismic.demo import faulted_sequence
from demseis.seismic.forward import synthetic_sections
from demseis.seismic.grid import Grid
from demseis.seismic.properties import (
    PropertyModel,
    draw_layer_properties,
    element_properties,
    fill_background,
    smooth,
)
from demseis.seismic.raster import rasterise


def _median_ms(fn, repeats: int) -> tuple[float, float]:
    """Median wall-clock and process-CPU milliseconds of ``fn()`` over ``repeats`` calls."""
    wall, cpu = [], []
    for _ in range(repeats):
        t0, c0 = time.perf_counter(), time.process_time()
        fn()
        wall.append(time.perf_counter() - t0)
        cpu.append(time.process_time() - c0)
    return float(np.median(wall) * 1e3), float(np.median(cpu) * 1e3)


def run_benchmark(nx: int = 512, nz: int = 288, cell_m: float = 10.0, repeats: int = 7,
                  freqs_hz: tuple[float, ...] = (20.0, 40.0, 60.0), seed: int = 0,
                  npz: str | None = None) -> dict:
    """Time the render of one faulted toy snapshot (``nx`` x ``nz`` cells of ``cell_m``).

    The snapshot is the last (throw 450 m) of :func:`demseis.seismic.demo.faulted_sequence`
    over ``nx cell_m`` x ``nz cell_m`` m (about 11,800 disks at 512 x 288). Timed, as medians
    of ``repeats`` runs after one warm-up (Numba compiled and cached): element properties,
    rasterisation, background fill, smoothing of both grids, the convolution for one frequency
    and for all of ``freqs_hz``, and the whole render (properties -> grids -> sections) for one
    frequency and for all. ``ms_per_section_*`` divides the whole render by the number of
    frequencies. Runs single-threaded Numba code (as in the dask workers).
    """
    rng = np.random.default_rng(seed)
    width, height = nx * cell_m, nz * cell_m
    if npz is None:
        snap = faulted_sequence(width, height, rng=rng)[-1]
        source = "kinematic toy sequence, last snapshot"
    else:
        from demseis.seismic.figures import load_snapshots

        snap = load_snapshots(npz)[-1]
        source = f"{npz}, last snapshot"
    grid = Grid.covering(width, height, cell_m)
    model = PropertyModel().validate()
    lp = draw_layer_properties(int(snap.layer.max()) + 1, model, rng)
    f1 = (freqs_hz[0],)

    def props():
        return element_properties(snap.ids, snap.layer, lp, model, seed)

    vp_e, rho_e = props()
    values = np.column_stack([vp_e, rho_e])

    def rast():
        return rasterise(snap.xy, snap.radius, values, grid)

    mean, count = rast()

    def background():
        return fill_background(mean.copy(), count, snap.xy, values, snap.layer.astype(np.int64),
                               grid, model.background)

    filled = background()

    def smoothing():
        return smooth(filled[:, :, 0], model), smooth(filled[:, :, 1], model)

    vp_g, rho_g = smoothing()

    def render(freqs):
        from demseis.seismic.properties import property_grids
        ve, re = element_properties(snap.ids, snap.layer, lp, model, seed)
        vg, rg = property_grids(snap.xy, snap.radius, ve, re, snap.layer, grid, model)
        return synthetic_sections(vg, rg, cell_m, freqs)

    render(freqs_hz)  # warm-up: Numba compilation / cache load
    nf = len(freqs_hz)
    comp = {
        "element_properties": _median_ms(props, repeats),
        "rasterise": _median_ms(rast, repeats),
        "background": _median_ms(background, repeats),
        "smooth_vp_rho": _median_ms(smoothing, repeats),
        "convolution_1f": _median_ms(lambda: synthetic_sections(vp_g, rho_g, cell_m, f1),
                                     repeats),
        f"convolution_{nf}f": _median_ms(
            lambda: synthetic_sections(vp_g, rho_g, cell_m, freqs_hz), repeats),
    }
    full1 = _median_ms(lambda: render(f1), repeats)
    fulln = _median_ms(lambda: render(freqs_hz), repeats)
    return {
        "benchmark": "seismic_render",
        "nz": grid.nz,
        "nx": grid.nx,
        "cell_m": cell_m,
        "snapshot": source,
        "n_elements": int(snap.ids.shape[0]),
        "freqs_hz": list(freqs_hz),
        "repeats": repeats,
        "loadavg_1min": round(os.getloadavg()[0], 2),
        "ms_snapshot_1f": round(full1[0], 2),
        f"ms_snapshot_{nf}f": round(fulln[0], 2),
        "ms_per_section_1f": round(full1[0], 2),
        f"ms_per_section_{nf}f": round(fulln[0] / nf, 2),
        "cpu_ms_snapshot_1f": round(full1[1], 2),
        f"cpu_ms_snapshot_{nf}f": round(fulln[1], 2),
        "components_ms": {k: round(v[0], 2) for k, v in comp.items()},
        "components_cpu_ms": {k: round(v[1], 2) for k, v in comp.items()},
    }
