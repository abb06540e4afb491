"""Figure: one snapshot imaged by the 1-D convolution and by the 2-D PSF at two angles.

Usage::

    demseis generate --preset quick --out quick.zarr          # DEM snapshots (90 s)
    PYTHONPATH=. python scripts/psf_figure.py --store quick.zarr --run 0 \\
        --out docs/figures/seismic_psf.png

Without ``--store`` the last snapshot of the kinematic toy sequence of
:mod:`demseis_dev.toys` is drawn (the title says which). Top row: the section at
``--freq`` Hz (depth domain, no noise) in 1-D and with the PSF at the two ``--angles``;
bottom row: the image of one point scatterer (one cell of 20 % higher density in a constant
medium: a +R / -R pair of reflection coefficients) by
each, i.e. the point-spread function itself (each panel scaled to its own peak, the peak
relative to the 1-D one written in it).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # demseis_dev: the checkout's

import numpy as np

from demseis.seismic import (PropertyModel, draw_layer_properties, element_properties,
                             imaged_sections, property_grids)
from demseis.types import Grid


def _snapshots(store: str | None, run: int, cell_m: float):
    """(snapshots, grid, source) of a store's run (its sweep's grid) or of the toy sequence."""
    if store is None:
        from demseis_dev.toys import faulted_sequence

        snaps = faulted_sequence(2500.0, 1100.0, n_layers=24, throw_m=300.0,
                                 rng=np.random.default_rng(0))
        return (snaps, Grid.covering(2500.0, 1100.0, cell_m),
                "kinematic toy fault (demseis_dev.toys), not DEM")
    from demseis.datasets import open_store, read_particles
    from demseis.generator.config.settings import parse_config

    model = parse_config(dict(open_store(store).attrs)["config"], source=store).model
    return (read_particles(store, run), Grid.covering(model.width_m, model.height_m, cell_m),
            f"DEM snapshot ({Path(store).name}, run {run})")


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--store", default=None, help="demseis store with particle snapshots")
    p.add_argument("--run", type=int, default=0)
    p.add_argument("--freq", type=float, default=30.0)
    p.add_argument("--angles", type=float, nargs=2, default=(45.0, 20.0))
    p.add_argument("--cell-m", type=float, default=10.0)
    p.add_argument("--out", default="docs/figures/seismic_psf.png")
    a = p.parse_args()

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    snaps, grid, source = _snapshots(a.store, a.run, a.cell_m)
    snap = snaps[-1]
    model = PropertyModel().validate()
    rng = np.random.default_rng(1)
    lp = draw_layer_properties(max(int(s.layer.max()) for s in snaps) + 1, model, rng)
    vp_e, rho_e = element_properties(snap.ids, snap.layer, lp, model, seed=1)
    vp_g, rho_g = property_grids(snap.xy, snap.radius, vp_e, rho_e, snap.layer, grid, model)

    # a point scatterer: one cell of higher impedance in a constant medium (its top and
    # bottom make a +R / -R pair, the image of a thin bed at a point)
    n, show = 201, 41                     # a large grid, its central 41 x 41 cells shown
    vp_p = np.full((n, n), 3000.0)
    rho_p = np.full((n, n), 2300.0)
    rho_p[n // 2, n // 2] *= 1.2

    cases = [("1-D convolution", "1d", 90.0)] + [
        (f"PSF, max angle {ang:g}°", "psf", ang) for ang in a.angles]
    fig, axes = plt.subplots(2, 3, figsize=(14, 6.4),
                             gridspec_kw={"height_ratios": [grid.nz / grid.nx * 3.0, 1.2]})
    sec = [imaged_sections(kind, vp_g, rho_g, grid.cell_m, [a.freq], psf_max_angle_deg=ang)[0]
           for _, kind, ang in cases]
    c0 = (n - show) // 2
    pt = [imaged_sections(kind, vp_p, rho_p, a.cell_m, [a.freq], psf_max_angle_deg=ang)[0]
          [c0:c0 + show, c0:c0 + show] for _, kind, ang in cases]
    clip = float(np.percentile(np.abs(sec[0]), 99.5))
    clip_p = float(np.abs(pt[0]).max())
    ext = [0.0, grid.nx * grid.cell_m / 1e3, grid.nz * grid.cell_m / 1e3, 0.0]
    half = show * a.cell_m / 2.0
    for j, (title, _, _) in enumerate(cases):
        ax = axes[0, j]
        ax.imshow(sec[j], cmap="gray_r", vmin=-clip, vmax=clip, extent=ext, aspect="equal",
                  interpolation="bilinear")
        ax.set_title(title)
        ax.set_xlabel("x (km)")
        ax = axes[1, j]
        peak = float(np.abs(pt[j]).max())
        ax.imshow(pt[j], cmap="seismic", vmin=-peak, vmax=peak, aspect="equal",
                  extent=[-half, half, half, -half], interpolation="bilinear")
        ax.set_xlabel("x (m)")
        ax.text(0.02, 0.04, f"peak / 1-D = {peak / clip_p:.2f}", transform=ax.transAxes,
                fontsize=8, backgroundcolor="w")
        rms = np.sqrt(np.mean(sec[j] ** 2) / np.mean(sec[0] ** 2))
        axes[0, j].text(0.01, 0.02, f"rms / 1-D = {rms:.2f}", transform=axes[0, j].transAxes,
                        color="k", backgroundcolor="w", fontsize=8)
    axes[0, 0].set_ylabel("depth (km)")
    axes[1, 0].set_ylabel("z (m)\npoint scatterer")
    fig.suptitle(f"{source}, throw {snap.throw_m:.0f} m, {a.freq:g} Hz Ricker, depth domain, "
                 f"{grid.cell_m:g} m cells")
    fig.tight_layout()
    Path(a.out).parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(a.out, dpi=110)
    print(f"wrote {a.out}")


if __name__ == "__main__":
    main()
