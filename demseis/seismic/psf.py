"""2-D imaging: a dip-limited, wavelet-band-limited point-spread function (PSF).

Beside the 1-D trace-by-trace convolution of :mod:`demseis.seismic.forward`, a section can be
rendered as the reflectivity convolved with a 2-D point-spread function, as a migrated image
of a survey with a limited illumination angle would look [Lecomte 2008; Lecomte et al. 2015].

The model
---------
The image is the 2-D convolution of the reflectivity ``r`` with a PSF ``h``,
``I(x, z) = (h ** r)(x, z)``, whose wavenumber spectrum is a product::

    H(k_x, k_z) = W(k_z) A(k_x, k_z)

- ``W`` is the wavelet's spectrum along the vertical: the Ricker of peak frequency ``f_p``,
  ``W(f) = (2 / sqrt(pi)) f^2 / f_p^3 exp(-f^2 / f_p^2)`` in two-way time, i.e. at the
  vertical wavenumber ``k_z = 2 f / v`` (cycles/m) in depth at the interval velocity ``v``;
- ``A`` is the illumination (dip) mask. A plane-wave component ``(k_x, k_z)`` is the image of
  a reflector whose normal makes the angle ``phi = arctan(|k_x| / |k_z|)`` with the vertical,
  i.e. a reflector of dip ``phi``. With zero-offset illumination up to ``theta`` from the
  vertical, only ``phi <= theta`` is imaged::

      A = T(phi),  T(phi) = 1                                     for phi <= theta - delta
                          = (1 + cos(pi (phi - theta + delta) / delta)) / 2   in between
                          = 0                                     for phi >= theta

  (``delta`` = ``taper_deg``, a raised-cosine taper that keeps the kernel compact; ``theta
  >= 90`` deg disables the mask). Equivalently ``|k_x| <= |k_z| tan(theta)`` with a smooth edge.

Because ``H`` is a product, ``h ** r = a ** (w * r)``: the PSF image is the dip filter ``a``
(spectrum ``A``) applied to the 1-D section ``w * r``. That 1-D section is exactly the one of
:func:`demseis.seismic.forward.synthetic_sections` (each reflection at its exact two-way time,
the Ricker evaluated at every output time, in depth at every cell-centre time), so in depth
the vertical band-limit honours the depth-time mapping of the Vp column (``k_z = 2 f / v(z)``
locally) without any resampling. A flat reflector has ``k_x = 0``, where ``A = 1``: its PSF
section *is* its 1-D section (a property of the model, tested to float precision).

Domains
-------
- depth: the section's axes are ``z`` and ``x``, both sampled at the cell size, so ``phi`` is
  the geometric dip directly: ``phi = arctan(|k_x| / |k_z|)``.
- time: the vertical axis is two-way time; a frequency ``f`` (Hz) of the time axis is the
  vertical wavenumber ``k_z = 2 f / v`` at interval velocity ``v``, so
  ``phi = arctan(v |k_x| / (2 |f|))`` and the mask needs ``v(t)``: the lateral mean of the
  interval velocity at each time, averaged over each depth window (below).

Depth-varying angle
-------------------
The maximum angle may decrease with depth, as it does for a survey of finite half-aperture
``L`` (``aperture_m``): a point at depth ``z`` below the grid top is illuminated up to
``theta(z) = min(theta_max, arctan(L / z))``. The mask (and, in time, the velocity) is then
evaluated at ``n_windows`` nodes evenly spaced down the section; the section is filtered once
per node and the results are blended with piecewise-linear hat weights, which sum to one at
every row: ``I(z) = sum_k g_k(z) (a_k ** s)(z)``. Since every ``a_k`` keeps ``k_x = 0``
unchanged and ``sum_k g_k = 1``, flat reflectors are still exactly the 1-D section. The angle
does not vary laterally (no lateral velocity field is used).

Boundaries
----------
The filter is applied with FFTs on a padded grid: the section is extended laterally by
mirror images (so a flat reflector stays flat to the edges, and the image of a dipping one is
that of a mirrored continuation) and with zeros below, by four half-widths of the wavelet
(as a depth length at the fastest Vp in depth). The fast path is thus an exact circular
convolution on that padded grid, which the tests compare with a direct spatial sum of the
same kernel; what wraps around is the PSF's tail beyond the padding (measured in
docs/seismic.md). Rows more than two half-widths below the last non-zero row of a section
(the end of a long time axis) are not transformed and stay zero.

References: I. Lecomte (2008), Resolution and illumination analyses in PSDM: a ray-based
approach, The Leading Edge 27(5); I. Lecomte et al. (2015), Ray-based seismic modeling of
geologic models: understanding and analyzing seismic images efficiently, Interpretation 3(4).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from demseis.errors import InputError
from demseis.seismic import _kernels
from demseis.seismic.forward import (_check_grids, coarse_velocity, interface_times,
                                     synthetic_sections)
from demseis.seismic.wavelet import as_wavelets, scipy_fft


DEFAULT_TAPER_DEG = 5.0
"""Width of the raised-cosine edge of the dip mask (degrees), inside the maximum angle."""


def dip_weight(phi_rad: np.ndarray, max_angle_deg: float,
               taper_deg: float = DEFAULT_TAPER_DEG) -> np.ndarray:
    """The illumination mask ``T(phi)`` of the module docstring.

    Parameters
    ----------
    phi_rad : dip angles of plane-wave components (radians, 0 = flat, pi/2 = vertical).
    max_angle_deg : maximum illumination angle theta (degrees, > 0); >= 90 passes everything.
    taper_deg : width delta of the raised-cosine edge (degrees, >= 0), inside theta.

    Returns
    -------
    float64 array of weights in [0, 1]: 1 up to ``theta - delta``, 0 from ``theta`` on.
    """
    phi = np.asarray(phi_rad, dtype=np.float64)
    if max_angle_deg >= 90.0:
        return np.ones_like(phi)
    theta = math.radians(max_angle_deg)
    delta = min(math.radians(taper_deg), theta)
    if delta <= 0.0:
        return (phi < theta).astype(np.float64)
    u = np.clip((phi - (theta - delta)) / delta, 0.0, 1.0)
    return 0.5 * (1.0 + np.cos(np.pi * u))


def _check_angle(max_angle_deg: float, taper_deg: float, aperture_m: float) -> None:
    if not (np.isfinite(max_angle_deg) and 0.0 < max_angle_deg <= 90.0):
        raise InputError(f"max_angle_deg must be in (0, 90] degrees, got {max_angle_deg!r}")
    if not (np.isfinite(taper_deg) and 0.0 <= taper_deg <= 45.0):
        raise InputError(f"taper_deg must be in [0, 45] degrees, got {taper_deg!r}")
    if not (aperture_m > 0):
        raise InputError(f"aperture_m must be > 0 m (inf for no limit), got {aperture_m!r}")


def node_weights(n_rows: int, n_windows: int) -> tuple[np.ndarray, np.ndarray]:
    """Nodes and piecewise-linear blending weights of ``n_windows`` depth (time) windows.

    Returns
    -------
    nodes : (K,) float64 row positions of the nodes, evenly spaced from the first row to the
        last (one node at the centre when K = 1).
    weights : (K, n_rows) float64 hat functions, ``weights[:, i].sum() == 1`` for every row.
    """
    if n_windows == 1:
        return np.array([(n_rows - 1) / 2.0]), np.ones((1, n_rows))
    nodes = np.linspace(0.0, n_rows - 1.0, n_windows)
    rows = np.arange(n_rows, dtype=np.float64)
    eye = np.eye(n_windows)
    weights = np.stack([np.interp(rows, nodes, eye[k]) for k in range(n_windows)])
    return nodes, weights


def padded_shape(n_rows: int, n_cols: int, pad_rows: int, pad_cols: int) -> tuple[int, int]:
    """FFT grid of a section padded by ``pad_rows`` below and ``pad_cols`` on each side
    (sizes rounded up to fast FFT lengths)."""
    (next_fast_len,) = scipy_fft("next_fast_len")

    return (next_fast_len(n_rows + pad_rows, real=True),
            next_fast_len(n_cols + 2 * pad_cols, real=True))


def pad_section(section: np.ndarray, shape: tuple[int, int], pad_cols: int) -> np.ndarray:
    """The section (last two axes (rows, cols)) on the padded FFT grid, float32: mirrored
    laterally (``pad_cols`` columns on the left, the rest on the right; repeated reflection,
    like ``np.pad(mode="symmetric")``) and zero below."""
    s = np.asarray(section, dtype=np.float32)
    n_rows, n_cols = s.shape[-2:]
    out = np.zeros(s.shape[:-2] + tuple(shape), dtype=np.float32)
    right = shape[1] - n_cols - pad_cols
    if pad_cols <= n_cols and right <= n_cols:          # one reflection each side: slices
        out[..., :n_rows, pad_cols:pad_cols + n_cols] = s
        out[..., :n_rows, :pad_cols] = s[..., pad_cols - 1::-1] if pad_cols else s[..., :0]
        out[..., :n_rows, pad_cols + n_cols:] = s[..., ::-1][..., :right]
        return out
    q = np.mod(np.arange(shape[1]) - pad_cols, 2 * n_cols)
    out[..., :n_rows, :] = s[..., np.where(q >= n_cols, 2 * n_cols - 1 - q, q)]
    return out


def dip_masks(shape: tuple[int, int], row_step: float, col_step_m: float,
              angles_deg: Sequence[float], kz_per_row_freq: Sequence[float],
              taper_deg: float = DEFAULT_TAPER_DEG) -> np.ndarray:
    """The masks ``A_k`` on the ``rfft2`` grid of ``shape`` (one per node).

    Parameters
    ----------
    shape : (N, M) padded grid (rows, columns).
    row_step : vertical sample interval (m in depth, s in time).
    col_step_m : lateral sample interval (m).
    angles_deg : (K,) maximum angle at each node (degrees).
    kz_per_row_freq : (K,) vertical wavenumber (cycles/m) per cycle per row unit: 1 in depth,
        ``2 / v_k`` (s/m) in time at the node's interval velocity ``v_k``.
    taper_deg : raised-cosine edge (degrees).

    Returns
    -------
    (K, N, M // 2 + 1) float64 weights.
    """
    fftfreq, rfftfreq = scipy_fft("fftfreq", "rfftfreq")

    fz = np.abs(fftfreq(shape[0], row_step)).astype(np.float32)[:, None]
    kx = np.abs(rfftfreq(shape[1], col_step_m)).astype(np.float32)[None, :]
    # tan(phi) = |k_x| / (s |f_z|): the ratio is formed once, each node compares it with its
    # edges scaled by s; arctan and cosine only inside the taper
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = kx / fz
    ratio[0, 0] = 0.0                                     # DC: flat
    out = np.empty((len(angles_deg), shape[0], shape[1] // 2 + 1), dtype=np.float32)
    for k, (ang, s) in enumerate(zip(angles_deg, kz_per_row_freq)):
        if ang >= 90.0:
            out[k] = 1.0
            continue
        theta = math.radians(ang)
        lo = s * math.tan(theta - min(math.radians(taper_deg), theta))
        out[k] = ratio <= lo
        band = np.flatnonzero((ratio > lo) & (ratio < s * math.tan(theta)))
        rows, cols = np.divmod(band, ratio.shape[1])
        out[k][rows, cols] = dip_weight(np.arctan(ratio[rows, cols] / s), float(ang), taper_deg)
    return out


@dataclass(frozen=True)
class PsfPlan:
    """Everything :func:`dip_filter` needs for one section shape (see :func:`psf_plan`).

    Attributes
    ----------
    row_step : vertical sample interval (m in depth, s in time).
    col_step_m : lateral sample interval (m).
    angles_deg : (K,) maximum illumination angle at each node (degrees).
    kz_scale : (K,) vertical wavenumber per unit of row frequency: 1 (depth) or ``2 / v_k``.
    pad_rows, pad_cols : zero rows below, mirrored columns on each side.
    taper_deg : raised-cosine edge of the mask (degrees).
    """

    row_step: float
    col_step_m: float
    angles_deg: tuple[float, ...]
    kz_scale: tuple[float, ...]
    pad_rows: int
    pad_cols: int
    taper_deg: float = DEFAULT_TAPER_DEG


def dip_filter(sections: np.ndarray, plan: PsfPlan) -> np.ndarray:
    """Apply the (node-blended) dip mask of ``plan`` to sections (FFT, the fast path).

    Parameters
    ----------
    sections : (..., n_rows, n_cols) sections (1-D images), any leading axes (frequencies).
    plan : sampling, node angles and velocities, padding (:func:`psf_plan`); the
        ``K = len(plan.angles_deg)`` nodes are evenly spaced down the rows (:func:`node_weights`).

    Returns
    -------
    float32 array of the input's shape: ``sum_k g_k(row) (a_k ** s)`` on the padded grid,
    cropped back.
    """
    ifft, irfft, rfft2 = scipy_fft("ifft", "irfft", "rfft2")

    s = np.asarray(sections)
    n_rows, n_cols = s.shape[-2:]
    out = np.zeros(s.shape, dtype=np.float32)
    live = np.flatnonzero(np.any(s != 0.0, axis=tuple(range(s.ndim - 2)) + (s.ndim - 1,)))
    if live.size == 0:
        return out
    # rows far below the last non-zero one (a time axis long enough for the slowest column)
    # only receive kernel tails: filter down to half the padding below it, zero further down
    n_keep = min(n_rows, int(live[-1]) + 1 + plan.pad_rows // 2)
    shape = padded_shape(n_keep, n_cols, plan.pad_rows, plan.pad_cols)
    masks = dip_masks(shape, plan.row_step, plan.col_step_m, plan.angles_deg, plan.kz_scale,
                      plan.taper_deg)
    weights = node_weights(n_rows, masks.shape[0])[1][:, :n_keep].astype(np.float32)
    # single precision transforms: 2x faster, ~1e-7 of the peak (the tests ask 1e-5)
    spec = rfft2(pad_section(s[..., :n_keep, :], shape, plan.pad_cols), axes=(-2, -1))
    # the blend sum_k g_k(z) (.) commutes with the inverse along x: blend in (z, k_x), then
    # one inverse along x for all rows
    acc = np.zeros(spec.shape[:-2] + (n_keep, spec.shape[-1]), dtype=spec.dtype)
    buf = np.empty_like(spec)
    for k in range(masks.shape[0]):
        rows = np.flatnonzero(weights[k] > 0.0)
        if rows.size == 0:
            continue
        r0, r1 = int(rows[0]), int(rows[-1]) + 1
        np.multiply(spec, masks[k], out=buf)
        tmp = ifft(buf, axis=-2, overwrite_x=True)
        acc[..., r0:r1, :] += weights[k, r0:r1, None] * tmp[..., r0:r1, :]
    cols = slice(plan.pad_cols, plan.pad_cols + n_cols)
    out[..., :n_keep, :] = irfft(acc, n=shape[1], axis=-1)[..., cols]
    return out


def _pads(half_s: float, vp_max_m_s: float, cell_m: float,
          dt_s: float | None, col_step_m: float | None = None) -> tuple[int, int]:
    """Padding (rows below, columns each side): four half-widths of the widest wavelet, as
    time samples (``dt_s``) or as a depth length at the fastest velocity (cells; columns of
    ``col_step_m``, default ``cell_m``). Beyond that
    distance the PSF is below 3 % of its peak for angles >= 20 deg (0.3 % of its energy;
    8 % and 1 % at 10 deg), measured for 20 and 40 Hz at 3000 m/s."""
    length_m = 2.0 * half_s * vp_max_m_s         # 4 half-widths, two-way time -> depth
    rows = length_m / cell_m if dt_s is None else 4.0 * half_s / dt_s
    col = cell_m if col_step_m is None else col_step_m
    return int(math.ceil(rows)) + 1, int(math.ceil(length_m / col)) + 1


def _time_profile(vp: np.ndarray, cell_m: float, t_s: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Lateral means of the interval velocity and of the depth (cell centre) at each time of
    ``t_s``, over the columns whose cells reach that time; held below the deepest column."""
    t_bottom, _ = interface_times(vp, cell_m)
    idx = np.empty((vp.shape[1], t_s.size), dtype=np.int64)
    _kernels.containing_cell(np.ascontiguousarray(t_bottom.T), t_s, idx)
    valid = idx >= 0
    n = valid.sum(axis=0)
    safe = np.where(valid, idx, 0)
    v_sum = np.where(valid, vp[safe, np.arange(vp.shape[1])[:, None]], 0.0).sum(axis=0)
    z_sum = np.where(valid, (safe + 0.5) * cell_m, 0.0).sum(axis=0)
    if not n.any():                      # no time inside any column (t_s all < 0)
        return np.full(t_s.size, vp.mean()), np.zeros(t_s.size)
    last = int(np.flatnonzero(n)[-1])
    n_held = np.maximum(n, 1)
    v_mean, z_mean = v_sum / n_held, z_sum / n_held
    v_mean[last + 1:] = v_mean[last]
    z_mean[last + 1:] = z_mean[last]
    return v_mean, z_mean


def node_angles_deg(depth_m: np.ndarray, max_angle_deg: float, aperture_m: float) -> np.ndarray:
    """``theta(z) = min(theta_max, arctan(L / z))`` (degrees) at depths ``z`` below the grid top."""
    z = np.maximum(np.asarray(depth_m, dtype=np.float64), 0.0)
    if not np.isfinite(aperture_m):
        return np.full(z.shape, float(max_angle_deg))
    return np.minimum(float(max_angle_deg), np.degrees(np.arctan2(aperture_m, z)))


def psf_plan(vp_g: np.ndarray, cell_m: float, freqs_hz: float | Sequence[float],
             max_angle_deg: float = 30.0, domain: str = "depth", *,
             t_s: np.ndarray | None = None, aperture_m: float = math.inf,
             taper_deg: float = DEFAULT_TAPER_DEG, n_windows: int | None = None,
             col_step_m: float | None = None) -> PsfPlan:
    """Node angles, velocities and padding of the PSF of one property grid (see
    :func:`psf_sections` for the parameters)."""
    col = float(cell_m) if col_step_m is None else float(col_step_m)
    if not (math.isfinite(col) and col > 0):
        raise InputError(f"col_step_m must be a trace spacing > 0 m, got {col_step_m!r}")
    vp = np.asarray(vp_g, dtype=np.float64)
    wavelets = as_wavelets(freqs_hz)
    _check_angle(max_angle_deg, taper_deg, aperture_m)
    varying = domain == "time" or np.isfinite(aperture_m)
    k = n_windows if n_windows is not None else (4 if varying else 1)
    if not (isinstance(k, (int, np.integer)) and k >= 1):
        raise InputError(f"n_windows must be a positive integer, got {n_windows!r}")
    half = max(w.half_width_s() for w in wavelets)
    if domain == "depth":
        nodes, _ = node_weights(vp.shape[0], k)
        angles = node_angles_deg((nodes + 0.5) * cell_m, max_angle_deg, aperture_m)
        scale = np.ones(k)
        row_step = float(cell_m)
        pads = _pads(half, float(vp.max()), cell_m, None, col)
    elif domain == "time":
        if t_s is None:
            raise InputError("domain='time' needs t_s, the sweep's time axis")
        t = np.asarray(t_s, dtype=np.float64)
        if t.ndim != 1 or t.size < 2 or not np.allclose(np.diff(t), t[1] - t[0], rtol=1e-6,
                                                         atol=0.0) or t[1] <= t[0]:
            raise InputError("the PSF in the time domain needs a regular, ascending time axis "
                             "t_s of at least two samples")
        row_step = float(t[1] - t[0])
        sub = np.arange(0, t.size, max(1, t.size // 256))    # the profile is smooth enough
        v_t, z_t = (np.interp(np.arange(t.size), sub, p) for p in _time_profile(vp, cell_m, t[sub]))
        nodes, weights = node_weights(t.size, k)
        scale = 2.0 / ((weights @ v_t) / weights.sum(axis=1))
        angles = node_angles_deg(np.interp(nodes, np.arange(t.size), z_t), max_angle_deg,
                                 aperture_m)
        pads = _pads(half, float(vp.max()), cell_m, row_step, col)
    else:
        raise InputError(f"domain must be 'depth' or 'time', got {domain!r}")
    return PsfPlan(row_step, col, tuple(map(float, angles)),
                   tuple(map(float, scale)), pads[0], pads[1], float(taper_deg))


def psf_sections(vp_g: np.ndarray, rho_g: np.ndarray, cell_m: float,
                 freqs_hz: float | Sequence[float], max_angle_deg: float = 30.0,
                 domain: str = "depth", *, t_s: np.ndarray | None = None,
                 aperture_m: float = math.inf, taper_deg: float = DEFAULT_TAPER_DEG,
                 n_windows: int | None = None, col_step_m: float | None = None,
                 rows_per_cell: int = 1) -> np.ndarray:
    """PSF-imaged, noise-free Ricker sections of a property grid, one per frequency.

    The 1-D sections of :func:`demseis.seismic.forward.synthetic_sections` filtered by the
    dip mask of the module docstring, i.e. the reflectivity convolved with the PSF
    ``H = W(k_z) A(k_x, k_z)``.

    Parameters
    ----------
    vp_g, rho_g, cell_m, freqs_hz, domain, t_s : as for ``synthetic_sections``.
    max_angle_deg : maximum illumination angle theta_max (degrees, (0, 90]; 90 = no limit).
    aperture_m : survey half-aperture L (m); the angle at depth z is
        ``min(theta_max, arctan(L / z))``. ``inf`` (default): the angle is constant.
    taper_deg : raised-cosine edge of the mask (degrees), inside theta.
    n_windows : depth (time) nodes of the blended mask; default 1 where nothing varies
        vertically (depth domain, infinite aperture), else 4.
    col_step_m : distance between the columns (traces), default ``cell_m``; a grid whose rows
        are finer than its columns (a fine stratigraphy sampled at a survey's traces) sets it.
    rows_per_cell : depth domain: the grid's rows split output cells in this odd number (as
        for ``synthetic_sections``); the 1-D section is evaluated at the cells' centres and
        the dip filter works on those cells (the cells' velocity: the harmonic mean of their
        rows').

    Returns
    -------
    (nf, nz, nx) float32 for depth, (nf, nt, nx) float32 for time.
    """
    vp, _ = _check_grids(vp_g, rho_g, cell_m)
    n = rows_per_cell if domain == "depth" else 1
    sections = synthetic_sections(vp_g, rho_g, cell_m, freqs_hz, domain, t_s=t_s,
                                  rows_per_cell=n)
    if n > 1:        # the plan of the output cells: n rows each, two-way time kept
        vp = coarse_velocity(vp, n)
    plan = psf_plan(vp, cell_m * n, freqs_hz, max_angle_deg, domain, t_s=t_s,
                    aperture_m=aperture_m, taper_deg=taper_deg, n_windows=n_windows,
                    col_step_m=cell_m if col_step_m is None else col_step_m)
    if max_angle_deg >= 90.0:
        return sections
    return dip_filter(sections, plan)
