"""``demseis train`` and ``demseis predict``: a fault-segmentation U-Net from a store to a file,
and from the file to the fault probability of any section (a store's, or your SEG-Y).

::

    from demseis.learning.model import train_model, predict_file
    metrics = train_model("quick.zarr", "model.pt", steps=300)  # held-out precision, recall, F1, AP
    metrics = train_model(["a.zarr", "b.zarr"], "ab.pt", weights=[2, 1])   # a mix of two stores
    predict_file("model.pt", "line.sgy", "faults.sgy")          # probability with line.sgy's headers
    predict_file("model.pt", "line.sgy", "p.sgy", mask="m.sgy") # and 0/1 at the model's threshold

Training is :func:`demseis.learning.train.train_unet` on the store's ``train`` runs; the model
kept is the best on the ``val`` runs, and the metrics are those of the ``test`` runs (never seen
in training or selection), scored by :func:`demseis.evaluation.store_scoring.score_store` at a
tolerance of :data:`TOLERANCE_PX` pixels. The three splits are whole runs
(:func:`demseis.datasets.split_of_shards`), so a store needs at least three runs. Several
stores train one model: each is split by its own runs, batches draw from their train runs in
proportion to ``weights``, and validation and the test metrics cover every store (pooled, and
per store in ``per_store``).

The model's threshold: a network's probabilities run as high as its training labels were dense
(a model trained on DEM labels puts most of a field section above 0.5), so 0.5 is no threshold
to read every model at. :func:`choose_threshold` picks the one that maximises F1 at
:data:`TOLERANCE_PX` on the validation runs (the sweep of :func:`demseis.evaluation.score`);
:func:`train_model` saves it in the model file and reports the test runs at it, and
:func:`predict_file` draws the fault mask there. :func:`set_threshold` chooses and saves one for
a model made without (``demseis threshold MODEL STORE``).

Files: ``OUT`` (``torch.save`` of a dict: the weights, the U-Net width, what it was trained on
and its metrics), ``OUT`` with the suffix ``.json`` (the metrics and settings), and ``OUT.ckpt``
(the training state every ``save_every`` steps, which ``resume=True`` continues from).
torch is imported inside the functions (the ``[torch]`` extra).
"""

from __future__ import annotations

import json
import os
import sys
from collections.abc import Callable, Sequence
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np
from tqdm import tqdm

from demseis.datasets import FaultSegDataset, open_store, store_layout
from demseis.errors import InputError, import_torch
from demseis.evaluation.scoring import SampleCounts, summarise
from demseis.evaluation.segyfile import (cube_geometry, is_segy, open_cube, read_crossline,
                                         read_inline, read_segy_section, write_segy_cube_like,
                                         write_segy_like)
from demseis.evaluation.store_scoring import score_store
from demseis.learning.train import (build_unet, check_pos_weight, check_weights, predict_sections,
                                    train_unet)

#: the model file's format tag and version
FORMAT = "demseis-unet"
VERSION = 1
#: matching distance (pixels) of the held-out metrics, as in training's validation
TOLERANCE_PX = 2
#: the default square training crop, cut to the sections' smaller side on smaller stores
DEFAULT_CROP = 96
#: the threshold of a model file that carries none (made before models carried one)
DEFAULT_THRESHOLD = 0.5
#: prediction tiles (pixels, square) and their overlap, for sections larger than a tile
TILE, OVERLAP = 512, 64


def metrics_path(out: str | Path) -> Path:
    """The JSON written beside the model ``out`` (``model.pt`` -> ``model.json``)."""
    return Path(out).with_suffix(".json")


def checkpoint_path(out: str | Path) -> Path:
    """The training state written beside the model ``out`` (``model.pt`` -> ``model.pt.ckpt``)."""
    return Path(f"{out}.ckpt")


def check_trainable(store: str | Path, crop: int | None) -> int:
    """The training crop for ``store``; InputError with the reason when it cannot be trained on.

    The store needs a ``seismic`` and a ``fault`` array, at least three runs (train,
    validation and test are whole runs) with complete samples in each split, and sections of
    at least 4 x 4 pixels. ``crop`` None picks :data:`DEFAULT_CROP`, cut to the sections'
    smaller side (a multiple of 4); a given ``crop`` must fit.
    """
    layout = store_layout(open_store(Path(store), "r"))
    missing = [a for a in ("seismic", "fault") if a not in layout.arrays]
    if missing:
        raise InputError(f"store {str(store)!r} has no {' or '.join(missing)} array to train on")
    if layout.n_shards < 3:
        raise InputError(f"store {str(store)!r} has {layout.n_shards} run(s); training needs at "
                         "least 3 (whole runs are held out for validation and testing): "
                         "generate more runs (sweep.n_runs)")
    for split in ("train", "val", "test"):
        if len(FaultSegDataset(store, inputs=("seismic",), targets=("fault",), split=split)) == 0:
            raise InputError(f"store {str(store)!r}: the {split} runs have no complete sample; "
                             "finish the sweep first (rerun demseis generate)")
    side = min(layout.shape)
    if side < 4:
        raise InputError(f"store {str(store)!r}: sections of {layout.shape[0]} x "
                         f"{layout.shape[1]} pixels are too small to train on (at least 4 x 4)")
    fit = side - side % 4
    if crop is None:
        return min(DEFAULT_CROP, fit)
    if crop < 4 or crop % 4 or crop > side:
        raise InputError(f"--crop {crop}: use a multiple of 4 from 4 to {fit} (the sections of "
                         f"{str(store)!r} are {layout.shape[0]} x {layout.shape[1]} pixels)")
    return int(crop)


def _pos_weight(pos_weight: float | Sequence[float], n_stores: int) -> float | list[float]:
    """``--pos-weight`` checked: one number > 0 (a float), or one per store (a list of
    floats); InputError naming ``--pos-weight`` otherwise."""
    try:
        check_pos_weight(pos_weight, n_stores)
    except InputError:
        shown = pos_weight if np.ndim(pos_weight) == 0 else ",".join(map(str, pos_weight))
        raise InputError(f"--pos-weight {shown}: use a number > 0, or one per store "
                         f"({n_stores} here), comma-separated") from None
    return float(pos_weight) if np.ndim(pos_weight) == 0 else [float(w) for w in pos_weight]


def train_model(store: str | Path | Sequence[str | Path], out: str | Path, *, steps: int = 300,
                crop: int | None = None, batch: int = 8, base: int = 16, lr: float = 2e-3,
                seed: int = 0, device: str | None = None, val_every: int | None = None,
                save_every: int = 50, resume: bool = False, threads: int | None = None,
                progress: bool = True, log: Callable[[str], None] | None = print,
                weights: Sequence[float] | None = None, ignore: str | None = None,
                ignore_values: Sequence[int] | None = None,
                select: str = "ods_f1",
                pos_weight: float | Sequence[float] | None = None) -> dict[str, Any]:
    """Train the U-Net on ``store`` (or several stores) and write it to ``out``; return the
    held-out metrics.

    Parameters
    ----------
    store : a demseis store with ``seismic`` and ``fault`` arrays and at least three runs, or
        a list of such stores. Each store is split by its own runs; the batches draw from
        each store's train runs in proportion to ``weights``, validation pools every store's
        val runs, and the metrics cover every store's test runs (overall and per store).
    out : the model file (``model.pt``); ``model.json`` and ``model.pt.ckpt`` go beside it.
    steps : optimiser steps in all (with ``resume``, counted from the first start).
    crop : square training crop (default: 96, or the smallest sections' smaller side when
        less).
    batch, base, lr, seed : batch size, U-Net width, Adam learning rate, seed.
    device : ``"cpu"``, ``"cuda"``, ``"cuda:1"`` ... (default: CUDA when available).
    val_every : validate on the ``val`` runs every this many steps and keep the best model
        (default: 5 times per training).
    save_every : write the training state to ``out.ckpt`` every this many steps.
    resume : continue from ``out.ckpt`` (InputError when there is none, or when it was
        trained on other stores, weights or width).
    threads : torch CPU threads.
    progress : a progress bar on stderr.
    log : called with progress lines (None: silent).
    weights : one positive weight per store (default: equal); store s gives the share
        ``weights[s] / sum(weights)`` of the training samples drawn.
    ignore, ignore_values : a label array whose pixels (with these values; None: any
        non-zero) are left out of the training loss, in the stores that hold it
        (:func:`demseis.learning.train.train_unet`); the test metrics still score every
        pixel against ``fault``.
    select : the validation score that picks the step kept: ``"ods_f1"`` (F1 at the
        model's best threshold, the threshold then saved with it) or ``"f1"`` (F1 at 0.5, as
        models were picked before they carried a threshold).
    pos_weight : the weight of fault pixels in the training loss (None: the background /
        fault ratio of the first batches, at most 50;
        :func:`demseis.learning.train.train_unet`), or one weight per store.

    Returns
    -------
    dict
        ``precision``, ``recall``, ``f1``, ``iou``, ``ap`` (average precision over thresholds)
        on the test runs of every store pooled, at threshold 0.5 and :data:`TOLERANCE_PX`;
        ``per_store`` (the same per store, with its weight, share and training samples
        drawn); ``stores`` and ``weights``; the training settings; ``pos_weight`` (the loss's
        weight of fault pixels, given or measured); ``chosen_threshold``
        (:func:`choose_threshold` on the validation runs: the threshold saved with the model)
        and ``at_chosen_threshold`` (precision, recall, F1, IoU of the pooled test runs at
        it). The same dict is written to ``out.json`` and kept in the model file.
    """
    torch = import_torch("demseis train")
    if steps < 1:
        raise InputError(f"--steps {steps}: use at least 1")
    for name, value in (("batch", batch), ("base", base), ("save-every", save_every)):
        if value < 1:
            raise InputError(f"--{name} {value}: use at least 1")
    if val_every is not None and val_every < 1:
        raise InputError(f"--val-every {val_every}: use at least 1")
    stores = [str(s) for s in store] if isinstance(store, (list, tuple)) else [str(store)]
    if not stores:
        raise InputError("no store to train on")
    if pos_weight is not None:
        pos_weight = _pos_weight(pos_weight, len(stores))
    shares = check_weights(weights, len(stores))
    weights = [1.0] * len(stores) if weights is None else [float(w) for w in weights]
    resolved = [str(Path(s).resolve()) for s in stores]
    twice = sorted({s for s in stores if resolved.count(str(Path(s).resolve())) > 1})
    if twice:
        raise InputError(f"store {twice[0]!r} is given twice; give each store once and "
                         "--weights to weigh it")
    crop = min(check_trainable(s, crop) for s in stores)
    out = Path(out)
    if not out.parent.is_dir():
        raise InputError(f"--out {str(out)!r}: its directory does not exist")
    ckpt = checkpoint_path(out)
    # "store": what a single store's model.json said before several stores could be given
    settings: dict[str, Any] = {**({"store": resolved[0]} if len(stores) == 1 else {}),
                                "stores": resolved, "weights": weights, "steps": steps,
                                "crop": crop, "batch": batch, "base": base, "lr": lr,
                                "seed": seed}
    if ignore is not None:  # only then: the settings of a training without it stay as they were
        settings["ignore"] = [ignore, None if ignore_values is None
                              else [int(v) for v in ignore_values]]
    settings["select"] = select
    if pos_weight is not None:  # likewise
        settings["pos_weight"] = pos_weight
    state = None
    if resume:
        if not ckpt.is_file():
            raise InputError(f"--resume: no training state {str(ckpt)!r} to resume from")
        state = torch.load(ckpt, map_location="cpu", weights_only=True)
        before = state.get("settings", {})
        # checkpoints of one store, from before several could be given, hold "store" only
        stores_before = before.get("stores") or [before.get("store")]
        w_before = before.get("weights")
        shares_before = None if w_before is not None and len(w_before) != len(stores_before) \
            else check_weights(w_before, len(stores_before))
        if stores_before != resolved or before.get("base") != base or shares_before is None \
                or not np.allclose(shares_before, shares) \
                or before.get("ignore") != settings.get("ignore") \
                or before.get("select", "f1") != select \
                or before.get("pos_weight") != settings.get("pos_weight"):
            raise InputError(f"--resume: {str(ckpt)!r} was trained on other stores, weights, "
                             "width, --ignore, --select or --pos-weight")
        if int(state["step"]) >= steps:
            raise InputError(f"--resume: {str(ckpt)!r} has done {state['step']} steps already; "
                             "give a larger --steps")

    def save(training: dict[str, Any]) -> None:
        _atomic_save(torch, {**training, "settings": settings}, ckpt)

    model, info = train_unet(stores if len(stores) > 1 else stores[0], steps=steps, crop=crop,
                             batch=batch, base=base, lr=lr, seed=seed, threads=threads,
                             device=device, val_every=val_every or max(1, steps // 5),
                             patience=steps, log=log, progress=progress, resume=state,
                             save_every=save_every, save=save, weights=weights, ignore=ignore,
                             ignore_values=ignore_values, select=select,
                             pos_weight=pos_weight)
    per_store, counts, n_test, n_runs, held = [], [], 0, 0, []
    for i, s in enumerate(stores):
        test = FaultSegDataset(s, inputs=("seismic",), targets=("fault",), split="test")
        prob = predict_sections(model, _sections(test))
        held.append((prob, s, test))
        result = score_store(prob, s, indices=test.indices, threshold=0.5,
                             tolerance_px=TOLERANCE_PX)
        runs = int(len(np.unique(test.run_ids)))
        per_store.append({"store": resolved[i], "weight": weights[i], "share": round(shares[i], 4),
                          "train_samples_drawn": int(info["drawn_per_store"][i]),
                          **_scores(result.overall), "test_samples": int(len(test)),
                          "test_runs": runs,
                          "best_val_f1": (info.get("val_f1_per_store") or [None] * len(stores))[i]})
        counts.append(result.counts)
        n_test, n_runs = n_test + len(test), n_runs + runs
    o = summarise(SampleCounts.concat(counts))  # every store's test samples, pooled
    val_runs = sum(len(np.unique(FaultSegDataset(s, inputs=("seismic",), targets=("fault",),
                                                 split="val").run_ids)) for s in stores)
    chosen = choose_threshold(model, stores)
    metrics = {**_scores(o), "threshold": 0.5, "tolerance_px": TOLERANCE_PX,
               "test_samples": n_test, "test_runs": n_runs,
               "train_runs": int(info["n_runs"]), "val_runs": int(val_runs),
               "device": info["device"],
               "steps": int(info["steps"]), "best_val_f1": info.get("best_val_f1"),
               "best_step": info.get("best_step"), **settings,
               "pos_weight": info["pos_weight"], "per_store": per_store,
               "chosen_threshold": chosen,
               "at_chosen_threshold": _at_threshold(held, chosen["threshold"])}
    metrics["warnings"] = training_warnings(metrics)
    blob = {"format": FORMAT, "version": VERSION, "base": base, "target": "fault",
            "threshold": chosen["threshold"],
            "state_dict": {k: v.detach().cpu() for k, v in model.state_dict().items()},
            "metrics": metrics}
    _atomic_save(torch, blob, out)
    metrics_path(out).write_text(json.dumps(metrics, indent=2) + "\n")
    if log:
        if len(stores) > 1:
            for r in per_store:
                log(f"test runs of {r['store']} ({r['test_samples']} samples): precision "
                    f"{r['precision']:.3f}  recall {r['recall']:.3f}  F1 {r['f1']:.3f}  "
                    f"AP {r['ap']:.3f}")
        log(f"test runs{' of every store' if len(stores) > 1 else ''} "
            f"({metrics['test_samples']} samples, tolerance {TOLERANCE_PX} px): "
            f"precision {metrics['precision']:.3f}  recall {metrics['recall']:.3f}  "
            f"F1 {metrics['f1']:.3f}  AP {metrics['ap']:.3f}")
        a = metrics["at_chosen_threshold"]
        log(f"threshold {a['threshold']:g} (best F1 on the validation runs, "
            f"{chosen['f1']:.3f}): test runs at it: precision {a['precision']:.3f}  "
            f"recall {a['recall']:.3f}  F1 {a['f1']:.3f}")
        log(f"wrote {out} and {metrics_path(out)}")
    return metrics


#: the best validation step, as a share of the steps, below which the training warns
EARLY_BEST = 0.3


def training_warnings(metrics: dict[str, Any]) -> list[str]:
    """What a user should know about a training from its metrics: a model chosen on a single
    validation run (chance picks its step), a best step early in the training (the later
    steps did not help: the data or the rate), a test on one run."""
    out = []
    if metrics.get("val_runs", 2) < 2:
        out.append(f"the model was chosen on {metrics['val_runs']} validation run: its best "
                   "step may be chance; generate more runs (10 % of the runs validate, at "
                   "least 20 runs give 2)")
    best, steps = metrics.get("best_step"), int(metrics.get("steps") or 0)
    if best is not None and steps and best < EARLY_BEST * steps:
        out.append(f"the best validation F1 came at step {best} of {steps}: the later steps "
                   "did not improve it (too few runs to learn from, or too high a --lr)")
    if metrics.get("test_runs", 2) < 2:
        out.append(f"the test scores come from {metrics['test_runs']} run: a rough estimate")
    return out


def _sections(ds: FaultSegDataset) -> np.ndarray:
    """The seismic sections of a dataset, stacked (N, H, W)."""
    return np.stack([ds[j][0][0].numpy() for j in range(len(ds))])


def choose_threshold(model: Any, stores: str | Path | Sequence[str | Path],
                     split: str = "val") -> dict[str, Any]:
    """The probability threshold at which ``model`` finds the faults of ``stores`` best: the one
    that maximises F1 at :data:`TOLERANCE_PX` on their ``split`` runs, pooled, over the
    threshold sweep of :func:`demseis.evaluation.score` (0.01 to 0.99).

    Returns ``{"threshold", "f1", "split", "samples", "runs", "tolerance_px"}``; the threshold
    is :data:`DEFAULT_THRESHOLD` when no threshold finds a labelled fault (F1 0). InputError
    when no store has a complete sample in ``split``.
    """
    stores = [stores] if isinstance(stores, (str, Path)) else list(stores)
    counts, samples, runs = [], 0, 0
    for prob, s, ds in _split_probs(model, stores, split):
        counts.append(score_store(prob, s, indices=ds.indices, threshold=DEFAULT_THRESHOLD,
                                  tolerance_px=TOLERANCE_PX).counts)
        samples, runs = samples + len(ds), runs + int(len(np.unique(ds.run_ids)))
    if not counts:
        raise InputError(f"no complete sample in the {split} runs of "
                         f"{', '.join(repr(str(s)) for s in stores)} to choose a threshold on")
    o = summarise(SampleCounts.concat(counts))
    found = float(o.ods_f1) > 0
    return {"threshold": round(float(o.ods_threshold), 4) if found else DEFAULT_THRESHOLD,
            "f1": _num(o.ods_f1), "split": split, "samples": samples, "runs": runs,
            "tolerance_px": TOLERANCE_PX}


def _split_probs(model: Any, stores: Sequence[str | Path],
                 split: str) -> list[tuple[np.ndarray, str | Path, FaultSegDataset]]:
    """(probabilities, store, dataset) of the ``split`` runs of every store that has any."""
    out = []
    for s in stores:
        ds = FaultSegDataset(s, inputs=("seismic",), targets=("fault",), split=split)
        if len(ds):
            out.append((predict_sections(model, _sections(ds)), s, ds))
    return out


def _at_threshold(held: list[tuple[Any, ...]], threshold: float) -> dict[str, Any]:
    """Precision, recall, F1 and IoU of the pooled ``held`` predictions (probabilities, store,
    dataset: :func:`_split_probs`) at ``threshold`` and :data:`TOLERANCE_PX`."""
    if not held:
        return {"threshold": threshold}
    o = summarise(SampleCounts.concat([
        score_store(p, s, indices=ds.indices, threshold=threshold,
                    tolerance_px=TOLERANCE_PX).counts for p, s, ds in held]))
    return {"threshold": threshold, **{k: v for k, v in _scores(o).items() if k != "ap"}}


def model_threshold(model: Any) -> tuple[float, str]:
    """The threshold of a model loaded by :func:`load_model`, and where it comes from: the one
    chosen on its validation runs (:func:`choose_threshold`), or :data:`DEFAULT_THRESHOLD` for
    a model file that carries none."""
    t = getattr(model, "demseis_threshold", None)
    if t is None:
        return DEFAULT_THRESHOLD, "default; the model carries no threshold"
    return float(t), "the model's"


def set_threshold(path: str | Path, stores: str | Path | Sequence[str | Path], *,
                  device: str | None = None) -> dict[str, Any]:
    """Choose the threshold of the model file ``path`` on the validation runs of ``stores``
    (:func:`choose_threshold`; give the stores it was trained on) and save it in the file, and
    in its metrics JSON when there is one, with the stores' test runs scored at it
    (``at_chosen_threshold``, as :func:`train_model` writes); return the choice. For models
    made before :func:`train_model` chose one itself."""
    torch = import_torch("demseis threshold")
    net = load_model(path, device)
    stores = [stores] if isinstance(stores, (str, Path)) else list(stores)
    chosen = choose_threshold(net, stores)
    at = _at_threshold(_split_probs(net, stores, "test"), chosen["threshold"])
    blob = torch.load(str(path), map_location="cpu", weights_only=True)
    blob["threshold"] = chosen["threshold"]
    blob.setdefault("metrics", {}).update(chosen_threshold=chosen, at_chosen_threshold=at)
    _atomic_save(torch, blob, Path(path))
    js = metrics_path(path)
    if js.is_file():
        metrics = json.loads(js.read_text())
        metrics.update(chosen_threshold=chosen, at_chosen_threshold=at)
        tmp = js.with_name(f".{js.name}.tmp{os.getpid()}")
        tmp.write_text(json.dumps(metrics, indent=2) + "\n")
        os.replace(tmp, js)
    return chosen


def _scores(o: Any) -> dict[str, float]:
    """precision, recall, F1, IoU and AP of a ScoreResult, rounded for the JSON."""
    return {"precision": _num(o.precision), "recall": _num(o.recall), "f1": _num(o.f1),
            "iou": _num(o.iou), "ap": _num(o.ap)}


def _num(x: Any) -> float:
    return round(float(x), 4)


def _atomic_save(torch: Any, obj: Any, path: Path) -> None:
    tmp = path.with_name(f".{path.name}.tmp{os.getpid()}")
    try:
        torch.save(obj, tmp)
        os.replace(tmp, path)
    finally:
        tmp.unlink(missing_ok=True)


#: the model shipped with demseis (docs/model.md: its data, recipe, scores and limits)
PRETRAINED = "fault_unet.pt"


def pretrained_path() -> Path:
    """Path of the model shipped with demseis (:data:`PRETRAINED`, in
    ``demseis/learning/pretrained/``); InputError if this installation lacks it."""
    path = Path(str(resources.files("demseis.learning") / "pretrained" / PRETRAINED))
    if not path.is_file():
        raise InputError(f"this installation of demseis has no shipped model ({path}); give "
                         "one with --model (demseis train makes one)")
    return path


def load_model(path: str | Path, device: str | None = None) -> Any:
    """The U-Net saved by :func:`train_model`, in eval mode on ``device`` (default: CUDA when
    available); its ``demseis_metrics`` attribute holds the saved metrics, and
    ``demseis_threshold`` its threshold (None when the file carries none;
    :func:`model_threshold`)."""
    torch = import_torch("demseis predict")
    if not os.path.isfile(path):
        raise InputError(f"model {str(path)!r} does not exist")
    not_model = InputError(f"model {str(path)!r} is not a demseis model (made by demseis train)")
    try:
        blob = torch.load(str(path), map_location="cpu", weights_only=True)
    except OSError as exc:  # permissions, a directory: the file itself cannot be read
        raise InputError(f"model {str(path)!r}: cannot read ({exc.strerror or exc})") from None
    except Exception:  # noqa: BLE001 - not a torch file, truncated, another pickle: not a model
        raise not_model from None
    if not isinstance(blob, dict) or blob.get("format") != FORMAT:
        raise not_model
    try:
        model = build_unet(int(blob["base"]))
        model.load_state_dict(blob["state_dict"])
    except (KeyError, TypeError, ValueError, RuntimeError):  # its format key but not its weights
        raise not_model from None
    dev = torch.device(device or ("cuda" if torch.cuda.is_available() else "cpu"))
    model.to(dev).eval()
    model.demseis_metrics = blob.get("metrics", {})
    t = blob.get("threshold")
    if t is not None and not (isinstance(t, float) and 0 < t < 1):
        raise not_model
    model.demseis_threshold = t
    return model


def predict_array(model: Any, sections: np.ndarray, *, tile: int = TILE,
                  overlap: int = OVERLAP) -> np.ndarray:
    """Fault probabilities of a (H, W) section or (N, H, W) sections, of any size.

    A section larger than ``tile`` in either direction is predicted in overlapping tiles whose
    probabilities are averaged; every piece is padded to a multiple of 4 (the U-Net's), by
    edge replication below 4 pixels and reflection otherwise.
    """
    arr = np.asarray(sections, dtype=np.float32)
    if arr.ndim not in (2, 3) or 0 in arr.shape:
        raise InputError(f"sections must be (H, W) or (N, H, W), got shape {arr.shape}")
    if not np.isfinite(arr).all():
        raise InputError("sections hold NaN or infinite values")
    stack = arr[None] if arr.ndim == 2 else arr
    out = np.stack([_predict_one(model, s, tile, overlap) for s in stack])
    return out[0] if arr.ndim == 2 else out


#: bytes of crossline-pass sums held in memory at once by :func:`predict_cube`
CUBE_BLOCK_BYTES = 16 * 2**20


def predict_cube(model: Any, inp: str | Path, out: str | Path, *,
                 progress: bool = False, mask: str | Path | None = None,
                 threshold: float = DEFAULT_THRESHOLD) -> Path:
    """Fault probability of a 3-D SEG-Y cube: every inline and every crossline predicted as a
    section (:func:`predict_array`), the two averaged at each sample, written to ``out`` (SEG-Y
    with the input's headers, or ``.npy`` (inlines, crosslines, samples)).

    Memory does not grow with the cube: the inline pass writes each inline's probabilities to
    a float32 ``.npy`` file beside ``out`` (as large as the cube; it becomes a ``.npy`` output,
    or is removed), and the crossline pass reads and rewrites them in blocks of crosslines of
    at most :data:`CUBE_BLOCK_BYTES`, with explicit reads and writes (no memory map, whose
    pages would count against the process). ``mask``: also write 1 where the probability
    reaches ``threshold`` and 0 elsewhere (SEG-Y float32, or ``.npy`` uint8), an inline at a
    time.
    """
    inp, out = Path(inp), Path(out)
    geom = cube_geometry(inp)
    if geom is None:
        raise InputError(f"{str(inp)!r} is not a 3-D cube (no inline/crossline geometry)")
    n_il, n_xl, n_s = geom.shape
    work = out.with_name(f".{out.name}.sum{os.getpid()}.npy")
    try:
        header = np.lib.format.open_memmap(work, mode="w+", dtype=np.float32, shape=geom.shape)
        offset = int(header.offset)
        del header
        row = n_xl * n_s * 4                      # bytes of one inline in the file
        step = max(1, CUBE_BLOCK_BYTES // (n_il * n_s * 4))
        bar = tqdm(total=n_il + n_xl, desc="predict", unit="line", disable=not progress,
                   file=sys.stderr)
        fd = os.open(work, os.O_RDWR)
        try:
            with open_cube(inp) as f:
                for i in range(n_il):              # inlines: (samples, crosslines)
                    prob = np.ascontiguousarray(predict_array(model, read_inline(f, i)).T)
                    os.pwrite(fd, prob.tobytes(), offset + i * row)
                    bar.update()
                for j0 in range(0, n_xl, step):    # crosslines, a block at a time
                    j1 = min(j0 + step, n_xl)
                    width = (j1 - j0) * n_s * 4
                    block = np.empty((n_il, j1 - j0, n_s), np.float32)
                    for i in range(n_il):
                        block[i] = np.frombuffer(
                            os.pread(fd, width, offset + i * row + j0 * n_s * 4),
                            np.float32).reshape(j1 - j0, n_s)
                    for j in range(j0, j1):        # (samples, inlines)
                        along = predict_array(model, read_crossline(f, j)).T
                        block[:, j - j0] = 0.5 * (block[:, j - j0] + along)
                        bar.update()
                    for i in range(n_il):
                        os.pwrite(fd, block[i].tobytes(), offset + i * row + j0 * n_s * 4)
        finally:
            os.close(fd)
            bar.close()
        if mask is not None:
            binary = _Above(_InlineFile(work, offset, geom.shape), threshold)
            if is_segy(mask):
                write_segy_cube_like(binary, inp, mask)
            else:
                _write_npy_inlines(binary, Path(mask))
        if is_segy(out):
            write_segy_cube_like(_InlineFile(work, offset, geom.shape), inp, out)
        else:
            os.replace(work, out)
    finally:
        work.unlink(missing_ok=True)
    return out


class _InlineFile:
    """The (inlines, crosslines, samples) float32 array of a file, read one inline per index
    with an explicit read (what :func:`~demseis.evaluation.segyfile.write_segy_cube_like`
    reads from)."""

    def __init__(self, path: Path, offset: int, shape: tuple[int, int, int]) -> None:
        self.path, self.offset, self.shape = path, offset, shape

    def __getitem__(self, k: int) -> np.ndarray:
        n_xl, n_s = self.shape[1:]
        with open(self.path, "rb") as f:
            f.seek(self.offset + int(k) * n_xl * n_s * 4)
            return np.fromfile(f, np.float32, n_xl * n_s).reshape(n_xl, n_s)


class _Above:
    """1 where an inline of ``cube`` (anything with ``shape`` and ``cube[k]``) reaches
    ``threshold``, 0 elsewhere, as uint8."""

    def __init__(self, cube: Any, threshold: float) -> None:
        self.cube, self.threshold, self.shape = cube, threshold, cube.shape

    def __getitem__(self, k: int) -> np.ndarray:
        return (self.cube[k] >= self.threshold).astype(np.uint8)


def _write_npy_inlines(cube: Any, out: Path) -> Path:
    """``cube`` (anything with ``shape`` and a uint8 ``cube[k]``) to the ``.npy`` file ``out``,
    an inline at a time, under a temporary name, then renamed."""
    tmp = out.with_name(f".{out.name}.tmp{os.getpid()}.npy")
    try:
        with open(tmp, "wb") as f:
            np.lib.format.write_array_header_1_0(f, {"descr": np.dtype(np.uint8).str,
                                                     "fortran_order": False,
                                                     "shape": tuple(cube.shape)})
            for k in range(cube.shape[0]):
                f.write(np.ascontiguousarray(cube[k], dtype=np.uint8).tobytes())
        os.replace(tmp, out)
    finally:
        tmp.unlink(missing_ok=True)
    return out


def _starts(n: int, tile: int, overlap: int) -> list[int]:
    if n <= tile:
        return [0]
    step = tile - overlap
    starts = list(range(0, n - tile, step)) + [n - tile]
    return sorted(set(starts))


def _predict_one(model: Any, sec: np.ndarray, tile: int, overlap: int) -> np.ndarray:
    h, w = sec.shape
    small = min(h, w) < 4
    padded = np.pad(sec, ((0, max(0, 4 - h)), (0, max(0, 4 - w))), mode="edge") if small else sec
    total = np.zeros(padded.shape, np.float32)
    count = np.zeros(padded.shape, np.float32)
    ph, pw = padded.shape
    for r in _starts(ph, tile, overlap):
        for c in _starts(pw, tile, overlap):
            piece = padded[r: r + tile, c: c + tile]
            total[r: r + tile, c: c + tile] += predict_sections(model, piece[None])[0]
            count[r: r + tile, c: c + tile] += 1
    return (total / count)[:h, :w]


def check_outputs(inp: str | Path, out: str | Path, *, mask: str | Path | None = None,
                  overwrite: bool = False, threshold: float | None = None) -> None:
    """InputError naming the flag when :func:`predict_file` could not write ``out`` or
    ``mask`` from ``inp`` (an existing file without ``overwrite``, a suffix it does not write,
    SEG-Y output from other input, the mask on the output) or ``threshold`` is no probability;
    checked before a model is loaded."""
    inp, out = Path(inp), Path(out)
    for flag, path in (("--out", out), ("--mask", mask)):
        if path is None:
            continue
        path = Path(path)
        if path.exists() and not overwrite:
            raise InputError(f"{flag} {str(path)!r} exists; pass --overwrite to replace it")
        if not (is_segy(path) or path.suffix == ".npy"):
            raise InputError(f"{flag} {str(path)!r}: name a .sgy, .segy or .npy file")
        if is_segy(path) and not is_segy(inp):
            raise InputError(f"{flag} {str(path)!r}: SEG-Y output needs SEG-Y input (its "
                             "headers)")
    if mask is not None and Path(mask).resolve() == out.resolve():
        raise InputError(f"--mask {str(mask)!r} is --out as well; name another file")
    if threshold is not None and not 0 < threshold < 1:
        raise InputError(f"--threshold {threshold!r}: expected a probability in (0, 1)")


def predict_file(model: Any, inp: str | Path, out: str | Path, *, device: str | None = None,
                 overwrite: bool = False, progress: bool = False,
                 mask: str | Path | None = None, threshold: float | None = None) -> Path:
    """Fault probability of the section(s) or cube in ``inp``, written to ``out``.

    Parameters
    ----------
    model : a model file from :func:`train_model`, or a loaded model (:func:`load_model`).
    inp : a SEG-Y file (``.sgy`` / ``.segy``): a 3-D cube with inline and crossline numbers
        in its trace headers (:func:`predict_cube`), or else one 2-D section, a trace per
        column; or a ``.npy`` array (H, W) or (N, H, W).
    out : ``.sgy`` / ``.segy`` (SEG-Y input only: the input's headers, float32 samples) or
        ``.npy`` (float32; (1, H, W) for a SEG-Y section, so that ``demseis score`` reads it;
        (inlines, crosslines, samples) for a cube; else the input's shape).
    overwrite : replace an existing ``out`` (and ``mask``).
    progress : a progress bar over a cube's lines on stderr.
    mask : also write the faults: 1 where the probability reaches ``threshold``, 0 elsewhere
        (the same kinds of file and shapes as ``out``; ``.npy`` as uint8).
    threshold : the probability the mask starts at, in (0, 1) (default: the model's,
        :func:`model_threshold`).
    """
    inp, out = Path(inp), Path(out)
    check_outputs(inp, out, mask=mask, overwrite=overwrite, threshold=threshold)
    cube = is_segy(inp) and cube_geometry(inp) is not None
    if cube:
        data = None
    elif is_segy(inp):
        data = read_segy_section(inp)
    elif inp.suffix == ".npy":
        if not inp.is_file():
            raise InputError(f"{str(inp)!r} does not exist")
        try:
            data = np.load(inp, allow_pickle=False)
        except (ValueError, OSError) as exc:
            raise InputError(f"{str(inp)!r}: cannot read as .npy ({exc})") from None
    else:
        raise InputError(f"{str(inp)!r}: give a SEG-Y (.sgy, .segy) or .npy file")
    net = load_model(model, device) if isinstance(model, (str, Path)) else model
    t = model_threshold(net)[0] if threshold is None else float(threshold)
    if cube:
        return predict_cube(net, inp, out, progress=progress, mask=mask, threshold=t)
    prob = predict_array(net, data)
    if is_segy(inp):
        prob = prob[None]  # (1, samples, traces): a section as demseis score reads it
    for path, values in ((mask, None), (out, prob)):
        if path is None:
            continue
        if values is None:
            values = (prob >= t).astype(np.uint8)
        if is_segy(path):
            write_segy_like(values[0], inp, path)
        else:
            np.save(path, values if values.dtype == np.uint8 else values.astype(np.float32))
    return out
