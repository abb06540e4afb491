"""Rock properties of layers and elements, and the smoothed property grids.

Model
-----
Each layer (0 = deepest; growth layers of deposited elements follow the pre-kinematic ones)
gets a lithology drawn with ``lithology_weights``; its mean Vp is uniform in that
lithology's ``[vp_min_m_s, vp_max_m_s]``; its density is Gardner's ``rho = a vp^b``
(``density="gardner"``, rho in kg/m^3 for Vp in m/s, a = 310, b = 0.25) or uniform in the
lithology's ``[rho_min_kg_m3, rho_max_kg_m3]`` (``density="range"``). Growth layers are drawn
from the same lithology ranges, so deposited elements inherit the property ranges of the
model's layers. Every element then scatters around its layer's values:
``vp_e = vp_L (1 + vp_scatter n1)``, ``rho_e = rho_L (1 + rho_scatter n2)`` with n1, n2
independent standard normals clipped at +-3, drawn from a hash of (seed, element id), so an
element keeps its values in every snapshot.

Grids
-----
The element values are rasterised (mean of the elements whose disk contains the cell centre),
empty cells take the background (the mean of the nearest element's layer, or the global
mean), then a light Gaussian filter and a small median filter are applied to Vp and density.
"""

from __future__ import annotations

from dataclasses import dataclass, fields

import numpy as np

from demseis.errors import ConfigError, InputError
from demseis.seismic import _kernels
from demseis.types import Grid
from demseis.seismic.raster import rasterise


@dataclass(frozen=True)
class PropertyModel:
    """Configurable rock-property model (a TOML ``[properties]`` table maps 1:1 onto it).

    Per-lithology fields are tuples with one entry per name in ``lithologies``.

    Attributes
    ----------
    lithologies : names of the lithologies (1 to 16, unique).
    lithology_weights : relative probability of each lithology for a layer (>= 0, sum > 0).
    vp_min_m_s, vp_max_m_s : Vp range of each lithology (m/s), 1200 <= min <= max <= 8000.
    density : ``"gardner"`` (rho = gardner_a * vp ** gardner_b) or ``"range"`` (uniform in
        [rho_min_kg_m3, rho_max_kg_m3] of the lithology).
    gardner_a : Gardner coefficient for rho in kg/m^3 and Vp in m/s, 100 to 1000 (310 standard).
    gardner_b : Gardner exponent, 0.1 to 0.5 (0.25 standard).
    rho_min_kg_m3, rho_max_kg_m3 : density range of each lithology (kg/m^3), 1000 <= min <=
        max <= 3500; used when ``density == "range"``.
    vp_scatter : relative standard deviation of per-element Vp around the layer Vp, 0 to 0.2.
    rho_scatter : relative standard deviation of per-element density, 0 to 0.2.
    background : value of cells no element covers: ``"layer"`` (mean of the layer of the
        nearest element) or ``"global"`` (mean of all elements).
    gaussian_sigma_cells : standard deviation of the Gaussian filter in cells, 0 (off) to 5.
    median_size_cells : width of the square median filter in cells, odd, 1 (off) to 9.
    """

    lithologies: tuple[str, ...] = ("shale", "sandstone", "limestone")
    lithology_weights: tuple[float, ...] = (0.45, 0.40, 0.15)
    vp_min_m_s: tuple[float, ...] = (2200.0, 2600.0, 3800.0)
    vp_max_m_s: tuple[float, ...] = (3200.0, 4000.0, 5500.0)
    density: str = "gardner"
    gardner_a: float = 310.0
    gardner_b: float = 0.25
    rho_min_kg_m3: tuple[float, ...] = (2250.0, 2100.0, 2450.0)
    rho_max_kg_m3: tuple[float, ...] = (2550.0, 2450.0, 2700.0)
    vp_scatter: float = 0.03
    rho_scatter: float = 0.01
    background: str = "layer"
    gaussian_sigma_cells: float = 0.7
    median_size_cells: int = 3

    def __post_init__(self) -> None:
        # TOML arrays arrive as lists: store tuples so the model stays hashable and frozen.
        for f in fields(self):
            v = getattr(self, f.name)
            if isinstance(v, list):
                object.__setattr__(self, f.name, tuple(v))

    @property
    def n_lithologies(self) -> int:
        return len(self.lithologies)

    @property
    def vp_lower_bound_m_s(self) -> float:
        """The smallest Vp an element (and so a smoothed cell) can take: min Vp (1 - 3 scatter)."""
        return float(min(self.vp_min_m_s)) * (1.0 - 3.0 * float(self.vp_scatter))

    def validate(self) -> "PropertyModel":
        """Check every field; raise :class:`ConfigError` naming field, value and allowed range.

        Returns ``self`` so it can be chained.
        """
        n = len(self.lithologies) if isinstance(self.lithologies, tuple) else -1
        if not (1 <= n <= 16) or not all(isinstance(s, str) and s for s in self.lithologies):
            raise ConfigError(f"properties.lithologies = {self.lithologies!r}: allowed is a list "
                              "of 1 to 16 non-empty names")
        if len(set(self.lithologies)) != n:
            raise ConfigError(f"properties.lithologies = {self.lithologies!r}: names must be "
                              "unique")
        per_lith = {
            "lithology_weights": (0.0, float("inf")),
            "vp_min_m_s": (1200.0, 8000.0),
            "vp_max_m_s": (1200.0, 8000.0),
            "rho_min_kg_m3": (1000.0, 3500.0),
            "rho_max_kg_m3": (1000.0, 3500.0),
        }
        for name, (lo, hi) in per_lith.items():
            v = getattr(self, name)
            if not isinstance(v, tuple) or len(v) != n:
                raise ConfigError(f"properties.{name} = {v!r}: allowed is a list of {n} numbers "
                                  f"(one per lithology {self.lithologies})")
            for x in v:
                if isinstance(x, bool) or not isinstance(x, (int, float)) or not lo <= x <= hi:
                    raise ConfigError(f"properties.{name} = {v!r}: every entry must be a number "
                                      f"in [{lo}, {hi}]")
        if sum(self.lithology_weights) <= 0:
            raise ConfigError(f"properties.lithology_weights = {self.lithology_weights!r}: "
                              "allowed are weights >= 0 with a positive sum")
        for a, b, unit in (("vp_min_m_s", "vp_max_m_s", "m/s"),
                           ("rho_min_kg_m3", "rho_max_kg_m3", "kg/m^3")):
            for k, (lo, hi) in enumerate(zip(getattr(self, a), getattr(self, b))):
                if lo > hi:
                    raise ConfigError(f"properties.{a}[{k}] = {lo} {unit} exceeds properties.{b}"
                                      f"[{k}] = {hi}: allowed is {a} <= {b}")
        _choice("density", self.density, ("gardner", "range"))
        _choice("background", self.background, ("layer", "global"))
        _number("gardner_a", self.gardner_a, 100.0, 1000.0)
        _number("gardner_b", self.gardner_b, 0.1, 0.5)
        _number("vp_scatter", self.vp_scatter, 0.0, 0.2)
        _number("rho_scatter", self.rho_scatter, 0.0, 0.2)
        _number("gaussian_sigma_cells", self.gaussian_sigma_cells, 0.0, 5.0)
        m = self.median_size_cells
        if isinstance(m, bool) or not isinstance(m, (int, np.integer)) or not (1 <= m <= 9) \
                or m % 2 == 0:
            raise ConfigError(f"properties.median_size_cells = {m!r}: allowed is an odd integer "
                              "in [1, 9] (1 = no median filter)")
        return self


def _choice(name: str, value, allowed: tuple[str, ...]) -> None:
    if value not in allowed:
        raise ConfigError(f"properties.{name} = {value!r}: allowed is one of {allowed}")


def _number(name: str, value, lo: float, hi: float) -> None:
    if isinstance(value, bool) or not isinstance(value, (int, float, np.floating)) \
            or not np.isfinite(value) or not lo <= value <= hi:
        raise ConfigError(f"properties.{name} = {value!r}: allowed is a number in [{lo}, {hi}]")


@dataclass(frozen=True)
class LayerProperties:
    """Properties of every layer index of a run (0 = deepest, growth layers included).

    Attributes
    ----------
    lithology : (L,) int16 index into ``PropertyModel.lithologies``.
    vp : (L,) float64 layer Vp (m/s).
    rho : (L,) float64 layer density (kg/m^3).
    """

    lithology: np.ndarray
    vp: np.ndarray
    rho: np.ndarray

    @property
    def n_layers(self) -> int:
        return int(self.vp.shape[0])


def draw_layer_properties(n_layers_total: int, model: PropertyModel,
                          rng: np.random.Generator) -> LayerProperties:
    """Draw a lithology, Vp and density for each of ``n_layers_total`` layers.

    Three uniforms per layer are taken in layer order (``rng.random((L, 3))``), so the first
    layers get the same values whatever the number of growth layers after them.

    Parameters
    ----------
    n_layers_total : number of layer indices (pre-kinematic plus growth layers), >= 1.
    model : the property model (validated here).
    rng : random generator.
    """
    model.validate()
    if isinstance(n_layers_total, bool) or not isinstance(n_layers_total, (int, np.integer)) \
            or n_layers_total < 1:
        raise InputError(f"n_layers_total must be an integer >= 1, got {n_layers_total!r}")
    u = rng.random((int(n_layers_total), 3))
    w = np.asarray(model.lithology_weights, dtype=np.float64)
    cdf = np.cumsum(w) / w.sum()
    lith = np.minimum(np.searchsorted(cdf, u[:, 0], side="right"), w.size - 1)
    vmin = np.asarray(model.vp_min_m_s, dtype=np.float64)[lith]
    vmax = np.asarray(model.vp_max_m_s, dtype=np.float64)[lith]
    vp = vmin + u[:, 1] * (vmax - vmin)
    if model.density == "gardner":
        rho = model.gardner_a * vp ** model.gardner_b
    else:
        rmin = np.asarray(model.rho_min_kg_m3, dtype=np.float64)[lith]
        rmax = np.asarray(model.rho_max_kg_m3, dtype=np.float64)[lith]
        rho = rmin + u[:, 2] * (rmax - rmin)
    return LayerProperties(lithology=lith.astype(np.int16), vp=vp, rho=rho)


_GOLDEN = np.uint64(0x9E3779B97F4A7C15)
_M1 = np.uint64(0xBF58476D1CE4E5B9)
_M2 = np.uint64(0x94D049BB133111EB)


def _splitmix64(x: np.ndarray) -> np.ndarray:
    """The SplitMix64 finaliser on a uint64 array (wrapping arithmetic): a 64-bit hash."""
    z = x + _GOLDEN
    z = (z ^ (z >> np.uint64(30))) * _M1
    z = (z ^ (z >> np.uint64(27))) * _M2
    return z ^ (z >> np.uint64(31))


def _hash_normals(ids: np.ndarray, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """Two independent standard normals per id, a pure function of (seed, id) (Box-Muller)."""
    with np.errstate(over="ignore"):
        key = _splitmix64(np.atleast_1d(np.uint64(seed % (1 << 64))))[0]
        h = _splitmix64(ids.astype(np.uint64) ^ key)
        h1 = _splitmix64(h ^ np.uint64(1))
        h2 = _splitmix64(h ^ np.uint64(2))
    scale = 2.0 ** -53
    u1 = ((h1 >> np.uint64(11)).astype(np.float64) + 0.5) * scale   # (0, 1)
    u2 = (h2 >> np.uint64(11)).astype(np.float64) * scale
    r = np.sqrt(-2.0 * np.log(u1))
    return r * np.cos(2.0 * np.pi * u2), r * np.sin(2.0 * np.pi * u2)


def element_properties(ids: np.ndarray, layer: np.ndarray, layer_props: LayerProperties,
                       model: PropertyModel, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """Per-element Vp and density: the layer's values with per-element scatter.

    ``vp_e = vp[layer] (1 + vp_scatter n1)``, ``rho_e = rho[layer] (1 + rho_scatter n2)``,
    n1, n2 standard normals clipped at +-3 drawn from a hash of ``(seed, id)``: the same id
    gets the same values in every snapshot of a run, whatever the element order.

    Parameters
    ----------
    ids : (n,) int64 element ids (>= 0).
    layer : (n,) integer layer index of each element, < ``layer_props.n_layers``.
    layer_props : from :func:`draw_layer_properties`.
    model : the property model.
    seed : integer seed of the run (>= 0).

    Returns
    -------
    vp_e (n,) float64 m/s, rho_e (n,) float64 kg/m^3.
    """
    ids = np.asarray(ids)
    layer = np.asarray(layer)
    if ids.ndim != 1 or layer.shape != ids.shape:
        raise InputError(f"ids and layer must be (n,) arrays, got {ids.shape} and {layer.shape}")
    if not (np.issubdtype(ids.dtype, np.integer) and np.issubdtype(layer.dtype, np.integer)):
        raise InputError(f"ids and layer must be integer arrays, got {ids.dtype}, {layer.dtype}")
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
        raise InputError(f"seed must be an integer >= 0, got {seed!r}")
    if ids.size and (ids.min() < 0):
        raise InputError(f"element ids must be >= 0, got minimum {ids.min()}")
    if layer.size and (layer.min() < 0 or layer.max() >= layer_props.n_layers):
        raise InputError(
            f"layer indices must be in [0, {layer_props.n_layers - 1}] (layer_props covers "
            f"{layer_props.n_layers} layers), got [{layer.min()}, {layer.max()}]"
        )
    n1, n2 = _hash_normals(ids, int(seed))
    vp = layer_props.vp[layer] * (1.0 + model.vp_scatter * np.clip(n1, -3.0, 3.0))
    rho = layer_props.rho[layer] * (1.0 + model.rho_scatter * np.clip(n2, -3.0, 3.0))
    return vp, rho


def gaussian_weights(sigma_cells: float, truncate: float = 4.0) -> np.ndarray:
    """Normalised Gaussian weights of ``scipy.ndimage.gaussian_filter`` (radius
    ``int(truncate sigma + 0.5)``)."""
    radius = int(truncate * float(sigma_cells) + 0.5)
    x = np.arange(-radius, radius + 1, dtype=np.float64)
    w = np.exp(-0.5 * (x / sigma_cells) ** 2)
    return w / w.sum()


def smooth(field: np.ndarray, model: PropertyModel) -> np.ndarray:
    """Gaussian filter (``gaussian_sigma_cells``) then median filter (``median_size_cells``),
    both with edge replication; equal to ``scipy.ndimage.gaussian_filter(mode="nearest")``
    followed by ``scipy.ndimage.median_filter(mode="nearest")``."""
    a = np.ascontiguousarray(field, dtype=np.float64)
    if model.gaussian_sigma_cells > 0:
        out = np.empty_like(a)
        _kernels.correlate_rows_cols(a, gaussian_weights(model.gaussian_sigma_cells), out)
        a = out
    if model.median_size_cells > 1:
        out = np.empty_like(a)
        _kernels.median_filter_square(a, int(model.median_size_cells), out)
        a = out
    return a


def _buckets(xy: np.ndarray, grid: Grid, bucket_m: float | None):
    """Bucket grid of element centres for the nearest-element search."""
    x = np.ascontiguousarray(xy[:, 0], dtype=np.float64)
    y = np.ascontiguousarray(xy[:, 1], dtype=np.float64)
    x_lo, y_lo = float(x.min()), float(y.min())
    span_x = float(x.max()) - x_lo
    span_y = float(y.max()) - y_lo
    if bucket_m is None:
        spacing = np.sqrt(max(span_x * span_y, 1.0) / x.size)
        bucket_m = max(spacing, grid.cell_m)
    nbx = int(span_x // bucket_m) + 1
    nby = int(span_y // bucket_m) + 1
    key = (np.floor((y - y_lo) / bucket_m).astype(np.int64) * nbx
           + np.floor((x - x_lo) / bucket_m).astype(np.int64))
    order = np.argsort(key, kind="stable").astype(np.int64)
    start = np.searchsorted(key[order], np.arange(nbx * nby + 1)).astype(np.int64)
    return x, y, order, start, x_lo, y_lo, float(bucket_m), nbx, nby


def nearest_element_index(xy: np.ndarray, grid: Grid, want: np.ndarray,
                          bucket_m: float | None = None) -> np.ndarray:
    """Index of the element whose centre is nearest to each wanted cell centre (-1 elsewhere).

    Exact (ties: lowest index), by a ring search over a bucket grid of side ``bucket_m``
    (default: the mean element spacing, at least one cell).
    """
    xy = np.asarray(xy, dtype=np.float64)
    idx = np.full(grid.shape, -1, dtype=np.int64)
    ii, jj = np.nonzero(np.asarray(want, dtype=bool))
    if ii.size == 0:
        return idx
    b = _buckets(xy, grid, bucket_m)
    out = np.empty(ii.size, dtype=np.int64)
    _kernels.nearest_element_cells(*b, grid.x_centres()[jj], grid.y_centres()[ii], out)
    idx[ii, jj] = out
    return idx


def fill_background(mean: np.ndarray, count: np.ndarray, xy: np.ndarray, values: np.ndarray,
                    layer: np.ndarray, grid: Grid, mode: str) -> np.ndarray:
    """Fill the empty cells (``count == 0``) of rasterised ``mean`` (nz, nx, k) in place.

    ``mode="global"``: the mean of all elements; ``"layer"``: the mean of the elements of the
    layer of the element whose centre is nearest to the cell centre (exact nearest search).
    """
    values = np.asarray(values, dtype=np.float64)
    if mode == "global":
        _kernels.fill_empty_constant(mean, count, values.mean(axis=0))
        return mean
    layer = np.asarray(layer, dtype=np.int64)
    n_layers = int(layer.max()) + 1
    counts = np.bincount(layer, minlength=n_layers).astype(np.float64)
    layer_mean = np.stack([np.bincount(layer, weights=values[:, c], minlength=n_layers)
                           for c in range(values.shape[1])], axis=1)
    layer_mean /= np.maximum(counts, 1.0)[:, None]
    b = _buckets(np.asarray(xy, dtype=np.float64), grid, None)
    _kernels.fill_empty_from_layer(mean, count, *b, float(grid.x0_m), float(grid.top_m),
                                   float(grid.cell_m), layer, layer_mean)
    return mean


def property_grids(xy: np.ndarray, radius: np.ndarray, vp_e: np.ndarray, rho_e: np.ndarray,
                   layer: np.ndarray, grid: Grid,
                   model: PropertyModel) -> tuple[np.ndarray, np.ndarray]:
    """Vp and density on the grid: rasterise, fill the background, Gaussian, then median.

    Parameters
    ----------
    xy : (n, 2) element centres (m), y up.
    radius : (n,) radii (m).
    vp_e, rho_e : (n,) element Vp (m/s) and density (kg/m^3).
    layer : (n,) integer layer index (for the ``"layer"`` background).
    grid : the target grid.
    model : the property model (background and filter settings).

    Returns
    -------
    vp_g, rho_g : (nz, nx) float64 grids, row 0 at the top.
    """
    xy = np.asarray(xy, dtype=np.float64)
    vp_e = np.asarray(vp_e, dtype=np.float64)
    rho_e = np.asarray(rho_e, dtype=np.float64)
    layer = np.asarray(layer)
    n = xy.shape[0] if xy.ndim == 2 else -1
    if n < 1 or vp_e.shape != (n,) or rho_e.shape != (n,) or layer.shape != (n,):
        raise InputError(
            f"property_grids: expected xy (n, 2) with n >= 1 and vp_e, rho_e, layer (n,); got "
            f"{xy.shape}, {vp_e.shape}, {rho_e.shape}, {layer.shape}"
        )
    if not (np.all(vp_e > 0) and np.all(rho_e > 0)):
        raise InputError("vp_e and rho_e must be > 0 for every element")
    values = np.column_stack([vp_e, rho_e])
    mean, count = rasterise(xy, radius, values, grid)
    fill_background(mean, count, xy, values, layer.astype(np.int64), grid, model.background)
    return smooth(mean[:, :, 0], model), smooth(mean[:, :, 1], model)
