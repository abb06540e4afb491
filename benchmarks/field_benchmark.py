"""The field benchmark: train the project's U-Net on each training set at one fixed budget and
score every model on field sections with faults picked by hand.

Training sets (each one model per seed):

- ``--store NAME=PATH`` (repeatable): a demseis store;
- ``--mix NAME=A:w,B:w`` (repeatable): a mix of stores (paths, or names of other training sets)
  with weights (default 1), store s giving the share w_s / sum(w) of every batch on average;
- ``--planar N`` and ``--planar-steep N``: the planar control, built in this run from the
  ``planar`` preset (FaultSeg-style random reflectivity, folds, 1-3 planar faults at 40-80
  degrees; the steep variant 3-10 faults at 50-86 degrees) with N runs, see ``CONTROLS``;
- ``--generate NAME=PRESET:N[:ENGINE]``: another store built from a preset in the same way
  (e.g. ``kin=field:12:kinematic``, the kinematic engine over the ``field`` preset).

Built stores go to ``--cache`` (``stores/NAME-<config digest>.zarr``); a complete store of the
same config is reused. Trained models are kept there too (``models/``), so that scoring a new
field set does not retrain.

Every model is :func:`demseis.learning.train.build_unet` trained by
:func:`demseis.learning.train.train_unet` on the train runs (75 %) of its store(s): the same
augmentation (flips, polarity, amplitude), budget (``--steps --base --crop --batch --lr``)
and seeds for all. CUDA with mixed precision when present (default 3000 steps, base 32), else
the CPU protocol: 600 steps, base 16, crop 96, batch 8. One 600-step CPU training (2 torch
threads, a 12-run kinematic ``field`` store) on machine A (docs/benchmarks.md: 2 cores of an
AMD EPYC, shared) took 767 s wall and 564 s of CPU with a load average of 3.5-5, and 1047 s
wall at a load of about 6.5; on 2 idle cores expect no less than about 5 minutes (564 s of
CPU over 2 threads).

Field sets, scored with :func:`demseis.evaluation.score` (ODS F1, OIS F1 and AP at each
``--tolerance``, default 3 px and 2 px), and the share of each section's pixels with
probability above 0.5:

- ``--field-dir DIR`` (repeatable; the set is named after DIR): pairs ``seismic_<key>.*`` /
  ``mask_<key>.*`` (.png, .npy, .sgy), the layout of the tutorial-03 sections of
  thilowrona/seismic_deep_learning (``benchmarks/fetch_field.sh`` fetches them) and of the
  Great South Basin lines of Cunha et al. (2020) (``benchmarks/fetch_field_gsb.sh``);
- ``--field [NAME=]SECTION:MASK`` (repeatable; set ``field`` unless named).

A display image (PNG) becomes an amplitude (grey level minus the image's median grey, unit
RMS) and is resampled onto its mask's grid when it was drawn at another size. Hand-drawn
masks are lines several pixels wide: they are thinned to one-pixel lines (scikit-image's
skeletonize; ``--no-thin`` keeps them), as the demseis labels are and as the scorer's
tolerance assumes (a thick label would count its width as missed recall).

``--f3 PATH`` (unlabelled, e.g. ../shared/field/f3_inline.sgy): the share above 0.5 only.

Field scale (``--field-scale``, default ``1 auto``, each reported): the network sees the
section at its own pixel size (``1``), or resampled by a factor (a number), or by ``auto`` =
the training stores' median dominant period over the section's
(:func:`demseis.evaluation.realism.dominant_period`, in samples), so that reflectors are as many
pixels apart as in training; both axes by the same factor (the faults' pixel dips stay), and
the probability is resampled back onto the mask's grid before scoring.

Held-out synthetic scores: F1 at threshold 0.5, ODS F1 and AP of every model on the held-out
runs (25 %) of every training store (at most ``--max-eval`` sections each).

At the held-out threshold (``at_heldout_threshold`` in each line): ODS F1 picks its threshold
on the field set itself, and the share above 0.5 depends on how high a model's probabilities
run (models trained on denser labels give higher ones everywhere). So each model is also read
at one threshold chosen without field data, the one that maximises its F1 at 2 px on the
held-out runs of its own training stores (pooled): the threshold, that held-out F1, F1 of every
field set at each tolerance and the share of its pixels at or above it, and F3's share (all at
field scale 1). A given model (``--model``) that carries a threshold (``demseis train`` chooses
one on its validation runs and saves it) is read at that threshold the same way
(``at_model_threshold``).

Results accumulate in ``--results`` (JSON): a (training set, seed) already trained with the
same configuration (stores, budget, device kind) is not retrained, and a score already there
for the same inputs (field files known by their bytes) is not recomputed. Prints one JSON line
per training set: mean, std, min, max over the seeds of every score. ``--figure`` draws one
seed's predictions (``--figure-seed``, default the first; at the first ``--field-scale``) on
every field section and F3 beside the masks.

    PYTHONPATH=$PWD python benchmarks/field_benchmark.py --store dem=D.zarr --store kin=K.zarr \\
        --planar 64 --field-dir ~/.cache/demseis-field/wrona-tutorial-03 \\
        --f3 ../shared/field/f3_inline.sgy --results field.json --figure field.png
"""

from __future__ import annotations

import argparse
import hashlib
import json
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

from _field_common import (add_training_args, budget,  # noqa: E402  (benchmarks/ is on sys.path)
                           field_dir_pairs, load_results, machine, read_field, read_pair,
                           read_section, resize, save_results, score_stack)

#: The controls built in the run: name -> (preset, overrides layered on it as a TOML file
#: beside ``--preset`` would be; ``[sweep] n_runs`` comes from the command line).
#: The ``planar`` preset draws 1-3 planar faults at 40-80 degrees; the steep variant is the one
#: its preset file documents (demseis/generator/presets/planar.toml).
CONTROLS = {
    "planar": ("planar", {}),
    "planar_steep": ("planar", {"sweep": {
        "planar_faults": {"dist": "choice", "values": list(range(3, 11))},
        "planar_dip_min_deg": 50.0, "planar_dip_max_deg": 86.0}}),
}
#: the scores of every field set, per tolerance
FIELD_METRICS = ("ods_f1", "ois_f1", "ap")
#: the held-out synthetic scores, per tolerance
SYNTH_METRICS = ("f1", "ods_f1", "ap")
#: share of a section's pixels above this probability
SHARE_AT = 0.5
#: the matching distance (px) of the threshold chosen on held-out synthetic runs
HELDOUT_TOL = 2.0


def digest(obj) -> str:
    return hashlib.sha1(json.dumps(obj, sort_keys=True, default=str).encode()).hexdigest()[:10]


def _file_id(path: str | Path) -> list:
    """A file's identity in a fingerprint: resolved path, size and the SHA-1 of its bytes (not
    its modification time: the same file copied or mounted afresh keeps its scores)."""
    p = Path(path).resolve()
    return [str(p), p.stat().st_size, hashlib.sha1(p.read_bytes()).hexdigest()[:16]]


# --------------------------------------------------------------------- training sets

def build_store(name: str, preset: str, overrides: dict, cache: Path, workers: int | None) -> Path:
    """The store of ``preset`` with ``overrides``, built in ``cache`` unless a complete one of
    the same config is there."""
    import tomllib

    import demseis
    from demseis.generator.config.settings import _merge, parse_config, preset_path

    raw = _merge(tomllib.loads(preset_path(preset).read_text()), overrides)
    out = cache / "stores" / f"{name}-{digest(raw)}.zarr"
    if out.exists():
        done = demseis.open(out).done
        if done.size and done.all():
            return out
    t0 = time.perf_counter()
    print(f"building {name} ({preset}, {overrides}) in {out}", file=sys.stderr)
    store = demseis.generate(parse_config(raw, source=f"{name}: preset {preset} + overrides"),
                             out=out, workers=workers)
    if not store.done.any():
        from demseis.errors import InputError

        raise InputError(f"{name}: no run of {out} completed")
    print(f"built {name} in {time.perf_counter() - t0:.0f} s", file=sys.stderr)
    return out


def training_sets(args: argparse.Namespace, cache: Path) -> dict[str, tuple[list[str], list]]:
    """name -> (the store paths it trains on, their weights: None for one store)."""
    from demseis.errors import InputError

    sets: dict[str, tuple[list[str], list | None]] = {}

    def add(name: str, stores: list[str], weights: list | None = None) -> None:
        if not name or name in sets:
            raise InputError(f"training set name {name!r}: empty or given twice")
        sets[name] = (stores, weights)

    for arg in args.store or []:
        name, _, path = arg.partition("=")
        if not path or not Path(path).is_dir():
            raise InputError(f"--store {arg!r}: expected NAME=PATH of a store")
        add(name, [str(Path(path))])
    builds = [(n, CONTROLS[n][0], {**CONTROLS[n][1]}, runs) for n, runs in
              (("planar", args.planar), ("planar_steep", args.planar_steep)) if runs]
    for arg in args.generate or []:
        name, _, spec = arg.partition("=")
        parts = spec.split(":")
        if len(parts) not in (2, 3) or not parts[1].isdigit():
            raise InputError(f"--generate {arg!r}: expected NAME=PRESET:N_RUNS[:ENGINE]")
        over = {"model": {"engine": parts[2]}} if len(parts) == 3 else {}
        builds.append((name, parts[0], over, int(parts[1])))
    for name, preset, over, runs in builds:
        over["sweep"] = {**over.get("sweep", {}), "n_runs": int(runs)}
        add(name, [str(build_store(name, preset, over, cache, args.workers))])
    for arg in args.mix or []:
        name, _, spec = arg.partition("=")
        stores, weights = [], []
        for part in spec.split(","):
            ref, _, w = part.rpartition(":")
            try:
                w = float(w)
            except ValueError:  # no weight: 1
                ref, w = part, 1.0
            paths = sets[ref][0] if ref in sets else ([ref] if Path(ref).is_dir() else None)
            if not paths or len(paths) != 1 or not w > 0:
                raise InputError(f"--mix {arg!r}: {part!r} is not STORE[:WEIGHT] (a store path "
                                 "or the name of a one-store training set, a weight > 0)")
            stores.append(paths[0])
            weights.append(w)
        add(name, stores, weights)
    if not sets:
        raise InputError("no training set: give --store, --mix, --planar, --planar-steep or "
                         "--generate")
    return sets


def store_id(path: str) -> list:
    """A store's identity in a fingerprint: resolved path, samples done, config digest."""
    import demseis

    s = demseis.open(path)
    return [str(Path(path).resolve()), int(s.done.sum()), digest(s.config)]


# ----------------------------------------------------------------------------- test sets

def field_sets(args: argparse.Namespace) -> dict[str, list[tuple[str, str, str]]]:
    """set name -> [(section name, section path, mask path)]."""
    sets: dict[str, list[tuple[str, str, str]]] = {}
    for d in args.field_dir or []:
        sets[Path(d).expanduser().name] = field_dir_pairs(d)
    for arg in args.field or []:
        name, eq, pair = arg.partition("=")
        if not eq or ":" in name:
            name, pair = "field", arg
        section, _, mask = pair.rpartition(":")
        read_field([pair])  # checks the pair now, with its message
        sets.setdefault(name, []).append((Path(section).stem, section, mask))
    return sets


def synthetic_test_set(store: str, fr: tuple, max_eval: int) -> tuple[list, list]:
    """Whole sections and truth of (at most ``max_eval`` of) the held-out runs of ``store``
    (none when the store has too few runs to hold any out)."""
    from demseis.datasets import FaultSegDataset

    ds = FaultSegDataset(store, inputs=("seismic",), targets=("fault",), split="test",
                         split_fractions=fr)
    idx = np.arange(len(ds))
    if len(idx) > max_eval:
        idx = np.sort(np.random.default_rng(12345).choice(len(idx), max_eval, replace=False))
    pairs = [ds[int(i)] for i in idx]
    return ([x[0].numpy() for x, _ in pairs], [(y.numpy() > 0) for _, y in pairs])


def store_period(store: str, n: int = 32) -> float:
    """Median dominant period (samples) of ``n`` sections of ``store`` spread over it."""
    import demseis
    from demseis.evaluation.realism import dominant_period

    s = demseis.open(store)
    idx = np.flatnonzero(s.done)
    idx = idx[np.linspace(0, idx.size - 1, min(n, idx.size)).astype(int)]
    return float(np.median([dominant_period(s.sample(int(i))["seismic"]) for i in idx]))


def scale_factor(scale: str, train_period: float, section: np.ndarray) -> float:
    """The resampling factor of ``section`` for ``--field-scale`` value ``scale``."""
    if scale != "auto":
        return float(scale)
    from demseis.evaluation.realism import dominant_period

    return train_period / dominant_period(section)


def predict(model, section: np.ndarray, factor: float) -> np.ndarray:
    """Fault probability of ``section`` resampled by ``factor``, on the section's own grid."""
    from demseis.learning.model import predict_array

    if abs(factor - 1.0) < 1e-3:
        return predict_array(model, section)
    shape = tuple(max(8, int(round(n * factor))) for n in section.shape)
    return resize(predict_array(model, resize(section, shape)), section.shape)


# --------------------------------------------------------------------------------- cells

def _test_set(cache: dict, store: str, fr: tuple, max_eval: int) -> tuple[list, list]:
    """:func:`synthetic_test_set`, read once per benchmark run."""
    key = ("test", str(store), tuple(fr), int(max_eval))
    if key not in cache:
        cache[key] = synthetic_test_set(store, fr, max_eval)
    return cache[key]


def _test_probs(model, cache: dict, probs: dict, store: str, fr: tuple,
                max_eval: int) -> tuple[list, list]:
    """(probabilities, truth) of ``store``'s held-out sections, predicted once per model."""
    secs, truth = _test_set(cache, store, fr, max_eval)
    key = ("test", str(store))
    if key not in probs:
        from demseis.learning.train import predict_sections

        probs[key] = list(predict_sections(model, np.stack(secs))) if secs else []
    return probs[key], truth


def item_scores(model, key: str, item: dict, tolerances: list[float], train_period: float,
                cache: dict, probs: dict | None = None, stores: list[str] | None = None) -> dict:
    """The scores of one item (a field set at one scale, F3 at one scale, a store's held-out
    runs, or the field sets at the threshold chosen on held-out runs) of one model.

    ``probs`` keeps the model's predictions between its items (held-out runs, field sets at
    scale 1, F3) so that the held-out-threshold item predicts nothing twice; ``stores`` are the
    model's training stores (that item only)."""
    probs = {} if probs is None else probs
    if item["kind"] == "heldout_threshold":
        return heldout_threshold_scores(model, item, stores or [], tolerances, cache, probs)
    if item["kind"] == "synthetic":
        secs = _test_set(cache, item["store"], item["fr"], item["max_eval"])[0]
        out = {"n_sections": len(secs)}
        if not secs:
            return out
        held, truth = _test_probs(model, cache, probs, item["store"], item["fr"],
                                  item["max_eval"])
        for tol in tolerances:
            r = score_stack(held, truth, tol)
            out.update({f"{m}_tol{tol:g}": round(float(getattr(r, m)), 4) for m in SYNTH_METRICS})
        return out
    if item["kind"] == "f3":
        sec = cache_f3(cache, item["path"])
        f = scale_factor(item["scale"], train_period, sec)
        prob = predict(model, sec, f)
        probs[("f3", item["scale"])] = prob
        return {"share_above_0.5": round(float((prob > SHARE_AT).mean()), 5),
                "factor": round(f, 4), "_prob": prob}
    secs = [(name, *cache_pair(cache, s, m, item["thin"])) for name, s, m in item["pairs"]]
    maps, factors = [], []
    for _, sec, _ in secs:
        factors.append(scale_factor(item["scale"], train_period, sec))
        maps.append(predict(model, sec, factors[-1]))
    probs[("field", item["name"], item["scale"])] = maps
    out = {"share_above_0.5": {n: round(float((p > SHARE_AT).mean()), 5)
                               for (n, _, _), p in zip(secs, maps)},
           "factor": {n: round(f, 4) for (n, _, _), f in zip(secs, factors)},
           "_prob": maps}
    for tol in tolerances:
        r = score_stack(maps, [t for _, _, t in secs], tol)
        out.update({f"{m}_tol{tol:g}": round(float(getattr(r, m)), 4) for m in FIELD_METRICS})
    return out


def heldout_threshold_scores(model, item: dict, stores: list[str], tolerances: list[float],
                             cache: dict, probs: dict) -> dict:
    """The field sets and F3 at one threshold chosen without field data: the one that maximises
    F1 at :data:`HELDOUT_TOL` px on the held-out runs of the model's own training stores
    (pooled, at most ``max_eval`` sections each; the threshold sweep of
    :func:`demseis.evaluation.score`). ODS F1 picks its threshold on the field set itself; this
    is the threshold a user without picks would take, and F3's share above it is that of a
    map thresholded so, not of one probability scale (models trained on denser labels give
    higher probabilities everywhere)."""
    held, truth = [], []
    for store in stores:
        p, t = _test_probs(model, cache, probs, store, item["fr"], item["max_eval"])
        held += p
        truth += t
    if not held:
        return {"n_sections": 0}
    r = score_stack(held, truth, HELDOUT_TOL)
    thr = float(r.ods_threshold)
    return {"n_sections": len(held), "threshold": round(thr, 4),
            f"heldout_f1_tol{HELDOUT_TOL:g}": round(float(r.ods_f1), 4),
            **field_at_threshold(model, item, thr, tolerances, cache, probs)}


def field_at_threshold(model, item: dict, thr: float, tolerances: list[float], cache: dict,
                       probs: dict) -> dict:
    """F1 of every field set of ``item`` at each tolerance and the share of its pixels at or
    above ``thr`` (``field``), and F3's share (``f3_share``), all at field scale 1."""
    out: dict = {"field": {}}
    for name, pairs in item["field"].items():
        key = ("field", name, "1")
        if key not in probs:
            probs[key] = [predict(model, cache_pair(cache, s, m, item["thin"])[0], 1.0)
                          for _, s, m in pairs]
        truths = [cache_pair(cache, s, m, item["thin"])[1] for _, s, m in pairs]
        got = {"share": round(float(np.mean([(p >= thr).mean() for p in probs[key]])), 5)}
        for tol in tolerances:
            got[f"f1_tol{tol:g}"] = round(float(score_stack(probs[key], truths, tol, thr).f1), 4)
        out["field"][name] = got
    if item.get("f3"):
        if ("f3", "1") not in probs:
            probs[("f3", "1")] = predict(model, cache_f3(cache, item["f3"]), 1.0)
        out["f3_share"] = round(float((probs[("f3", "1")] >= thr).mean()), 5)
    return out


def cache_pair(cache: dict, section: str, mask: str, thin: bool) -> tuple:
    """(section, mask) of a field pair, read once per benchmark run."""
    if (section, mask) not in cache:
        cache[(section, mask)] = read_pair(section, mask, thin_lines=thin)
    return cache[(section, mask)]


def cache_f3(cache: dict, path: str) -> np.ndarray:
    """The unlabelled section of ``--f3``, read once per benchmark run."""
    if "f3" not in cache:
        cache["f3"] = read_section(path, "--f3")
    return cache["f3"]


def stats(values) -> dict | None:
    """mean, std (n - 1), min, max and n of ``values`` (None when there are none)."""
    v = np.asarray(values, dtype=float)
    if v.size == 0:
        return None
    return {"mean": round(float(v.mean()), 4),
            "std": round(float(v.std(ddof=1)) if v.size > 1 else 0.0, 4),
            "min": round(float(v.min()), 4), "max": round(float(v.max()), 4), "n": int(v.size)}


def learning_curve_sets(tsets: dict, train_runs: list[int]) -> tuple[dict, dict[str, int]]:
    """Each one-store training set ``NAME`` as ``NAME@N`` for every ``N`` of ``train_runs``:
    (the new sets, name -> N)."""
    from demseis.errors import InputError

    out, limits = {}, {}
    for name, (stores, weights) in tsets.items():
        if len(stores) != 1:
            raise InputError(f"--train-runs takes one-store training sets; {name!r} mixes "
                             f"{len(stores)}")
        for n in train_runs:
            out[f"{name}@{n}"] = (stores, weights)
            limits[f"{name}@{n}"] = int(n)
    return out, limits


def pos_weights(text: str) -> float | list[float]:
    """``--pos-weight``: ``15`` (one weight) or ``40,5`` (one per store)."""
    try:
        values = [float(v) for v in text.split(",")]
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r}: numbers separated by commas") from None
    return values[0] if len(values) == 1 else values


def first_train_runs(store: str, fr: tuple[float, float, float], n: int) -> list[int]:
    """The first ``n`` train runs of ``store`` (in run order) under the split ``fr``."""
    from demseis.datasets import FaultSegDataset
    from demseis.errors import InputError

    runs = np.unique(FaultSegDataset(store, inputs=("seismic",), targets=("fault",),
                                     split="train", split_fractions=fr).run_ids)
    if not 0 < n <= runs.size:
        raise InputError(f"--train-runs {n}: {store} has {runs.size} train runs")
    return [int(r) for r in runs[:n]]


def summary_line(name: str, cells: list[dict], items: dict, config: dict) -> dict:
    """The JSON line of one training set: every score's statistics over its seeds."""
    line = {"benchmark": "field_benchmark", "model": name, "stores": config["stores"],
            "weights": config["weights"],
            "seeds": sorted(c["seed"] for c in cells), **{k: config[k] for k in (
                "steps", "base", "crop", "batch", "lr", "device")},
            **({"train_runs": config["train_runs"]} if "train_runs" in config else {}),
            **({"ignore": config["ignore"]} if "ignore" in config else {}),
            **({"pos_weight": config["pos_weight"]} if "pos_weight" in config else {}),
            "machine": " | ".join(sorted({c.get("machine", config["machine"]) for c in cells})),
            "train_seconds": stats([c["train"]["seconds"] for c in cells]),
            "score_seconds": stats([c["score_seconds"] for c in cells if "score_seconds" in c]),
            "field": {}, "f3": {}, "synthetic": {}}
    for key, item in items.items():
        got = [c["scores"][key] for c in cells if key in c["scores"]]
        if not got:
            continue
        if item["kind"] == "synthetic":
            line["synthetic"][item["name"]] = {m: stats([g[m] for g in got]) for m in got[0]}
        elif item["kind"] == "heldout_threshold":
            got = [g for g in got if "threshold" in g]
            if got:
                line["at_heldout_threshold"] = {
                    m: stats([g[m] for g in got]) for m in got[0] if m != "field"}
                line["at_heldout_threshold"]["field"] = {
                    n: {m: stats([g["field"][n][m] for g in got]) for m in v}
                    for n, v in got[0]["field"].items()}
        elif item["kind"] == "f3":
            line["f3"][item["scale"]] = {"share_above_0.5": stats(
                [g["share_above_0.5"] for g in got]), "factor": got[0]["factor"]}
        else:
            out = {m: stats([g[m] for g in got]) for m in got[0]
                   if m not in ("share_above_0.5", "factor")}
            out["share_above_0.5"] = stats([np.mean(list(g["share_above_0.5"].values()))
                                            for g in got])
            out["share_above_0.5_by_section"] = {
                s: round(float(np.mean([g["share_above_0.5"][s] for g in got])), 5)
                for s in got[0]["share_above_0.5"]}
            out["factor"] = got[0]["factor"]
            line["field"].setdefault(item["name"], {})[item["scale"]] = out
    return line


def model_line(arg: str, items: dict, tolerances: list[float]) -> dict:
    """The JSON line of a given model file (``NAME=PATH``, :func:`demseis.learning.model.load_model`)
    scored on the field sets and F3 (one model: no seeds to summarise)."""
    from demseis.errors import InputError
    from demseis.learning.model import load_model

    name, eq, path = arg.partition("=")
    if not eq or not name or not Path(path).is_file():
        raise InputError(f"--model {arg!r}: expected NAME=PATH of a model file")
    model = load_model(path, "cpu")
    cache: dict = {}
    line = {"benchmark": "field_benchmark", "model": name, "path": str(path),
            "trained": {k: model.demseis_metrics.get(k) for k in ("steps", "base", "seed")},
            "field": {}, "f3": {}}
    probs: dict = {}
    for key, item in items.items():
        # "auto" scales by the training stores' period, which a given model does not come with;
        # nor does it come with held-out runs: it is read at its own threshold, if it has one
        if item["kind"] == "heldout_threshold" and model.demseis_threshold is not None:
            line["at_model_threshold"] = {
                "threshold": model.demseis_threshold,
                **field_at_threshold(model, item, model.demseis_threshold, tolerances, cache,
                                     probs)}
        if item["kind"] in ("synthetic", "heldout_threshold") or item.get("scale") == "auto":
            continue
        got = item_scores(model, key, item, tolerances, 1.0, cache, probs)
        got.pop("_prob", None)
        if item["kind"] == "f3":
            line["f3"][item["scale"]] = got
        else:
            got["share_above_0.5_by_section"] = got.pop("share_above_0.5")
            got["share_above_0.5"] = round(float(np.mean(list(
                got["share_above_0.5_by_section"].values()))), 5)
            line["field"].setdefault(item["name"], {})[item["scale"]] = got
    return line


# -------------------------------------------------------------------------------- figure

def draw(path: Path, panels: dict, sections: list[tuple[str, np.ndarray, np.ndarray | None]],
         title: str) -> None:
    """Rows: field sections (and F3); columns: the section with its mask, then each model's
    probability (shown above 0.2)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from scipy import ndimage

    models = list(panels)
    fig, axes = plt.subplots(len(sections), 1 + len(models), squeeze=False,
                             figsize=(3.6 * (1 + len(models)), 2.0 * len(sections)))
    for i, (name, sec, mask) in enumerate(sections):
        clip = float(np.percentile(np.abs(sec), 99))
        for j in range(1 + len(models)):
            ax = axes[i, j]
            ax.imshow(sec, cmap="gray", vmin=-clip, vmax=clip, aspect="auto")
            if j == 0:
                if mask is not None:  # one-pixel lines, drawn 3 px wide to show at this size
                    thick = ndimage.binary_dilation(mask)
                    ax.imshow(np.ma.masked_equal(thick.astype(float), 0), cmap="autumn",
                              aspect="auto", interpolation="nearest")
                ax.set_title(f"{name}" + (" (mask)" if mask is not None else " (no labels)"),
                             fontsize=8)
            else:
                prob = panels[models[j - 1]][name]
                ax.imshow(np.ma.masked_less(prob, 0.2), cmap="magma_r", vmin=0, vmax=1,
                          aspect="auto", alpha=0.85)
                ax.set_title(f"{models[j - 1]}: {100 * (prob > SHARE_AT).mean():.1f} % > 0.5",
                             fontsize=8)
            ax.set_xticks([])
            ax.set_yticks([])
    fig.suptitle(title, fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=80)
    plt.close(fig)


# ---------------------------------------------------------------------------------- main

def parse_args(argv: list[str] | None) -> argparse.Namespace:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--store", action="append", metavar="NAME=PATH", help="a training store")
    ap.add_argument("--mix", action="append", metavar="NAME=A:w,B:w",
                    help="a mixed training set: store paths or training-set names, weights")
    ap.add_argument("--model", action="append", metavar="NAME=PATH",
                    help="a trained model file (demseis train's, e.g. the shipped one) scored "
                    "as it is, without training: field sets and F3 only")
    ap.add_argument("--planar", type=int, metavar="N_RUNS",
                    help="build and train the planar control")
    ap.add_argument("--planar-steep", type=int, metavar="N_RUNS",
                    help="build and train the steep planar control (3-10 faults, 50-86 degrees)")
    ap.add_argument("--generate", action="append", metavar="NAME=PRESET:N[:ENGINE]",
                    help="build a store from a preset and train on it")
    ap.add_argument("--cache", default=str(Path.home() / ".cache" / "demseis-bench" / "field"),
                    help="built stores and trained models")
    ap.add_argument("--workers", type=int, help="sweep workers for built stores (0: in process)")
    ap.add_argument("--field-dir", action="append", metavar="DIR",
                    help="seismic_<key>.* / mask_<key>.* pairs (a field set named after DIR)")
    ap.add_argument("--field", action="append", metavar="[NAME=]SECTION:MASK",
                    help="one labelled section (.png, .npy, .sgy) of field set NAME (field)")
    ap.add_argument("--no-thin", action="store_true", help="score masks as drawn, not thinned")
    ap.add_argument("--f3", metavar="PATH", help="an unlabelled section (F3): share above 0.5")
    ap.add_argument("--field-scale", nargs="+", default=["1", "auto"],
                    help="resampling of field sections: 1, auto (dominant periods) or a factor")
    ap.add_argument("--tolerance", type=float, nargs="+", default=[3.0, 2.0],
                    help="matching distances (px)")
    ap.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2, 3, 4])
    ap.add_argument("--train-runs", type=int, nargs="+", metavar="N",
                    help="a learning curve: each one-store training set trains one model per N "
                    "on its first N train runs (named NAME@N), the held-out runs unchanged")
    add_training_args(ap, 600, "held-out sections scored per store")
    ap.add_argument("--results", default="field_benchmark.json", help="accumulated results")
    ap.add_argument("--figure", help="PNG: one seed's predictions beside the masks")
    ap.add_argument("--figure-seed", type=int, help="the seed drawn (default: the first)")
    ap.add_argument("--ignore", metavar="ARRAY[=V,V]",
                    help="train with the pixels of this label array (with these values; "
                         "default any non-zero) left out of the loss, in the stores that hold "
                         "it (fault_uncertain: train_unet(ignore=))")
    ap.add_argument("--pos-weight", type=pos_weights, metavar="W[,W...]",
                    help="the fault pixels' weight in the cross-entropy (train_unet(pos_weight=)"
                         "; default: the background / fault ratio, capped at 50); several: "
                         "one per store of each training set, in the stores' order")
    args = ap.parse_args(argv)
    from demseis.errors import InputError
    from demseis.learning.train import parse_ignore

    args.ignore, args.ignore_values = parse_ignore(args.ignore)

    for s in args.field_scale:
        if s != "auto":
            try:
                ok = float(s) > 0
            except ValueError:
                ok = False
            if not ok:
                raise InputError(f"--field-scale {s!r}: expected auto or a factor > 0")
    return args


def main(argv: list[str] | None = None) -> int:
    args = parse_args(argv)
    import torch

    from demseis.errors import InputError
    from demseis.learning.train import build_unet, train_unet

    cuda, device, steps, base = budget(args, 600)
    fr = (1.0 - args.test_fraction, 0.0, args.test_fraction)
    tols = sorted(set(args.tolerance), key=args.tolerance.index)
    cache = Path(args.cache).expanduser()
    (cache / "models").mkdir(parents=True, exist_ok=True)
    fsets = field_sets(args)
    trains = any((args.store, args.mix, args.planar, args.planar_steep, args.generate))
    tsets = training_sets(args, cache) if trains or not args.model else {}
    limits: dict[str, int] = {}  # training set -> the train runs it uses (--train-runs)
    if args.train_runs:
        tsets, limits = learning_curve_sets(tsets, args.train_runs)
    for name, (stores, _) in tsets.items():
        if isinstance(args.pos_weight, list) and len(args.pos_weight) != len(stores):
            raise InputError(f"--pos-weight: {len(args.pos_weight)} weights for training set "
                             f"{name!r} of {len(stores)} store(s); give one, or one per store")

    # what every model is scored on: item key -> item; a key names its inputs
    items: dict[str, dict] = {}
    for store in dict.fromkeys(p for ps, _ in tsets.values() for p in ps):
        name = next((n.split("@")[0] for n, (ps, _) in tsets.items() if ps == [store]),
                    Path(store).stem)
        items[f"synthetic:{name}:{digest([store_id(store), fr, args.max_eval, tols])}"] = {
            "kind": "synthetic", "name": name, "store": store, "fr": fr,
            "max_eval": args.max_eval}
    for scale in args.field_scale:
        for fname, pairs in fsets.items():
            ids = [_file_id(s) + _file_id(m) for _, s, m in pairs]
            items[f"field:{fname}:{scale}:{digest([ids, not args.no_thin, tols])}"] = {
                "kind": "field", "name": fname, "scale": scale, "pairs": pairs,
                "thin": not args.no_thin}
        if args.f3:
            items[f"f3:{scale}:{digest(_file_id(args.f3))}"] = {
                "kind": "f3", "scale": scale, "path": args.f3}

    if fsets or args.f3:  # the field sets and F3 at the threshold chosen on held-out runs
        ids = [[_file_id(s) + _file_id(m) for _, s, m in pairs] for pairs in fsets.values()]
        f3_id = _file_id(args.f3) if args.f3 else None
        items["heldout_threshold:" + digest([ids, f3_id, not args.no_thin, fr, args.max_eval,
                                             tols, HELDOUT_TOL])] = {
            "kind": "heldout_threshold", "field": fsets, "f3": args.f3, "fr": fr,
            "max_eval": args.max_eval, "thin": not args.no_thin}

    for arg in args.model or []:  # given models: scored as they are, on the field sections
        print(json.dumps(model_line(arg, items, tols)), flush=True)

    path = Path(args.results)
    results = load_results(path, "field_benchmark")
    fig_seed = args.figure_seed if args.figure_seed is not None else args.seeds[0]
    panels: dict = {}
    cache_data: dict = {}
    periods: dict[str, float] = {}
    for name, (stores, weights) in tsets.items():
        config = {"stores": stores, "weights": weights,
                  "store_ids": [store_id(s) for s in stores], "steps": steps,
                  "base": base, "crop": args.crop, "batch": args.batch, "lr": args.lr,
                  "device": device.split(":")[0], "augment": True, "amp": cuda,
                  "test_fraction": args.test_fraction}
        if args.ignore:  # only then in the config: the fingerprints without it stay
            config["ignore"] = [args.ignore, args.ignore_values]
        if args.pos_weight is not None:  # likewise
            config["pos_weight"] = args.pos_weight
        where = None
        if name in limits:  # only then in the config: the fingerprints of full sets stay
            config["train_runs"] = limits[name]
            where = {"run_id": first_train_runs(stores[0], fr, limits[name])}
        fp = digest({k: v for k, v in config.items() if k != "stores"})
        results.setdefault("configs", {}).setdefault(fp, config)
        config["machine"] = machine(cuda, args.threads)
        for s in stores if "auto" in args.field_scale else ():
            if s not in periods:
                periods[s] = store_period(s)
        train_period = float(np.median([periods[s] for s in stores])) if periods else 1.0
        cells = []
        for seed in args.seeds:
            cell = next((c for c in results["cells"] if c["config"] == fp and c["seed"] == seed),
                        None)
            todo = [k for k in items if cell is None or k not in cell["scores"]]
            want_fig = args.figure and seed == fig_seed
            if cell is not None and not todo and not want_fig:
                cells.append(cell)
                continue
            saved = cache / "models" / f"{fp}-{seed}.pt"
            if cell is not None and saved.exists():
                model = build_unet(base)
                model.load_state_dict(torch.load(saved, map_location="cpu", weights_only=True))
                model.to(device)
            else:
                print(f"training {name} seed {seed} ({steps} steps)", file=sys.stderr)
                model, info = train_unet(stores, steps=steps, crop=args.crop, batch=args.batch,
                                         base=base, lr=args.lr, seed=seed, threads=args.threads,
                                         device=device, split_fractions=fr, log=None,
                                         augment=True, amp=cuda, weights=weights,
                                         where=where, ignore=args.ignore,
                                         ignore_values=args.ignore_values,
                                         pos_weight=args.pos_weight)
                torch.save(model.state_dict(), saved)
                results["cells"] = [c for c in results["cells"]
                                    if not (c["config"] == fp and c["seed"] == seed)]
                cell = {"config": fp, "model": name, "seed": seed, "train": info,
                        "machine": config["machine"], "scores": {}}
                results["cells"].append(cell)
                todo = list(items)
            if want_fig:  # the drawn predictions are made again (they are not kept)
                todo += [k for k, it in items.items() if k not in todo
                         and it["kind"] in ("field", "f3") and it["scale"] == args.field_scale[0]]
            t0 = time.perf_counter()
            cell_probs: dict = {}  # this model's predictions, shared between its items
            for key in sorted(todo, key=lambda k: items[k]["kind"] == "heldout_threshold"):
                got = item_scores(model, key, items[key], tols, train_period, cache_data,
                                  cell_probs, stores)
                probs = got.pop("_prob", None)
                cell["scores"][key] = got
                scale = items[key].get("scale")
                if want_fig and probs is not None and scale == args.field_scale[0]:
                    names = ["F3"] if items[key]["kind"] == "f3" else \
                        [f"{items[key]['name']}/{n}" for n, _, _ in items[key]["pairs"]]
                    probs = [probs] if items[key]["kind"] == "f3" else probs
                    panels.setdefault(name, {}).update(zip(names, probs))
            cell["score_seconds"] = round(time.perf_counter() - t0, 1)
            save_results(path, results)  # after every cell: an interrupted run loses one cell
            cells.append(cell)
        print(json.dumps(summary_line(name, cells, items, results["configs"][fp])), flush=True)
    if args.figure and panels:
        sections = [(f"{it['name']}/{n}", *cache_data[(s, m)]) for it in items.values()
                    if it["kind"] == "field" and it["scale"] == args.field_scale[0]
                    for n, s, m in it["pairs"]]
        if args.f3:
            sections.append(("F3", cache_data["f3"], None))
        note = (" F3 Netherlands data courtesy of dGB Earth Sciences, CC BY-SA 3.0; the figure "
                "is CC BY-SA 3.0." if args.f3 else "")
        draw(Path(args.figure), panels, sections,
             f"fault probability (> 0.2), seed {fig_seed}, field scale "
             f"{args.field_scale[0]}, {steps} steps, base {base}.{note}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
