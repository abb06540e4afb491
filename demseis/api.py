"""The Python front door: :func:`generate`, :func:`open`, :func:`score`, :func:`train`,
:func:`predict` and :class:`Store`.

Re-exported lazily by :mod:`demseis` (``demseis.generate`` ...), so ``import demseis`` stays
light; dask, torch and xarray are imported only by the calls that need them, and so are the
generator and the scoring code (``demseis.open`` needs neither)::

    import demseis
    store = demseis.generate("tiny", out="t.zarr")      # a preset, a TOML path, a dict or a Config
    print(store)                                        # samples, shape, arrays, parameters
    s = store.sample(0)                                 # {"seismic": (H, W) array, ..., "freq_hz": 20.0, ...}
    store.params["dip_deg"]                             # (N,) per-sample parameter table
    ds = store.torch_dataset(crop=128, split="train")   # a torch Dataset (FaultSegDataset)
    xr = store.to_xarray()                              # an xarray.Dataset (needs xarray)
    result = demseis.score(pred, store, by=("freq_hz",))
    result = demseis.score(pred, "picks.png", tolerance_px=2)  # against a hand-picked mask
    metrics = demseis.train(store, out="model.pt", steps=300)   # needs demseis[torch]
    metrics = demseis.train(["a.zarr", "b.zarr"], weights=[2, 1], out="ab.pt")  # a mix
    demseis.predict("model.pt", "line.sgy", out="faults.sgy")   # SEG-Y in, probability out
"""

from __future__ import annotations

import os
import warnings
from collections.abc import Mapping
from pathlib import Path
from types import ModuleType
from typing import Any

import numpy as np

from demseis.datasets import FaultSegDataset, open_store, read_sample, store_layout, to_xarray
from demseis.datasets.read import done_samples, read_params, store_summary
from demseis.errors import InputError, StoreError, import_torch
from demseis.generator.sweep.workers import start_forkserver


class Store:
    """A demseis store: its samples, per-sample parameters and views for training and analysis.

    Parameters
    ----------
    path : str or Path
        The store directory (``demseis generate --out``). It is checked on opening: a missing
        path, a foreign Zarr store or another schema version raises :class:`StoreError`.

    Attributes
    ----------
    path : Path
    layout : demseis.datasets.StoreLayout
        Shards, samples per shard, sample shape, array and parameter dtypes.
    """

    def __init__(self, path: str | Path) -> None:
        self.path = Path(path)
        self._root = open_store(self.path, "r")
        self.layout = store_layout(self._root)
        self._params: Mapping[str, np.ndarray] | None = None
        #: what :func:`generate` did (a SweepSummary), None for an opened store
        self.run_summary: Any = None

    # ---- sizes and metadata ---------------------------------------------------------------
    def __len__(self) -> int:
        """Number of samples (complete or not; see :attr:`done`)."""
        return self.layout.n_samples

    @property
    def attrs(self) -> dict[str, Any]:
        """The store's root attributes (``config``, ``grid``, ``demseis``, ``failures`` ...)."""
        return dict(self._root.attrs)

    @property
    def config(self) -> dict[str, Any]:
        """The resolved config the store was generated with."""
        return dict(self.attrs.get("config", {}))

    @property
    def arrays(self) -> tuple[str, ...]:
        """Names of the per-sample arrays (``seismic``, ``fault``, ...)."""
        return tuple(self.layout.arrays)

    @property
    def done(self) -> np.ndarray:
        """(N,) bool: the samples whose shard is complete."""
        return done_samples(self._root, len(self), self.path, require_any=False)

    @property
    def params(self) -> Mapping[str, np.ndarray]:
        """The per-sample parameter table: name -> (N,) array (categorical ones as strings).

        ``demseis params`` and ``docs/parameters.md`` describe every column.
        """
        if self._params is None:  # each (N,) column is read when first asked for
            self._params = read_params(self.path, decode=True)
        return self._params

    def sample(self, index: int) -> dict[str, Any]:
        """Sample ``index``: every array as (H, W) NumPy and every parameter as a scalar;
        ``"params"`` holds all parameters, including those named like an array (``dip_deg`` is
        the label array at the top level, the run's basement dip in ``params``).

        Raises
        ------
        InputError
            ``index`` is out of range.
        StoreError
            Its shard is not complete (nothing valid was written there).
        """
        n = len(self)
        if isinstance(index, bool) or not isinstance(index, (int, np.integer)) \
                or not -n <= index < n:
            raise InputError(f"sample {index!r} is out of range: the store has samples 0..{n - 1}")
        i = int(index) % n
        if not self.done[i]:
            raise StoreError(f"sample {i} of {str(self.path)!r} belongs to a shard that is not "
                             "complete; finish the sweep first (rerun demseis generate)")
        # checksums checked: a damaged sample is a StoreError naming the sample and the array
        sample = read_sample(self.path, i, self.arrays)
        out: dict[str, Any] = dict(sample.arrays)
        params = {k: v.item() if hasattr(v, "item") else v  # categorical ones as their names
                  for k, v in sample.params.items()}
        # a parameter named like an array (dip_deg: the run's basement dip, and the label of
        # each fault pixel's dip) leaves the array in place; every parameter is in "params"
        out.update({k: v for k, v in params.items() if k not in out})
        out["params"] = params
        return out

    def summary(self) -> str:
        """What ``demseis info`` prints: samples, shapes, parameter ranges, config, failures."""
        return "\n".join(store_summary(self.path))

    def __repr__(self) -> str:
        lay = self.layout
        h, w = lay.shape
        grid = self.attrs.get("grid", {})
        domain = grid.get("domain", "depth")
        cell = f"{grid.get('cell_m', '?')} m cells" if domain == "depth" else "time samples"
        n_done = int(self.done.sum())
        return (f"<demseis.Store {str(self.path)!r}: {len(self)} samples ({n_done} done) from "
                f"{lay.n_shards} runs ({lay.samples_per_shard} samples each); {h} x {w} {cell}; "
                f"arrays {', '.join(self.arrays)}; {len(lay.params)} per-sample parameters>")

    # ---- views ------------------------------------------------------------------------------
    def torch_dataset(self, **kwargs: Any) -> Any:
        """A PyTorch Dataset of this store (:class:`demseis.datasets.FaultSegDataset`).

        Keyword arguments go to :class:`~demseis.datasets.FaultSegDataset` (``inputs``,
        ``targets``, ``crop``, ``split``, ``where``, ``transform``, ``seed`` ...).

        Raises
        ------
        MissingExtra
            torch is not installed (``pip install "demseis[torch]"``).
        """
        import_torch("Store.torch_dataset")  # fail here, not in the first batch
        return FaultSegDataset(self.path, **kwargs)

    def to_xarray(self) -> Any:
        """The samples as a lazy :class:`xarray.Dataset` (:func:`demseis.datasets.to_xarray`):
        coordinates in metres (x, depth) or seconds (twt), units, parameters along ``sample``."""
        return to_xarray(self.path)


def _resolve_config(config: Any) -> Any:
    """A :class:`~demseis.generator.config.settings.Config` from a Config, a dict, a preset name or a
    TOML path."""
    # lazy: the config loads the label and seismic stages (Numba, SciPy; ~0.7 s), which
    # demseis.open and demseis.score never need
    from demseis.generator.config.settings import PRESETS, Config, load_config, parse_config

    if isinstance(config, Config):
        return config
    if isinstance(config, dict):
        return parse_config(config, source="config dict")
    if config is None:
        return load_config()
    if isinstance(config, str) and config in PRESETS:
        return load_config(preset=config)
    if isinstance(config, (str, Path)):
        return load_config(config)
    raise InputError(f"config {config!r}: give a preset name ({', '.join(PRESETS)}), a TOML "
                     "path, a dict or a demseis.generator.config.settings.Config")


class WorkersWarning(UserWarning):
    """More dask workers were asked for than this machine has cores."""


def workers_warning(workers: int | None) -> str | None:
    """``"workers N exceeds ..."`` when ``workers`` is more than this machine's cores, else None."""
    cores = os.cpu_count() or 1
    if workers is None or workers <= cores:
        return None
    return (f"workers {workers} exceeds the {cores} cores of this machine: the extra workers "
            "share cores with the others and only add start-up time and memory")


def generate(config: Any = None, *, out: str | Path, workers: int | None = None,
             overwrite: bool = False, scheduler: str | None = None,
             progress: bool = False) -> Store:
    """Run a sweep and write its labelled samples to the store ``out``; return the :class:`Store`.

    Rerunning with the same config on an existing store completes only the missing shards.

    Parameters
    ----------
    config : str, Path, dict or Config, optional
        A preset name (``"tiny"``, ``"quick"``, ``"seed"``), a TOML file (layered on the
        ``quick`` preset), a config dict, or a parsed Config. Default: the ``quick`` preset.
    out : the store directory.
    workers : dask worker processes (default: all cores; 0 = run in this process, no dask).
    overwrite : replace an existing store written with a different config.
    scheduler : address of an existing dask scheduler (instead of ``workers``).
    progress : show a progress bar on stderr.

    Returns
    -------
    Store
        Its ``run_summary`` attribute holds what the sweep did (runs computed, failed, timing).
        Failed runs are recorded in the store (``store.attrs["failures"]``); their samples are
        not done.
    """
    cfg = _resolve_config(config)
    if workers is not None and scheduler is not None:
        raise InputError("give either workers or scheduler, not both")
    warning = workers_warning(workers) if scheduler is None else None
    if warning:
        warnings.warn(warning, WorkersWarning, stacklevel=2)
    if scheduler is None and workers != 0:
        # its preload (imports, Numba kernels) runs while this process imports the sweep,
        # prepares the store and starts the scheduler (demseis.generator.sweep.workers)
        start_forkserver()
    # lazy: imported after start_forkserver() so that the server's preload runs meanwhile
    from demseis.generator.sweep.driver import run_sweep

    summary = run_sweep(cfg, out, workers=workers, scheduler=scheduler, overwrite=overwrite,
                        progress=progress)
    store = Store(out)
    store.run_summary = summary
    return store


def open(path: str | Path) -> Store:  # noqa: A001 - demseis.open, like xarray.open_dataset
    """Open an existing demseis store read-only."""
    return Store(path)


def score(pred: Any, store: Any, **kwargs: Any) -> Any:
    """Score fault predictions against a store's labels
    (:func:`demseis.evaluation.store_scoring.score_store`), or against a hand-picked mask
    (:func:`demseis.evaluation.store_scoring.score_mask`).

    Parameters
    ----------
    pred : (N_pred, H, W) array of probabilities in [0, 1], or a ``.npy`` / Zarr / SEG-Y path
        ((H, W) too against a mask).
    store : a :class:`Store` or its path; or a mask: a ``.npy``, ``.png``, ``.sgy`` or
        ``.segy`` file (:func:`demseis.evaluation.fieldio.read_masks` says which pixels are
        faults) or an array (H, W) / (N, H, W), nonzero on a fault.
    **kwargs : ``indices``, ``threshold``, ``tolerance_px``, ``by``, ``bins``, ``thresholds``,
        ``progress``; against a mask ``threshold``, ``tolerance_px``, ``thresholds``,
        ``progress`` and ``resize`` (resample the predictions onto the mask's grid).

    Returns
    -------
    demseis.evaluation.store_scoring.StoreScore
        ``.overall`` (precision, recall, F1, IoU, ODS/OIS/AP), ``.rows`` per group,
        ``.table()``, ``.write(prefix)``. The same protocol and fields for a mask, with the
        overall group only.
    """
    # lazy: SciPy, which open() never needs
    from demseis.evaluation.fieldio import is_mask_file
    from demseis.evaluation.store_scoring import score_mask, score_store

    is_path = isinstance(store, (str, Path))
    if is_path and os.path.isfile(store) and not is_mask_file(store):
        raise InputError(f"{str(store)!r} is a file but neither a store (a directory) nor a "
                         "mask (.npy, .png, .sgy or .segy)")
    if (is_path and is_mask_file(store)) or (not is_path and not isinstance(store, Store)
                                             and hasattr(store, "shape")):
        for name in ("by", "indices"):
            if kwargs.pop(name, None):
                raise InputError(f"{name}: a mask has no store samples or parameters; "
                                 f"{name} goes with a store")
        kwargs.pop("bins", None)
        return score_mask(pred, store, **kwargs)
    if kwargs.pop("resize", False):
        raise InputError("resize: predictions are resampled onto a mask's grid, not a store's")
    return score_store(pred, store, **kwargs)


def train(store: Any, out: str | Path = "model.pt", **kwargs: Any) -> dict[str, Any]:
    """Train the fault-segmentation U-Net on a store, or on several; write ``out``,
    ``out.json``, ``out.ckpt``.

    Whole runs are held out: the model kept is the best on the validation runs, and the
    returned metrics (precision, recall, F1, IoU, AP at a 2-pixel tolerance) are those of the
    test runs. Needs torch (``pip install "demseis[torch]"``) and stores of at least 3 runs.

    Parameters
    ----------
    store : a :class:`Store` or its path, or a list of them: each is split by its own runs,
        the batches draw from their train runs in proportion to ``weights``, and the metrics
        cover every store's test runs (pooled, and per store in ``metrics["per_store"]``).
    out : the model file.
    **kwargs : ``weights`` (one positive number per store; default equal), ``steps`` (300),
        ``crop``, ``batch``, ``base``, ``lr``, ``seed``, ``device``, ``val_every``,
        ``save_every``, ``resume``, ``threads``, ``progress``, ``log``, ``ignore`` and
        ``ignore_values`` (:func:`demseis.learning.model.train_model`).
    """
    train_model = _learning_model().train_model
    if isinstance(store, (list, tuple)):
        return train_model([str(getattr(s, "path", s)) for s in store], out, **kwargs)
    return train_model(str(getattr(store, "path", store)), out, **kwargs)


def _learning_model() -> ModuleType:
    """:mod:`demseis.learning.model`, imported at the first call: it imports torch (about 2 s,
    and an optional extra), which generating, opening and scoring never need."""
    from demseis.learning import model  # lazy: torch

    return model


def predict(model: Any, source: Any, out: str | Path | None = None, *,
            device: str | None = None, overwrite: bool = False, progress: bool = False,
            mask: str | Path | None = None, threshold: float | None = None) -> Any:
    """Fault probability of seismic sections with a model from :func:`train`.

    Parameters
    ----------
    model : the model file (``model.pt``) or a model loaded by
        :func:`demseis.learning.model.load_model`; None: the model shipped with demseis
        (:data:`demseis.learning.model.PRETRAINED`, docs/model.md).
    source : a SEG-Y file (``.sgy``, ``.segy``: a 2-D line, or a 3-D cube predicted along its
        inlines and crosslines, :func:`demseis.learning.model.predict_cube`), a ``.npy``
        file, or an array (H, W) or (N, H, W) of any size.
    out : where to write (``.sgy`` with the input's headers, or ``.npy``); None returns the
        probabilities as an array of the input's shape (a SEG-Y section as (samples, traces);
        a cube needs ``out``).
    device : ``"cpu"``, ``"cuda"`` ... (default: CUDA when available).
    overwrite : replace an existing ``out`` (and ``mask``).
    progress : a progress bar over a cube's lines.
    mask : with ``out``, also write the faults as 1 where the probability reaches
        ``threshold`` and 0 elsewhere (``.sgy`` or ``.npy``, as ``out``).
    threshold : the mask's threshold (default: the one saved with the model, chosen on its
        validation runs; :func:`demseis.learning.model.model_threshold`).

    Returns
    -------
    Path of ``out``, or the probability array when ``out`` is None.
    """
    m = _learning_model()
    if model is None:
        model = m.pretrained_path()
    if out is not None:  # the paths are checked before the model is loaded
        return m.predict_file(model, source, out, device=device, overwrite=overwrite,
                              progress=progress, mask=mask, threshold=threshold)
    if mask is not None:
        raise InputError("mask: give out as well (the probability file written beside it)")
    net = m.load_model(model, device) if isinstance(model, (str, Path)) else model
    if isinstance(source, (str, Path)):
        data = m.read_segy_section(source) if m.is_segy(source) else np.load(source)
    else:
        data = np.asarray(source)
    return m.predict_array(net, data)


__all__ = ["Store", "generate", "open", "predict", "score", "train"]
