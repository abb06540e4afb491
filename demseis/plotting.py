"""All matplotlib drawing of demseis: ``demseis preview`` (PNG figures of one run, like the
paper's Figures 2-6), ``demseis plot`` (one stored sample) and :func:`plot_snapshots` (particle
plots of DEM snapshots, like the paper's Figure 2).

matplotlib is imported by :func:`_mpl` when a figure is drawn: it takes ~0.6 s to import, and the
figures select the Agg backend when they are drawn, not when this module is imported (importing
it must not switch the backend of an interactive session)."""

from __future__ import annotations

import os
from collections.abc import Sequence
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import numpy as np

from demseis.datasets import open_store, read_particles, read_sample, shard_status
from demseis.errors import ConfigError, InputError
from demseis.evaluation.fieldio import read_mask, read_section
from demseis.evaluation.realism_report import report_rows
from demseis.evaluation.segyfile import cube_geometry, is_segy, read_cube_line, read_segy_section
from demseis.generator.config.layout import grid_of
from demseis.generator.config.sampling import plan_run
from demseis.generator.config.settings import PRESETS, Config, load_config, stored_config
from demseis.generator.engines import get_engine, require_particles
from demseis.generator.engines.runsetup import property_model_of, run_properties
from demseis.labels import displacement_history, label_maps, strain_history
from demseis.schema import sample_array
from demseis.seismic import (element_properties, imaging_mode, property_grids, rasterise,
                             synthetic_sections)
from demseis.types import Snapshot


def _mpl() -> SimpleNamespace:
    """matplotlib on the Agg backend, imported at the first figure (see the module docstring):
    ``mpl`` (the package), ``plt`` (pyplot), ``EllipseCollection``, ``ListedColormap``."""
    import matplotlib  # lazy: see the module docstring

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt  # lazy (and with it matplotlib.collections and .colors)

    return SimpleNamespace(mpl=matplotlib, plt=plt,
                           EllipseCollection=matplotlib.collections.EllipseCollection,
                           ListedColormap=matplotlib.colors.ListedColormap)


def noise_title(snr_db: float, kind: str) -> str:
    """How a sample's noise reads in a title: ``SNR 10 dB (white)``, or ``no noise``."""
    snr = float(snr_db)
    return "no noise" if not np.isfinite(snr) else f"SNR {snr:.3g} dB ({kind})"

def _load_source(source: str, run: int) -> tuple[Config, list[Snapshot]]:
    path = Path(source)
    if path.is_dir():
        root = open_store(path)
        cfg = stored_config(dict(root.attrs)["config"], source=str(path))
        require_particles(cfg, "preview")
        if run >= cfg.sweep.n_runs:
            raise InputError(f"--run {run}: the store has runs 0..{cfg.sweep.n_runs - 1}")
        if shard_status(path)[run] != 1:
            raise InputError(f"--run {run} is not done in store {source!r}")
        return cfg, read_particles(path, run)
    if source in PRESETS:
        cfg = load_config(preset=source)
    elif path.is_file():
        cfg = load_config(path)
    else:
        raise ConfigError(f"{source!r} is neither a config file, a preset ({', '.join(PRESETS)}) nor a store")
    if run >= cfg.sweep.n_runs:
        raise InputError(f"--run {run}: the config has runs 0..{cfg.sweep.n_runs - 1}")
    require_particles(cfg, "preview")
    return cfg, list(get_engine(cfg.model.engine).simulate(cfg, plan_run(cfg, run)).snapshots)


def _draw_particles(ax: Any, snap: Snapshot, colors: np.ndarray, *, alpha_deposited: float = 0.45,
                    values: np.ndarray | None = None, cmap: str | None = None) -> Any:
    d = 2 * snap.radius
    kw: dict[str, Any] = {}
    if values is None:
        fc = colors.copy()
        fc[snap.deposited, 3] = alpha_deposited
        kw["facecolors"] = fc
    coll = _mpl().EllipseCollection(d, d, np.zeros_like(d), units="xy", offsets=snap.xy,
                             offset_transform=ax.transData, linewidths=0, **kw)
    if values is not None:
        coll.set_array(values)
        coll.set_cmap(cmap)
    ax.add_collection(coll)
    ax.set_aspect("equal")
    return coll


def layer_colors(layer: np.ndarray, n_pre: int) -> np.ndarray:
    """RGBA per element: alternating warm/cool bands for pre-kinematic layers, greys for growth."""
    cmap = _mpl().mpl.colormaps["tab20"]
    rgba = np.asarray(cmap((layer % 20) / 20.0))
    growth = layer >= n_pre
    rgba[growth, :3] = np.where((layer[growth] % 2)[:, None] == 0, 0.55, 0.8)
    return rgba


def preview(source: str, out_dir: str | Path, *, run: int = 0) -> list[Path]:
    """Write the preview figures of run ``run`` of ``source`` into ``out_dir``; return the paths."""
    plt = _mpl().plt

    cfg, snaps = _load_source(source, run)
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    spec = plan_run(cfg, run)
    p = spec.params
    n_pre = int(p["n_layers"])
    grid = grid_of(cfg)
    W, H = cfg.model.width_m, cfg.model.height_m
    extent = (grid.x0_m, grid.x0_m + grid.nx * grid.cell_m, grid.top_m - grid.nz * grid.cell_m, grid.top_m)
    title = f"run {run}: dip {p['dip_deg']:.0f}°, throw {p['throw_m']:.0f} m"
    written: list[Path] = []

    def save(fig: Any, name: str) -> None:
        path = out / name
        fig.savefig(path, dpi=110, bbox_inches="tight")
        plt.close(fig)
        written.append(path)

    # Figure 2: particle evolution
    ncol = min(3, len(snaps))
    nrow = int(np.ceil(len(snaps) / ncol))
    fig, axes = plt.subplots(nrow, ncol, figsize=(5.2 * ncol, 2.9 * nrow), squeeze=False)
    for ax, s in zip(axes.flat, snaps):
        _draw_particles(ax, s, layer_colors(s.layer, n_pre))
        ax.set_xlim(0, W)
        ax.set_ylim(min(0.0, float((s.xy[:, 1] - s.radius).min())), H * 1.02)
        ax.set_title(f"snapshot {s.index}: throw {s.throw_m:.0f} m, step {s.step}", fontsize=9)
    for ax in list(axes.flat)[len(snaps):]:
        ax.axis("off")
    fig.suptitle(f"Particle evolution ({title}); translucent = syn-tectonic deposits")
    save(fig, "fig2_particles.png")

    # Figure 3: particle Vp and density
    model = property_model_of(cfg, p)
    n_total = max(int(s.layer.max()) for s in snaps) + 1
    layer_props, elem_seed = run_properties(cfg, run, model, n_total)
    last = snaps[-1]
    vp_e, rho_e = element_properties(last.ids, last.layer, layer_props, model, elem_seed)
    fig, axes = plt.subplots(1, 2, figsize=(13, 3.4))
    for ax, vals, lab in ((axes[0], vp_e, "Vp (m/s)"), (axes[1], rho_e, "density (kg/m³)")):
        coll = _draw_particles(ax, last, np.zeros((last.n, 4)), values=vals, cmap="viridis")
        ax.set_xlim(0, W)
        ax.set_ylim(min(0.0, float(last.xy[:, 1].min())), H * 1.02)
        fig.colorbar(coll, ax=ax, label=lab, shrink=0.8)
    fig.suptitle(f"Particle-scale properties after deformation ({title})")
    save(fig, "fig3_particle_properties.png")

    # Figure 4: gridded fields before filtering
    raw_mean, _ = rasterise(last.xy, last.radius, np.stack([vp_e, rho_e], axis=1), grid)
    fig, axes = plt.subplots(1, 3, figsize=(16, 3.2))
    for ax, img, lab in ((axes[0], raw_mean[..., 0], "Vp (m/s)"), (axes[1], raw_mean[..., 1], "density (kg/m³)"),
                         (axes[2], raw_mean[..., 0] * raw_mean[..., 1], "impedance (kg/m²/s)")):
        im = ax.imshow(img, extent=extent, cmap="viridis", aspect="equal")
        fig.colorbar(im, ax=ax, label=lab, shrink=0.8)
    fig.suptitle("Gridded fields before filtering (white = no element covers the cell centre)")
    save(fig, "fig4_gridded.png")

    # Figure 5: section with the particles overlaid, and labels
    vp_g, rho_g = property_grids(last.xy, last.radius, vp_e, rho_e, last.layer, grid, model)
    fmax = max(r.freq_hz for r in spec.renders)
    sec = synthetic_sections(vp_g, rho_g, grid.cell_m, [fmax])[0]
    clip = float(np.percentile(np.abs(sec), 99)) or 1.0
    hist = strain_history(snaps, cfg.labels)
    maps = label_maps(last, hist[-1], grid, cfg.labels, displacement=displacement_history(snaps)[-1])
    fig, axes = plt.subplots(1, 3, figsize=(18, 3.4))
    axes[0].imshow(sec, extent=extent, cmap="seismic", vmin=-clip, vmax=clip, aspect="equal")
    axes[0].set_title(f"(a) {fmax:g} Hz section")
    axes[1].imshow(sec, extent=extent, cmap="gray", vmin=-clip, vmax=clip, aspect="equal")
    _draw_particles(axes[1], last, np.concatenate([layer_colors(last.layer, n_pre)[:, :3],
                                                   np.full((last.n, 1), 0.35)], axis=1), alpha_deposited=0.2)
    axes[1].set_xlim(extent[0], extent[1])
    axes[1].set_ylim(extent[2], extent[3])
    axes[1].set_title("(b) with the final DEM elements overlaid")
    axes[2].imshow(sec, extent=extent, cmap="gray", vmin=-clip, vmax=clip, aspect="equal")
    dmg = np.ma.masked_equal(maps["damage"], 0)
    axes[2].imshow(dmg, extent=extent, cmap="autumn_r", alpha=0.6, vmin=1, vmax=2, aspect="equal")
    axes[2].set_title("(c) labels: damage zone (yellow), fault (red)")
    save(fig, "fig5_section_overlay.png")

    # Figure 6: frequency panel across snapshots
    freqs = [20.0, 40.0, 60.0]
    show = snaps if len(snaps) <= 4 else [snaps[i] for i in np.linspace(0, len(snaps) - 1, 4).round().astype(int)]
    fig, axes = plt.subplots(len(freqs), len(show), figsize=(4.6 * len(show), 2.0 * len(freqs)), squeeze=False)
    for j, s in enumerate(show):
        ve, re_ = element_properties(s.ids, s.layer, layer_props, model, elem_seed)
        vg, rg = property_grids(s.xy, s.radius, ve, re_, s.layer, grid, model)
        secs = synthetic_sections(vg, rg, grid.cell_m, freqs)
        for i, f in enumerate(freqs):
            c = float(np.percentile(np.abs(secs[i]), 99)) or 1.0
            axes[i, j].imshow(secs[i], extent=extent, cmap="gray", vmin=-c, vmax=c, aspect="equal")
            axes[i, j].set_xticks([])
            axes[i, j].set_yticks([])
            if j == 0:
                axes[i, j].set_ylabel(f"{f:g} Hz")
            if i == 0:
                axes[i, j].set_title(f"snapshot {s.index} (throw {s.throw_m:.0f} m)", fontsize=9)
    fig.suptitle("Frequency sensitivity across the deformation sequence")
    save(fig, "fig6_frequency.png")
    return written


def _deformation(p: dict) -> str:
    """What deformed a sample: its basement fault's dip and throw so far, and the base's
    stretch (a run without a basement fault has only the stretch)."""
    stretch = float(p.get("base_stretch", 0.0))
    parts = []
    if int(p.get("n_basement_faults", 1)) > 0:
        parts.append(f"dip {float(p['dip_deg']):.0f}°, throw so far {float(p['throw_m']):.0f} m")
    if stretch != 0.0:
        parts.append(f"base {'stretched' if stretch > 0 else 'shortened'} by "
                     f"{100 * abs(stretch):.1f} %")
    return ", ".join(parts)


def plot_sample(store: str | Path, index: int, out: str | Path) -> Path:
    """One stored sample: the section, its fault label over it, and the damage-zone map."""
    plt = _mpl().plt

    root = open_store(store)
    n = root["seismic"].shape[0]
    if not 0 <= index < n:
        raise InputError(f"--sample {index}: the store has samples 0..{n - 1}")
    grid = dict(root.attrs)["grid"]
    # StoreError naming the sample when it is damaged or its shard is not done
    sample = read_sample(store, index, ("seismic", "fault", "damage"))
    sec, fault, damage = (sample.arrays[k] for k in ("seismic", "fault", "damage"))
    p = sample.params
    noise = p["noise_kind"]
    imaging = f", {imaging_mode(p['imaging']).title(p)}" if "imaging" in p else ""
    # a store whose sampling varies from run to run holds each sample's own
    dx = float(p["trace_spacing_m"]) if "trace_spacing_m" in p else grid.get("dx_m",
                                                                              grid["cell_m"])
    w_m = grid["nx"] * dx
    if "twt" in root or grid.get("domain") == "time":  # rows are two-way-time samples
        dt = float(p["dt_s"]) if "dt_s" in p else float(grid["dt_s"])
        extent = (0, w_m / 1000, sec.shape[0] * dt, 0.0)
        aspect, y_label = "auto", "two-way time (s)"
        height_ratio = sec.shape[0] / sec.shape[1]
    else:
        h_m = grid["nz"] * grid["cell_m"]
        extent = (0, w_m / 1000, h_m / 1000, 0)
        aspect, y_label = "equal", "depth (km)"
        height_ratio = h_m / w_m
    clip = float(np.percentile(np.abs(sec), 99)) or 1.0
    ListedColormap = _mpl().ListedColormap

    fig, axes = plt.subplots(1, 3, figsize=(16, 1.3 + 16 / 3 * height_ratio), sharey=True,
                             layout="constrained")
    axes[0].imshow(sec, cmap="gray", vmin=-clip, vmax=clip, extent=extent, aspect=aspect)
    axes[0].set_title(f"seismic: {float(p['freq_hz']):.3g} Hz, {noise_title(p['snr_db'], noise)}"
                      f"{imaging}")
    axes[1].imshow(sec, cmap="gray", vmin=-clip, vmax=clip, extent=extent, aspect=aspect)
    if "fault_id" in root:  # slip-trace labels: one colour per fault instance
        fid = np.asarray(root["fault_id"][index]).astype(float)
        fid[fault == 0] = 0
        axes[1].imshow(np.ma.masked_equal(fid, 0), cmap="tab10", vmin=0.5, vmax=10.5,
                       extent=extent, aspect=aspect, interpolation="nearest")
        n_f = int(np.unique(fid[fid > 0]).size)
        slip = np.asarray(root["slip_m"][index])
        axes[1].set_title(f"fault label over the section: {n_f} faults (colour = id), "
                          f"max slip {float(slip.max()):.0f} m")
    else:
        axes[1].imshow(np.ma.masked_equal(fault, 0), cmap=ListedColormap(["red"]),
                       extent=extent, aspect=aspect, interpolation="nearest")
        axes[1].set_title("fault label (red) over the section")
    damage_spec = sample_array("damage")
    axes[2].imshow(damage, cmap="magma", vmin=damage_spec.valid_range[0],
                   vmax=damage_spec.valid_range[1], extent=extent, aspect=aspect,
                   interpolation="nearest")
    axes[2].set_title(damage_spec.description)
    for ax in axes:
        ax.set_xlabel("x (km)")
    axes[0].set_ylabel(y_label)
    fig.suptitle(f"sample {index}: run {int(p['run_id'])}, snapshot {int(p['snapshot'])}, "
                 f"{_deformation(p)}")
    out = Path(out)
    # the name is kept as given: no suffix means PNG (matplotlib would append ".png")
    fmt = out.suffix[1:].lower() or "png"
    if fmt not in fig.canvas.get_supported_filetypes():
        plt.close(fig)
        raise InputError(f"--out {str(out)!r}: unknown image type {out.suffix!r}; use .png, "
                         ".pdf, .svg or no suffix (PNG)")
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=110, bbox_inches="tight", format=fmt)
    plt.close(fig)
    return out


def otsu_threshold(values: np.ndarray, bins: int = 256) -> float:
    """Otsu's threshold of ``values`` in [0, 1]: the cut of their histogram that maximises the
    between-class variance (what a prediction's own probabilities say separates fault from
    background); 0.5 where the values are all equal."""
    v = np.asarray(values, np.float64).ravel()
    v = v[np.isfinite(v)]
    if v.size == 0 or v.min() == v.max():
        return 0.5
    hist, edges = np.histogram(v, bins=bins, range=(0.0, 1.0))
    centres = 0.5 * (edges[1:] + edges[:-1])
    w0 = np.cumsum(hist)[:-1].astype(np.float64)
    w1 = v.size - w0
    m0 = np.cumsum(hist * centres)[:-1]
    total = float((hist * centres).sum())
    with np.errstate(divide="ignore", invalid="ignore"):
        between = w0 * w1 * (m0 / w0 - (total - m0) / w1) ** 2
    between[~np.isfinite(between)] = -1.0
    return float(edges[1:-1][int(np.argmax(between))])


def _read_line(path: str | Path, line: tuple[str, int] | None, flag: str) -> np.ndarray:
    """The section in ``path``, or its inline / crossline ``line`` if it is a 3-D cube."""
    if is_segy(path) and cube_geometry(path) is not None:
        if line is None:
            raise InputError(f"{flag} {str(path)!r} is a 3-D cube: give --inline N or "
                             "--crossline N")
        return read_cube_line(path, *line)
    if line is not None and flag == "section":
        raise InputError(f"--{line[0]} is for a 3-D cube; {str(path)!r} is one section")
    return read_section(path)


def plot_section(section: str | Path, out: str | Path, *, pred: str | Path | None = None,
                 labels: str | Path | None = None, threshold: float | None = None,
                 line: tuple[str, int] | None = None, how: str | None = None) -> Path:
    """A section from a file (SEG-Y, ``.npy`` or ``.png``), with a fault prediction over it
    (``pred``: probabilities in [0, 1], the same shape) and a hand-picked mask
    (``labels``: ``.npy``, ``.png`` or SEG-Y), each in its own panel. For a 3-D SEG-Y cube
    (and a prediction cube), ``line`` = ``("inline", N)`` or ``("crossline", N)`` picks the
    line by its header number.

    The prediction is drawn where it reaches ``threshold``: by default Otsu's threshold of its
    own probabilities (:func:`otsu_threshold`), named in the title, so that a model whose
    probabilities run low still shows its faults; the colour is the probability. ``how``
    names where a given threshold comes from in the title (default "given").

    Raises
    ------
    InputError
        A file that cannot be read as a section or mask, or whose shape differs from the
        section's, or a threshold outside (0, 1).
    """
    plt = _mpl().plt

    sec = _read_line(section, line, "section")
    # (title, what is drawn over the section, the probability it is drawn from; None: a mask)
    name = Path(section).name + ("" if line is None else f", {line[0]} {line[1]}")
    panels: list[tuple[str, np.ndarray | None, float | None]] = [
        (f"section: {name}", None, None)]
    if pred is not None:
        prob = _read_line(pred, line, "--pred")
        _same_shape(prob, sec, "--pred", pred)
        if prob.min() < 0 or prob.max() > 1:
            raise InputError(f"--pred {str(pred)!r}: values {prob.min():.3g}..{prob.max():.3g} "
                             "are not probabilities in [0, 1]")
        if threshold is not None and not 0 < threshold < 1:
            raise InputError(f"--threshold {threshold!r}: expected a probability in (0, 1)")
        t = otsu_threshold(prob) if threshold is None else float(threshold)
        share = float((prob >= t).mean())
        how = "Otsu of its probabilities" if threshold is None else (how or "given")
        panels.append((f"prediction >= {t:.2f} ({how}; {100 * share:.1f} % of pixels)", prob, t))
    if labels is not None:
        mask = read_mask(labels)
        _same_shape(mask, sec, "--labels", labels)
        panels.append((f"picked faults: {Path(labels).name}", mask.astype(np.float32), None))
    clip = float(np.percentile(np.abs(sec - np.median(sec)), 99)) or 1.0
    centre = float(np.median(sec))
    n = len(panels)
    h, w = sec.shape
    fig, axes = plt.subplots(1, n, figsize=(5.5 * n, 1.2 + 5.5 * min(h / w, 2.0)), sharey=True,
                             layout="constrained", squeeze=False)
    for ax, (title, over, drawn_from) in zip(axes[0], panels):
        ax.imshow(sec, cmap="gray", vmin=centre - clip, vmax=centre + clip, aspect="auto",
                  interpolation="nearest")
        if over is not None and drawn_from is None:
            ax.imshow(np.ma.masked_equal(over, 0), cmap="autumn", vmin=0, vmax=1, aspect="auto",
                      interpolation="nearest")
        elif over is not None:
            im = ax.imshow(np.ma.masked_less(over, drawn_from), cmap="inferno", vmin=0.0,
                           vmax=1.0, aspect="auto", interpolation="nearest", alpha=0.85)
            fig.colorbar(im, ax=ax, shrink=0.8, label="fault probability")
        ax.set_title(title, fontsize=9)
        ax.set_xlabel("trace")
    axes[0][0].set_ylabel("sample")
    out = Path(out)
    fig.savefig(out, dpi=110)
    plt.close(fig)
    return out


def _same_shape(a: np.ndarray, sec: np.ndarray, flag: str, path: str | Path) -> None:
    if a.shape != sec.shape:
        raise InputError(f"{flag} {str(path)!r} has shape {a.shape}, the section "
                         f"{sec.shape}: they must be the same grid")


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
    mpl = _mpl()
    plt, EllipseCollection = mpl.plt, mpl.EllipseCollection

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


def plot_realism(report: dict, out: str | Path, *, credit: str | None = None) -> Path:
    """The figure of a realism report (:func:`demseis.evaluation.realism_report.realism_report`).

    Top: a measured store sample with its fault label, the field section (when the report has
    one), the mean amplitude spectra, and the table's scalar measures. Bottom: the store's
    distributions of apparent dip (pixels), faults per 100 traces, label fraction and throw
    (output samples), with the field targets as grey bands (10th-90th percentile or range)
    and dashed lines (median). ``credit`` (a data licence line) is printed under the figure.
    """
    plt = _mpl().plt

    st, field, targets = report["store"], report.get("field"), report["targets"]
    fig, axes = plt.subplots(2, 4, figsize=(17, 8), layout="constrained")
    # a sample with faults, if one was measured
    idx = st["seismic_samples"]
    pick = idx[0]
    for i in idx:
        if np.any(read_sample(st["path"], i, ("fault",)).arrays["fault"] == 1):
            pick = i
            break
    arrays = ("seismic", "fault") if "fault" in open_store(st["path"]) else ("seismic",)
    a = read_sample(st["path"], pick, arrays).arrays
    sec = a["seismic"]
    clip = float(np.percentile(np.abs(sec), 99)) or 1.0
    ax = axes[0, 0]
    ax.imshow(sec, cmap="gray", vmin=-clip, vmax=clip, aspect="auto", interpolation="nearest")
    if "fault" in a:
        ListedColormap = _mpl().ListedColormap

        ax.imshow(np.ma.masked_not_equal(a["fault"], 1), cmap=ListedColormap(["red"]),
                  aspect="auto", interpolation="nearest", alpha=0.8)
    ax.set_title(f"store sample {pick} (label red)")
    ax.set_xlabel("trace (column)")
    ax.set_ylabel(st["pixels"].split(" of ")[0].rstrip("s") + " (row)")
    ax = axes[0, 1]
    if field:
        fsec = read_segy_section(field["path"])
        clip = float(np.percentile(np.abs(fsec), 99)) or 1.0
        ax.imshow(fsec, cmap="gray", vmin=-clip, vmax=clip, aspect="auto", interpolation="nearest")
        ax.set_title(f"field section {Path(field['path']).name}")
        ax.set_xlabel("trace")
        ax.set_ylabel("time sample")
    else:
        ax.axis("off")
        ax.text(0.5, 0.5, "no field section", ha="center", va="center", transform=ax.transAxes)
    ax = axes[0, 2]
    for part, name, color in ((st, "store", "C0"), (field, "field", "k")):
        if part:
            sp = part["spectrum"]
            ax.plot(sp["freq_cycles_per_sample"], sp["amplitude"], color=color, label=name)
    ax.set_xlim(0, 0.5)
    ax.set_xlabel("frequency (cycles per sample; period = 1 / f)")
    ax.set_ylabel("mean amplitude (peak = 1)")
    ax.set_title("amplitude spectra of the traces")
    ax.legend()
    ax = axes[0, 3]
    ax.axis("off")
    rows = [r for r in report_rows(report)][:5]
    text = "\n\n".join(f"{r[0]}\n  store {r[1]}   field {r[2]}   target {r[3]}" for r in rows)
    ax.text(0, 1, text, va="top", ha="left", family="monospace", fontsize=8.5,
            transform=ax.transAxes)
    ax.set_title("seismic measures")
    hists = (("apparent_dip_deg", "apparent dip in pixels (deg from horizontal)"),
             ("faults_per_100_traces", "faults per 100 traces (per sample)"),
             ("label_fraction_pct", "label fraction (% of pixels, per sample)"),
             ("throw_samples", f"throw ({st['pixels'].split(' of ')[0]}, per label pixel)"))
    for ax, (key, label) in zip(axes[1], hists):
        d = st["measures"].get(key)
        if not d:
            ax.text(0.5, 0.5, "no labels", ha="center", va="center", transform=ax.transAxes)
            ax.set_title(label)
            continue
        edges = np.asarray(d["hist"]["edges"])
        counts = np.asarray(d["hist"]["counts"], float)
        ax.stairs(counts / max(counts.sum(), 1), edges, fill=True, alpha=0.6, color="C0",
                  label="store")
        t = targets.get(key)
        if t:
            if t.get("low") is not None:
                ax.axvspan(t["low"], t["high"], color="0.5", alpha=0.25,
                           label=f"field target {t['text']}")
            if t.get("median") is not None:
                ax.axvline(t["median"], color="k", ls="--", lw=1)
        ax.axvline(d["median"], color="C0", lw=1.5)
        ax.set_title(label)
        ax.set_ylabel("share")
        ax.legend(fontsize=8, loc="upper left")
    fig.suptitle(f"{Path(st['path']).name}: {st['selection']}", fontsize=9)
    if credit:
        fig.text(0.5, -0.01, credit, ha="center", va="top", fontsize=9)
    out = Path(out)
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=100, bbox_inches="tight")
    plt.close(fig)
    return out
