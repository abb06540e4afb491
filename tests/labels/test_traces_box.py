"""The box and Gaussian filters of the slip-trace modules run on the bounding box of their mask
(:func:`demseis.labels.direction.box_support`): same bits at the cells that are used as the
whole-grid filters. The reference is the same code with ``box_support`` returning the whole
grid."""

from __future__ import annotations

import sys

import numpy as np
import pytest

from demseis.labels.crest import project_on_local_line, shear_field
from demseis.labels.direction import along_trace_mean, box_support, local_direction


def _whole_grid(mask, size):
    return (slice(0, mask.shape[0]), slice(0, mask.shape[1])) if mask.any() else None


def _on_whole_grid(monkeypatch, fn, *args):
    """``fn(*args)`` with ``box_support`` giving the whole grid in every labels module using it."""
    users = [m for name, m in list(sys.modules.items()) if name.startswith("demseis.labels.")
             and getattr(m, "box_support", None) is box_support]
    assert len(users) >= 2  # direction and crest at least
    with monkeypatch.context() as mp:
        for m in users:
            mp.setattr(m, "box_support", _whole_grid)
        return fn(*args)


def _masks(seed):
    """Noisy lines at random angles (some reaching the grid edges) and scattered cells."""
    rng = np.random.default_rng(seed)
    shape = (int(rng.integers(60, 140)), int(rng.integers(120, 260)))
    m = np.zeros(shape, bool)
    for _ in range(int(rng.integers(1, 4))):
        r0, c0 = rng.integers(0, shape[0]), rng.integers(0, shape[1])
        ang = rng.uniform(0, np.pi)
        t = np.arange(-80, 80)
        rr = np.rint(r0 + t * np.sin(ang) + rng.normal(0, 0.6, t.size)).astype(int)
        cc = np.rint(c0 + t * np.cos(ang) + rng.normal(0, 0.6, t.size)).astype(int)
        ok = (rr >= 0) & (rr < shape[0]) & (cc >= 0) & (cc < shape[1])
        m[rr[ok], cc[ok]] = True
    m |= rng.random(shape) < 0.002
    return m, rng


@pytest.mark.parametrize("seed", range(12))
def test_box_filters_on_the_support_equal_the_whole_grid_to_the_bit(seed, monkeypatch):
    m, rng = _masks(seed)
    t_r, t_c = local_direction(m)
    r_r, r_c = _on_whole_grid(monkeypatch, local_direction, m)
    assert t_r[m].tobytes() == r_r[m].tobytes() and t_c[m].tobytes() == r_c[m].tobytes()
    shift = rng.normal(0, 0.7, (*m.shape, 2))
    shift[rng.random(m.shape) < 0.3] = np.nan
    got = project_on_local_line(m, shift, 7)
    assert got.any() and np.array_equal(got, _on_whole_grid(monkeypatch, project_on_local_line,
                                                            m, shift, 7))
    values = rng.normal(0, 3.0, m.shape)
    ok = rng.random(m.shape) < 0.7
    got = along_trace_mean(m, values, ok)
    ref = _on_whole_grid(monkeypatch, along_trace_mean, m, values, ok)
    assert got[m].tobytes() == ref[m].tobytes() and np.isfinite(got[m & ok]).all()


def test_support_is_the_grown_bounding_box():
    m = np.zeros((50, 60), bool)
    assert box_support(m, 9) is None
    m[10, 20] = m[30, 58] = True
    assert box_support(m, 9) == (slice(5, 36), slice(15, 60))
    assert box_support(np.ones((5, 6), bool), 9) == (slice(0, 5), slice(0, 6))


@pytest.mark.parametrize("seed", range(8))
@pytest.mark.parametrize("sigma", [0.7, 2.0])
def test_shear_field_per_cohort_box_equals_the_whole_grid_to_the_bit(seed, sigma, monkeypatch):
    rng = np.random.default_rng(seed)
    nz, nx = 90, 160
    rows = np.arange(nz)[:, None] + 0 * np.arange(nx)[None, :]
    top = 8 + rng.integers(0, 6)  # rock below an irregular surface, with holes
    rock = (rows >= top + rng.integers(0, 3, (1, nx))) & (rng.random((nz, nx)) > 0.03)
    # cohorts: the pack below, and thin bands of sediment on top (as deposition makes)
    cohort = np.zeros((nz, nx), np.int64)
    b1, b2 = top + 4 + rng.integers(0, 4), top + 10 + rng.integers(0, 6)
    cohort[rows < b2] = 1
    cohort[rows < b1] = 2
    cohort[(rng.random((nz, nx)) < 0.01) & (rows < b2)] = 3  # scattered elements
    ux = np.cumsum(rng.normal(0, 1.0, (nz, nx)), axis=1) + 30.0 * (np.arange(nx) > nx // 2)
    uy = rng.normal(0, 2.0, (nz, nx)) - 15.0 * (rows > nz // 2)
    got = shear_field(ux, uy, rock, 10.0, sigma, cohort)
    ref = _on_whole_grid(monkeypatch, shear_field, ux, uy, rock, 10.0, sigma, cohort)
    assert got.tobytes() == ref.tobytes()
    assert (got[rock] > 0).mean() > 0.9
