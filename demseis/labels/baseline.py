"""A reference fault detector with no learning: the floor a model has to beat.

The attribute is *dip-scanned semblance* (Marfurt, Kirlin, Farmer & Bahorich, 1998, Geophysics
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
tune it with the ODS threshold that :func:`demseis.labels.scoring.score` reports.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from demseis.errors import InputError

__all__ = ["DEFAULT_C_REF", "DEFAULT_THRESHOLD", "SemblanceBaseline", "semblance_fault_probability"]

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
    from demseis.labels._scoring_kernels import dip_scan_semblance

    cfg = config or SemblanceBaseline()
    a = np.asarray(section)
    if a.ndim not in (2, 3) or a.size == 0:
        raise InputError(f"section: expected a non-empty (H, W) or (N, H, W) array, "
                         f"got shape {a.shape}")
    if not np.issubdtype(a.dtype, np.number):
        raise InputError(f"section: expected numeric amplitudes, got dtype {a.dtype}")
    stack = a[None] if a.ndim == 2 else a
    stack = stack.astype(np.float64, copy=False)
    if not np.isfinite(stack).all():
        raise InputError("section: contains NaN or infinite amplitudes")
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
    return out if a.ndim == 3 else out[0]
