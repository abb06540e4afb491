"""Particle plots of DEM snapshots (like the paper's Figure 2). Imports matplotlib lazily."""

from __future__ import annotations

import os
from collections.abc import Sequence

import numpy as np

from demseis.dem.types import Snapshot


def plot_snapshots(snaps: Sequence[Snapshot], path: str | os.PathLike, *, n_groups: int = 6,
                   layers_per_group: int | None = None, ncols: int = 2, dpi: int = 110,
                   title: str | None = None) -> None:
    """Draw each snapshot as disks coloured by layer group; deposited disks semi-transparent.

    Parameters
    ----------
    snaps : snapshots of one run.
    path : output image file (.png).
    n_groups : number of colours cycled over layer groups.
    layers_per_group : layers sharing one colour (default: n_pre_kinematic_layers / 12).
    ncols : panels per row.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.collections import EllipseCollection

    pre = snaps[0].layer[~snaps[0].deposited]
    n_layers = int(pre.max()) + 1 if pre.size else 1
    lpg = layers_per_group or max(1, n_layers // 12)
    cmap = plt.get_cmap("tab10")
    xmin = min(float(np.min(s.xy[:, 0] - s.radius)) for s in snaps)
    xmax = max(float(np.max(s.xy[:, 0] + s.radius)) for s in snaps)
    ymin = min(float(np.min(s.xy[:, 1] - s.radius)) for s in snaps)
    ymax = max(float(np.max(s.xy[:, 1] + s.radius)) for s in snaps)
    nrows = int(np.ceil(len(snaps) / ncols))
    aspect = (ymax - ymin) / (xmax - xmin)
    fig, axes = plt.subplots(nrows, ncols, figsize=(7.5 * ncols, 7.5 * aspect * nrows + 0.6),
                             squeeze=False)
    for ax in axes.ravel()[len(snaps):]:
        ax.axis("off")
    for ax, s in zip(axes.ravel(), snaps):
        grp = np.where(s.deposited, s.layer - n_layers, s.layer // lpg)
        colors = cmap((grp % n_groups) / 10.0 + 0.001)
        if s.deposited.any():
            colors[s.deposited] = plt.get_cmap("Set2")((grp[s.deposited] % 8) / 8.0 + 0.001)
            colors[s.deposited, 3] = 0.55
        d = 2 * s.radius
        ec = EllipseCollection(d, d, np.zeros_like(d), units="xy", offsets=s.xy,
                               transOffset=ax.transData, facecolors=colors, edgecolors="none")
        ax.add_collection(ec)
        ax.set_xlim(xmin, xmax)
        ax.set_ylim(ymin, ymax)
        ax.set_aspect("equal")
        ax.set_title(f"snapshot {s.index}: throw {s.throw_m:.0f} m, {s.n} elements", fontsize=9)
        ax.tick_params(labelsize=7)
    if title:
        fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=dpi)
    plt.close(fig)
