"""Reference fault detectors with no learning: the floor a model has to beat.

Two attributes, both scaled to probabilities in [0, 1] with default threshold 0.5:

- ``"dip"`` (default of ``demseis baseline``, :func:`dip_fault_probability`): reflector dip
  from the structure tensor, weighted by its coherence. demseis layers are deposited flat, so
  steep reflector segments mark fault drag, offsets and the fault plane itself. It is not a
  general-purpose fault attribute (regional dip reads as faults), but it is the stronger floor
  on demseis sections (docs/scoring.md has the measurements).
- ``"semblance"`` (:func:`semblance_fault_probability`): dip-scanned semblance, the classic
  lateral-discontinuity attribute, insensitive to regional dip, described below.

The semblance attribute is *dip-scanned semblance* (Marfurt, Kirlin, Farmer & Bahorich, 1998, Geophysics
63(4)): in a small window of neighbouring traces, semblance measures how alike the traces are
along the best of a set of trial slopes, so continuous (also dipping) reflectors give values near
1 and reflectors cut and offset by a fault give low values. With the discontinuity
``d = 1 - c_max`` and ``d_med`` its median over the section, the fault probability is

    prob = clip((d - d_med) / ((1 - d_med) (1 - c_ref)), 0, 1),   c_ref = DEFAULT_C_REF

Subtracting the section median removes the background discontinuity that noise gives every
window (on synthetic sections at 0 dB SNR it cut false positives on an unfaulted section from
72 % to 18 % of pixels, with no change on clean sections); the stretch makes a relative
discontinuity of ``1 - c_ref`` or more probability 1.

The default threshold :data:`DEFAULT_THRESHOLD` is the value at which a pixel is
called a fault; it was chosen on synthetic Ricker sections (see docs/scoring.md) and users can
tune it with the ODS threshold that :func:`demseis.evaluation.scoring.score` reports.
"""

from __future__ import annotations

import os
import shutil
import sys
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy import ndimage
from tqdm import tqdm

from demseis.datasets._nodes import zarr_lib
from demseis.datasets.read import open_sections
from demseis.errors import InputError

__all__ = [
    "DEFAULT_C_REF",
    "DEFAULT_THRESHOLD",
    "METHODS",
    "SemblanceBaseline",
    "baseline_fault_probability",
    "dip_fault_probability",
    "semblance_fault_probability",
]

#: baseline methods by name; "dip" is the default of ``demseis baseline``
METHODS = ("dip", "semblance")

#: probability at which the baseline calls a pixel a fault
DEFAULT_THRESHOLD = 0.5
#: semblance mapped to probability 1
DEFAULT_C_REF = 0.5


@dataclass(frozen=True)
class SemblanceBaseline:
    """Settings of the dip-scanned semblance detector.

    Attributes
    ----------
    half_traces : int
        Window half-width in traces (window is 2*half_traces+1 traces wide).
    half_samples : int
        Window half-height in samples.
    max_slope : float
        Largest trial reflector slope in samples per trace (1.0 = 45 degrees on a square grid).
    n_slopes : int
        Number of trial slopes, evenly spaced in [-max_slope, max_slope].
    eps_frac : float
        Regulariser as a fraction of the mean window energy of the section; keeps windows
        without reflections from reading as discontinuities.
    c_ref : float
        Semblance mapped to probability 1.
    """

    half_traces: int = 2
    half_samples: int = 4
    max_slope: float = 1.0
    n_slopes: int = 9
    eps_frac: float = 0.05
    c_ref: float = DEFAULT_C_REF

    def __post_init__(self) -> None:
        for name in ("half_traces", "half_samples", "n_slopes"):
            v = getattr(self, name)
            if int(v) != v or v < 1:
                raise InputError(f"{name}: must be a positive integer, got {v!r}")
        if not (0.0 <= self.max_slope <= 10.0):
            raise InputError(f"max_slope: must lie in [0, 10] samples per trace, "
                             f"got {self.max_slope!r}")
        if not (0.0 <= self.eps_frac < 10.0):
            raise InputError(f"eps_frac: must lie in [0, 10), got {self.eps_frac!r}")
        if not (0.0 <= self.c_ref < 1.0):
            raise InputError(f"c_ref: must lie in [0, 1), got {self.c_ref!r}")

    def slopes(self) -> NDArray[np.float64]:
        """Trial slopes in samples per trace, shape (n_slopes,)."""
        if self.n_slopes == 1:
            return np.zeros(1)
        return np.linspace(-self.max_slope, self.max_slope, int(self.n_slopes))


def semblance_fault_probability(section: ArrayLike,
                                config: SemblanceBaseline | None = None) -> NDArray[np.float32]:
    """Fault probability of one section or a stack of sections from dip-scanned semblance.

    Parameters
    ----------
    section : array_like, shape (H, W) or (N, H, W)
        Seismic amplitude, rows are depth samples, columns traces. Must be finite.
    config : SemblanceBaseline, optional
        Window and scaling settings; defaults are documented on :class:`SemblanceBaseline`.

    Returns
    -------
    ndarray, float32, same shape as ``section``
        Probabilities in [0, 1]; call a pixel a fault at ``>= DEFAULT_THRESHOLD``.
    """
    # lazy: the Numba kernels load numba (~0.25 s), which scoring and the dip baseline never need
    from demseis.evaluation._kernels import dip_scan_semblance

    cfg = config or SemblanceBaseline()
    stack, two_d = _check_section(section)
    nwin = (2 * cfg.half_traces + 1) ** 2 * (2 * cfg.half_samples + 1)
    out = np.empty(stack.shape, np.float32)
    slopes = cfg.slopes()
    for i in range(stack.shape[0]):
        s = stack[i]
        eps = cfg.eps_frac * nwin * float(np.mean(s * s))
        if eps == 0.0:  # an all-zero section has no discontinuity
            out[i] = 0.0
            continue
        c = dip_scan_semblance(np.ascontiguousarray(s), slopes, int(cfg.half_traces),
                               int(cfg.half_samples), eps)
        d = 1.0 - c.astype(np.float64)
        d_med = float(np.median(d))
        scale = (1.0 - d_med) * (1.0 - cfg.c_ref)
        out[i] = np.clip((d - d_med) / scale, 0.0, 1.0) if scale > 0 else 0.0
    return out[0] if two_d else out


def dip_fault_probability(section: ArrayLike, *, sigma_grad_px: float = 1.0,
                          sigma_tensor_px: float = 4.0,
                          dip_scale: float = 0.5) -> NDArray[np.float32]:
    """Fault probability from coherence-weighted reflector dip (structure tensor).

    With Gaussian-derivative gradients ``g = (d/dz, d/dx)`` of the section (scale
    ``sigma_grad_px``) and the structure tensor ``J = G_sigma * (g g^T)`` (scale
    ``sigma_tensor_px``), the dominant gradient makes the angle
    ``theta = 0.5 atan2(2 J_xz, J_zz - J_xx)`` with the vertical, which is the reflector dip,
    and ``coh = sqrt((J_zz - J_xx)^2 + 4 J_xz^2) / (J_zz + J_xx)`` in [0, 1] says how
    clearly oriented the reflections are (van Vliet & Verbeek, 1995). Then::

        prob = clip(|sin theta| * coh / dip_scale, 0, 1)

    so a clearly oriented reflector dipping 30 degrees (|sin| = 0.5) or more is probability 1.

    Parameters
    ----------
    section : array_like, shape (H, W) or (N, H, W)
        Seismic amplitude, rows depth samples, columns traces (square cells assumed).
    sigma_grad_px, sigma_tensor_px : float
        Gradient and tensor smoothing scales in pixels (> 0).
    dip_scale : float
        ``|sin(dip)| * coh`` mapped to probability 1, in (0, 1].

    Returns
    -------
    ndarray, float32, same shape as ``section``
    """
    stack, two_d = _check_section(section)
    for name, v in (("sigma_grad_px", sigma_grad_px), ("sigma_tensor_px", sigma_tensor_px)):
        if not (np.isfinite(v) and v > 0):
            raise InputError(f"{name}: must be a positive number of pixels, got {v!r}")
    if not (0 < dip_scale <= 1):
        raise InputError(f"dip_scale: must lie in (0, 1], got {dip_scale!r}")
    out = np.empty(stack.shape, np.float32)
    for i in range(stack.shape[0]):
        s = stack[i]
        gz = ndimage.gaussian_filter(s, sigma_grad_px, order=(1, 0))
        gx = ndimage.gaussian_filter(s, sigma_grad_px, order=(0, 1))
        jzz = ndimage.gaussian_filter(gz * gz, sigma_tensor_px)
        jxx = ndimage.gaussian_filter(gx * gx, sigma_tensor_px)
        jxz = ndimage.gaussian_filter(gx * gz, sigma_tensor_px)
        theta = 0.5 * np.arctan2(2 * jxz, jzz - jxx)
        trace = jzz + jxx
        tiny = 1e-12 * max(float(trace.max()), 1e-300)
        coh = np.sqrt((jzz - jxx) ** 2 + 4 * jxz**2) / np.maximum(trace, tiny)
        coh = np.where(trace > tiny, coh, 0.0)
        out[i] = np.clip(np.abs(np.sin(theta)) * coh / dip_scale, 0.0, 1.0)
    return out[0] if two_d else out


def _check_section(section: ArrayLike) -> tuple[NDArray[np.float64], bool]:
    a = np.asarray(section)
    if a.ndim not in (2, 3) or a.size == 0:
        raise InputError(f"section: expected a non-empty (H, W) or (N, H, W) array, "
                         f"got shape {a.shape}")
    if not np.issubdtype(a.dtype, np.number):
        raise InputError(f"section: expected numeric amplitudes, got dtype {a.dtype}")
    stack = (a[None] if a.ndim == 2 else a).astype(np.float64, copy=False)
    if not np.isfinite(stack).all():
        raise InputError("section: contains NaN or infinite amplitudes")
    return stack, a.ndim == 2


def baseline_fault_probability(section: ArrayLike, method: str = "dip") -> NDArray[np.float32]:
    """Fault probability by the named no-learning ``method`` (one of :data:`METHODS`)."""
    if method == "dip":
        return dip_fault_probability(section)
    if method == "semblance":
        return semblance_fault_probability(section)
    raise InputError(f"method: must be one of {METHODS}, got {method!r}")


def baseline_store(store: Any, out: str, *, method: str = "dip", array: str = "seismic",
                   sigma_tensor_px: float = 4.0,
                   semblance: SemblanceBaseline | None = None, overwrite: bool = False,
                   progress: bool = False) -> tuple[int, int]:
    """Run the baseline over every completed sample of a store; write (N, H, W) probabilities.

    Parameters
    ----------
    store : str, Path or object with a ``path`` attribute (e.g. :class:`demseis.Store`)
    out : str
        ``PATH.npy`` for a NumPy file, anything else for a Zarr array. Samples of incomplete
        shards are 0. The output is written under a temporary name and renamed.
    method : ``"dip"`` (:func:`dip_fault_probability`) or ``"semblance"``
        (:func:`semblance_fault_probability` with ``semblance``).
    array : input array of the store.
    sigma_tensor_px : structure-tensor smoothing of the dip method (pixels).
    overwrite : replace an existing ``out``.

    Returns
    -------
    (done, n) : samples computed and samples in the store.
    """
    if method not in ("dip", "semblance"):
        raise InputError(f"method = {method!r}; allowed: 'dip' or 'semblance'")
    cfg = semblance or SemblanceBaseline()
    if method == "dip":
        settings: dict[str, Any] = {"method": "dip", "sigma_tensor_px": sigma_tensor_px}

        def detect(sec: np.ndarray) -> np.ndarray:
            return dip_fault_probability(sec, sigma_tensor_px=sigma_tensor_px)
    else:
        settings = {"method": "semblance", **cfg.__dict__}

        def detect(sec: np.ndarray) -> np.ndarray:
            return semblance_fault_probability(sec, cfg)
    path = str(getattr(store, "path", store))
    seis, valid = open_sections(path, array)
    if os.path.exists(out) and not overwrite:
        raise InputError(f"--out {out!r} exists; pass --overwrite to replace it")
    n, h, w = (int(v) for v in seis.shape)
    if out.endswith(".npy"):
        dest: Any = np.lib.format.open_memmap(out + ".part.npy", mode="w+", dtype=np.float32,
                                              shape=(n, h, w))
    else:
        dest = zarr_lib().create_array(out + ".part", shape=(n, h, w), chunks=(1, h, w),
                                 dtype="float32", fill_value=0.0, overwrite=True)
        dest.attrs["demseis_baseline"] = {"threshold": 0.5, **settings}
    done = np.flatnonzero(valid)
    if progress:
        done_iter: Any = tqdm(done, desc="baseline", unit="sample", file=sys.stderr)
    else:
        done_iter = done
    partial = out + (".part.npy" if out.endswith(".npy") else ".part")
    try:
        for i in done_iter:
            dest[int(i)] = detect(np.asarray(seis[int(i)]))
    except BaseException:  # a damaged chunk, Ctrl-C: no half-written output is left behind
        del dest
        if os.path.isdir(partial):
            shutil.rmtree(partial, ignore_errors=True)
        elif os.path.exists(partial):
            os.remove(partial)
        raise
    if isinstance(dest, np.memmap):  # a new memmap is zero-filled: skipped samples stay 0
        dest.flush()
        del dest
        os.replace(out + ".part.npy", out)
    else:
        if os.path.exists(out):
            shutil.rmtree(out)
        os.replace(out + ".part", out)
    return int(done.size), n
