"""Figures of the seismic stage (``python scripts/seismic_figures.py --out docs/figures``).

- ``seismic_frequency_sequence.png``: like the paper's Figure 6, sections at 20/40/60 Hz
  (rows) across the deformation sequence (columns);
- ``seismic_properties.png``: raw rasterised impedance, smoothed impedance, reflectivity and
  the 40 Hz section of the last snapshot (like Figures 4-5);
- ``seismic_tuning.png``: Ricker wavelets and the wedge tuning curves with lambda/4 marked.

Snapshots come from an ``.npz`` written from DEM snapshots with
:func:`demseis.types.save_snapshots` or, without one, from the kinematic toy sequence of
:func:`demseis_dev.toys.faulted_sequence` (the figure title says which).
matplotlib is imported inside the functions.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # demseis_dev: the checkout's

import numpy as np

from demseis.seismic.forward import impedance, reflectivity, synthetic_sections
from demseis.seismic.properties import (PropertyModel, draw_layer_properties, element_properties,
                                        fill_background, property_grids)
from demseis.seismic.raster import rasterise
from demseis.types import Grid, load_snapshots


def _extent_km(grid: Grid) -> list[float]:
    """imshow extent (left, right, bottom, top) in km: x across, depth below the grid top."""
    return [grid.x0_m / 1e3, (grid.x0_m + grid.nx * grid.cell_m) / 1e3,
            grid.nz * grid.cell_m / 1e3, 0.0]


def render_sequence(snaps, grid: Grid, freqs_hz, model: PropertyModel, seed: int = 0):
    """Sections (n_snap, nf, nz, nx) and the last snapshot's grids, as the generator renders."""
    n_layers = max(int(s.layer.max()) for s in snaps) + 1
    lp = draw_layer_properties(n_layers, model, np.random.default_rng(seed))
    out = []
    for s in snaps:
        vp_e, rho_e = element_properties(s.ids, s.layer, lp, model, seed)
        vp_g, rho_g = property_grids(s.xy, s.radius, vp_e, rho_e, s.layer, grid, model)
        out.append(synthetic_sections(vp_g, rho_g, grid.cell_m, freqs_hz))
    return np.stack(out), (vp_e, rho_e, vp_g, rho_g)


def frequency_sequence_figure(snaps, grid: Grid, out: Path, source: str,
                              freqs_hz=(20.0, 40.0, 60.0), model: PropertyModel | None = None):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    model = PropertyModel() if model is None else model
    secs, _ = render_sequence(snaps, grid, freqs_hz, model)
    n = len(snaps)
    ext = _extent_km(grid)
    fig, axes = plt.subplots(len(freqs_hz), n, figsize=(2.6 * n, 1.75 * len(freqs_hz) + 0.6),
                             sharex=True, sharey=True, constrained_layout=True)
    axes = np.atleast_2d(axes)
    for r, f in enumerate(freqs_hz):
        clip = np.percentile(np.abs(secs[:, r]), 99)
        for c, s in enumerate(snaps):
            ax = axes[r, c]
            ax.imshow(secs[c, r], cmap="seismic_r", vmin=-clip, vmax=clip, extent=ext,
                      aspect="auto", interpolation="bilinear")
            if r == 0:
                ax.set_title(f"throw {s.throw_m:.0f} m", fontsize=9)
            if c == 0:
                ax.set_ylabel(f"{f:.0f} Hz\ndepth (km)", fontsize=9)
            if r == len(freqs_hz) - 1:
                ax.set_xlabel("x (km)", fontsize=9)
            ax.tick_params(labelsize=7)
    fig.suptitle(f"Zero-phase Ricker sections (depth domain, {grid.cell_m:g} m cells) across the "
                 f"deformation sequence; snapshots: {source}", fontsize=10)
    fig.savefig(out, dpi=100)
    plt.close(fig)


def properties_figure(snap, grid: Grid, out: Path, source: str, model: PropertyModel | None = None,
                      freq_hz: float = 40.0):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    model = PropertyModel() if model is None else model
    lp = draw_layer_properties(int(snap.layer.max()) + 1, model, np.random.default_rng(0))
    vp_e, rho_e = element_properties(snap.ids, snap.layer, lp, model, 0)
    vals = np.column_stack([vp_e, rho_e])
    raw, count = rasterise(snap.xy, snap.radius, vals, grid)
    z_raw = raw[:, :, 0] * raw[:, :, 1]
    filled = fill_background(raw.copy(), count, snap.xy, vals, snap.layer.astype(np.int64), grid,
                             model.background)
    vp_g, rho_g = property_grids(snap.xy, snap.radius, vp_e, rho_e, snap.layer, grid, model)
    z = impedance(vp_g, rho_g)
    refl = reflectivity(z)
    sec = synthetic_sections(vp_g, rho_g, grid.cell_m, [freq_hz])[0]
    ext = _extent_km(grid)
    panels = [
        ("rasterised impedance (empty cells white)", z_raw / 1e6, "viridis", None),
        ("background-filled, Gaussian + median", z / 1e6, "viridis", None),
        ("reflectivity (Z2 - Z1)/(Z2 + Z1)", refl, "seismic_r", np.percentile(np.abs(refl), 99)),
        (f"{freq_hz:g} Hz Ricker section", sec, "seismic_r", np.percentile(np.abs(sec), 99)),
    ]
    zlim = (np.nanpercentile(filled[:, :, 0] * filled[:, :, 1], 1) / 1e6,
            np.nanpercentile(filled[:, :, 0] * filled[:, :, 1], 99) / 1e6)
    fig, axes = plt.subplots(2, 2, figsize=(11, 5.2), sharex=True, sharey=True,
                             constrained_layout=True)
    for ax, (title, img, cmap, clip) in zip(axes.ravel(), panels):
        kw = dict(vmin=-clip, vmax=clip) if clip is not None else dict(vmin=zlim[0], vmax=zlim[1])
        im = ax.imshow(img, cmap=cmap, extent=ext, aspect="auto", interpolation="nearest", **kw)
        ax.set_title(title, fontsize=9)
        fig.colorbar(im, ax=ax, shrink=0.8, label="Z (10^6 kg m^-2 s^-1)" if clip is None else "")
    for ax in axes[:, 0]:
        ax.set_ylabel("depth (km)")
    for ax in axes[-1]:
        ax.set_xlabel("x (km)")
    fig.suptitle(f"From elements to seismic, last snapshot (throw {snap.throw_m:.0f} m); "
                 f"snapshots: {source}", fontsize=10)
    fig.savefig(out, dpi=130)
    plt.close(fig)


def tuning_figure(out: Path, freqs_hz=(20.0, 40.0, 60.0), v_m_s: float = 3000.0):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from demseis.seismic.wavelet import ricker

    fig, (a0, a1) = plt.subplots(1, 2, figsize=(11, 3.8), constrained_layout=True)
    dt = 0.0005
    for f in freqs_hz:
        w = ricker(f, dt, 0.2)
        t = (np.arange(w.size) - w.size // 2) * dt * 1e3
        a0.plot(t, w, label=f"{f:g} Hz")
    a0.set_xlabel("time (ms)")
    a0.set_title("demseis.seismic.ricker (zero phase, peak 1)")
    a0.legend()
    cell = 1.0
    top, nmax = 120, 90
    nz, nx = 2 * top + nmax, nmax + 1
    vp = np.full((nz, nx), v_m_s)
    rho = np.full((nz, nx), 2400.0)
    for j in range(nx):
        rho[top:top + j, j] = 2100.0
    secs = synthetic_sections(vp, rho, cell, list(freqs_hz))
    r = abs((2100 - 2400) / (2100 + 2400))
    for k, f in enumerate(freqs_hz):
        peak = np.max(np.abs(secs[k]), axis=0) / r
        line, = a1.plot(np.arange(nx) * cell, peak, label=f"{f:g} Hz")
        a1.axvline(v_m_s / (4 * f), color=line.get_color(), ls="--", lw=0.8)
        a1.axvline(v_m_s * np.sqrt(1.5) / (np.pi * f) / 2, color=line.get_color(), ls=":", lw=0.8)
    a1.set_xlabel("wedge thickness (m)")
    a1.set_ylabel("peak |amplitude| / |R|")
    a1.set_title(f"wedge tuning, V = {v_m_s:g} m/s\n"
                 "(dashed: V/4f; dotted: Ricker theory 0.39 V/2f)", fontsize=10)
    a1.legend()
    fig.savefig(out, dpi=130)
    plt.close(fig)


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--npz", help="DEM snapshots (.npz); default: kinematic toy sequence")
    p.add_argument("--out", default="docs/figures", help="output folder")
    p.add_argument("--width-m", type=float, default=5000.0)
    p.add_argument("--height-m", type=float, default=2770.0)
    a = p.parse_args(argv)
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    if a.npz:
        snaps = load_snapshots(a.npz)
        source = "DEM (branch dem, simulate)"
    else:
        from demseis_dev.toys import faulted_sequence

        snaps = faulted_sequence(a.width_m, a.height_m, dip_deg=60.0,
                                 rng=np.random.default_rng(0))
        source = "kinematic toy fault (not DEM)"
    grid = Grid.covering(a.width_m, a.height_m, 10.0)
    frequency_sequence_figure(snaps, grid, out / "seismic_frequency_sequence.png", source)
    properties_figure(snaps[-1], grid, out / "seismic_properties.png", source)
    tuning_figure(out / "seismic_tuning.png")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
