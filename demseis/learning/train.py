"""A small 2D U-Net trained on a demseis store: one training loop for the examples and benchmarks.

Only the public API is used (:class:`demseis.datasets.FaultSegDataset`, PyTorch). PyTorch
(~2 s to import) is imported inside the functions that run it, so importing this module stays
light.

::

    from demseis.learning.train import train_unet, predict_sections
    model, log = train_unet("quick.zarr", steps=300)             # train split, random crops
    prob = predict_sections(model, sections)                      # (N, H, W) probabilities

The model: a 3-level U-Net (``base``, 2 ``base``, 4 ``base`` channels; ~120k parameters at
``base = 16``), each section standardised on the fly; loss = binary cross-entropy (positive
weight = background / fault pixel ratio of the first batches, capped at 50, or a given
``pos_weight``) + soft Dice; Adam.
Everything is seeded; on CPU results repeat for a fixed thread count.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Mapping, Sequence
from typing import Any

import numpy as np
from tqdm.auto import tqdm

from demseis.datasets import FaultSegDataset, open_store, store_layout
from demseis.errors import InputError, import_torch
from demseis.evaluation.scoring import SampleCounts, count_samples, summarise


def build_unet(base: int = 16):
    """A 3-level 2D U-Net: (B, 1, H, W) seismic -> (B, 1, H, W) fault logits (H, W % 4 == 0)."""
    torch = import_torch("the U-Net")  # lazy: heavy (~2 s), see the module docstring
    nn = torch.nn

    def block(cin: int, cout: int) -> nn.Sequential:
        return nn.Sequential(
            nn.Conv2d(cin, cout, 3, padding=1, bias=False), nn.BatchNorm2d(cout), nn.ReLU(True),
            nn.Conv2d(cout, cout, 3, padding=1, bias=False), nn.BatchNorm2d(cout), nn.ReLU(True),
        )

    class UNet(nn.Module):
        def __init__(self) -> None:
            super().__init__()
            self.enc1, self.enc2, self.mid = block(1, base), block(base, 2 * base), \
                block(2 * base, 4 * base)
            self.pool = nn.MaxPool2d(2)
            self.up2 = nn.ConvTranspose2d(4 * base, 2 * base, 2, stride=2)
            self.dec2 = block(4 * base, 2 * base)
            self.up1 = nn.ConvTranspose2d(2 * base, base, 2, stride=2)
            self.dec1 = block(2 * base, base)
            self.head = nn.Conv2d(base, 1, 1)

        def forward(self, x: torch.Tensor) -> torch.Tensor:
            # amplitude scale differs between sections: standardise each one
            x = (x - x.mean(dim=(2, 3), keepdim=True)) / (x.std(dim=(2, 3), keepdim=True) + 1e-6)
            e1 = self.enc1(x)
            e2 = self.enc2(self.pool(e1))
            m = self.mid(self.pool(e2))
            d2 = self.dec2(torch.cat([self.up2(m), e2], 1))
            d1 = self.dec1(torch.cat([self.up1(d2), e1], 1))
            return self.head(d1)

    return UNet()


def predict_sections(model, sections: np.ndarray, batch: int = 4,
                     device: str | None = None) -> np.ndarray:
    """Fault probabilities (N, H, W) float32 of seismic sections (N, H, W), padded to % 4."""
    torch = import_torch("prediction")  # lazy: heavy (~2 s), see the module docstring

    sections = np.asarray(sections)
    if sections.ndim != 3:
        raise InputError(f"sections must be (N, H, W), got shape {sections.shape}")
    dev = torch.device(device) if device else next(model.parameters()).device
    n, h, w = sections.shape
    ph, pw = (-h) % 4, (-w) % 4
    out = np.empty((n, h, w), np.float32)
    model.eval()
    with torch.no_grad():
        for s in range(0, n, batch):
            x = torch.from_numpy(np.ascontiguousarray(sections[s: s + batch], np.float32))[:, None]
            x = torch.nn.functional.pad(x, (0, pw, 0, ph), mode="reflect").to(dev)
            out[s: s + batch] = torch.sigmoid(model(x))[:, 0, :h, :w].float().cpu().numpy()
    return out


#: the validation scores that can pick the model kept (``select``), as the log names them
SELECT = {"f1": "F1", "ods_f1": "ODS F1"}


def train_unet(store: Any, *, steps: int | None = None, minutes: float | None = None,
               split: str = "train", target: str = "fault", crop: int = 96, batch: int = 8,
               base: int = 16, lr: float = 2e-3, seed: int = 0, threads: int | None = None,
               device: str | None = None, where: Mapping[str, Any] | Callable | None = None,
               split_fractions: tuple[float, float, float] = (0.8, 0.1, 0.1),
               log: Callable[[str], None] | None = print, augment: bool = False,
               amp: bool | None = None, val_every: int | None = None, patience: int = 5,
               checkpoint: str | None = None,
               progress: bool = False, resume: Mapping[str, Any] | None = None,
               save_every: int | None = None,
               save: Callable[[dict[str, Any]], None] | None = None,
               weights: Sequence[float] | None = None, ignore: str | None = None,
               ignore_values: Sequence[int] | None = None,
               select: str = "f1", pos_weight: float | Sequence[float] | None = None
               ) -> tuple[Any, dict[str, Any]]:
    """Train :func:`build_unet` on random crops of a store's ``split``.

    Parameters
    ----------
    store : a store path (or what :class:`demseis.datasets.FaultSegDataset` accepts), or a
        list of them: the training set is then their ``split`` samples, drawn (with
        replacement) so that store s gives the share ``weights[s] / sum(weights)`` of every
        batch on average (a mix; :func:`mix_sampler`).
    weights : one positive weight per store (default: equal shares); :func:`check_weights`.
    ignore : a label array whose pixels with one of ``ignore_values`` (None: any non-zero
        value) are left out of the loss (binary cross-entropy and Dice alike), in each store
        that holds it; stores without it train on every pixel. ``"fault_uncertain"``
        (``[labels] fault_uncertain = true``) marks where the fault label and the section's
        visible offsets disagree. None: every pixel counts.
    pos_weight : the weight of fault pixels in the binary cross-entropy. None: the background /
        fault pixel ratio of the first 8 batches (kept pixels only), capped at 50, which makes
        the probabilities of faint faults high (a model is then read at a threshold well above
        0.5). 1: unweighted (the cross-entropy alone would then estimate the chance of a
        label; docs/benchmarks.md, "The loss weight of fault pixels"). A list of one weight
        per store (a mix): each sample's fault pixels are weighted by its store's weight.
    augment : random left-right flips, polarity flips and amplitude scaling (x 0.5 .. 2) of
        each training crop.
    amp : CUDA mixed precision (autocast + gradient scaling); None = on when on CUDA.
    val_every : every this many steps, score whole sections of the ``val`` split (runs held
        out of training, of every store) at tolerance 2 px (by ``select``); keep the best
        model, write it to ``checkpoint`` (``torch.save`` of the state dict, when given),
        and stop after ``patience`` evaluations without improvement. The returned model is the
        best one. None: no validation.
    progress : a progress bar on stderr (tqdm).
    resume : a state from ``save`` (:func:`training_state`): training goes on from its step
        with its weights, optimiser, positive weight and best validation model.
    save_every, save : every ``save_every`` steps and at the end, ``save`` is called with the
        training state (weights, optimiser, step ...), for a later ``resume``.
    steps : optimiser steps (exactly this many), or
    minutes : a wall-clock budget instead (the number of steps then depends on the machine).
    split, where, split_fractions : which samples (see
        :class:`demseis.datasets.FaultSegDataset`).
    target : label array learned (``"fault"``).
    crop : square training crop (multiple of 4, at most the section's smaller side).
    batch, base, lr, seed : batch size, U-Net base width, Adam learning rate, seed.
    threads : torch CPU threads (None: leave torch's setting).
    device : ``"cuda"``, ``"cpu"``... (None: CUDA when available).
    log : called with progress lines (None: silent).
    select : the validation score that picks the model kept: ``"f1"`` at threshold 0.5, or
        ``"ods_f1"``, F1 at the threshold best for that model (the threshold sweep of
        :func:`demseis.evaluation.score`), for a model read at a threshold chosen on the
        validation runs (:func:`demseis.learning.model.choose_threshold`).

    Returns
    -------
    (model, info) with info keys steps, epochs, seconds, final_loss, pos_weight, n_samples,
    n_runs, device, drawn_per_store (training samples drawn from each store, counted over the
    steps, a resumed training's included), with ``ignore`` ignored_fraction (the share of the
    first batches' pixels left out of the loss); with validation also best_val_f1 (pooled over
    every store's val runs: the ``select`` score), val_f1_per_store (each store's score of
    the kept model), best_step, stopped_early, val_history.
    """
    torch = import_torch("training")  # lazy: heavy (~2 s), see the module docstring
    data = torch.utils.data
    if select not in SELECT:
        raise InputError(f"select {select!r}: expected one of {', '.join(SELECT)}")
    stores = list(store) if isinstance(store, (list, tuple)) else [store]
    per_store = check_pos_weight(pos_weight, len(stores))
    if per_store and len(stores) == 1:  # one store: its weight is the weight
        pos_weight, per_store = float(pos_weight[0]), False

    if (steps is None) == (minutes is None):
        raise InputError("train_unet: give exactly one of steps or minutes")
    if steps is not None and steps < 1:
        raise InputError(f"train_unet: steps = {steps}; allowed: >= 1")
    torch.manual_seed(seed)
    if threads:
        torch.set_num_threads(int(threads))
    dev = torch.device(device or ("cuda" if torch.cuda.is_available() else "cpu"))
    shares = check_weights(weights, len(stores))
    read = dict(inputs=("seismic",), split=split, crop=(crop, crop), seed=seed, where=where,
                split_fractions=split_fractions)
    parts = ([FaultSegDataset(s, targets=(target,), **read) for s in stores] if ignore is None
             else _with_ignore(stores, target, ignore, read))
    for s, part in zip(stores, parts):
        if len(part) == 0:
            raise InputError(f"the {split} split of store {str(s)!r} is empty")
        h, w = part.layout.shape
        if crop > min(h, w) or crop % 4:
            raise InputError(f"crop = {crop}; allowed: a multiple of 4, at most {min(h, w)}")
    gen = torch.Generator().manual_seed(seed)
    if len(parts) == 1:
        ds = parts[0]
        # what DataLoader(shuffle=True, generator=gen) draws, with the draws counted
        draws = _StoreDraws(data.RandomSampler(ds, generator=gen), [len(ds)])
        loader = data.DataLoader(ds, batch_size=batch, sampler=draws, generator=gen,
                                 drop_last=False)
    else:
        ds = _Mixed(parts, data.ConcatDataset(parts))
        sizes = [len(p) for p in parts]
        draws = _StoreDraws(mix_sampler(sizes, shares, gen), sizes)
        # each item tagged with its store, for a weight of fault pixels per store
        loader = data.DataLoader(_Tagged(ds.concat, sizes), batch_size=batch, sampler=draws,
                                 drop_last=False)
    use_amp = (dev.type == "cuda") if amp is None else bool(amp and dev.type == "cuda")
    scaler = torch.amp.GradScaler("cuda", enabled=use_amp)
    if resume is None:
        # fault pixels are rare: weight them by the background / fault ratio of a few batches
        if ignore is None:
            frac = np.mean([float((b[1] > 0).float().mean()) for _, b in zip(range(8), loader)])
        else:
            first = [_split_ignore(b[1], target, ignore, ignore_values) for _, b in
                     zip(range(8), loader)]
            kept = sum(float(k.sum()) for _, k in first)
            frac = sum(float(((y > 0) & k).sum()) for y, k in first) / max(kept, 1.0)
            ignored_fraction = 1.0 - kept / max(sum(k.numel() for _, k in first), 1)
        ratio = min((1 - frac) / max(frac, 1e-6), 50.0) if pos_weight is None else pos_weight
        draws.counts[:] = 0  # those batches were looked at, not trained on
    else:
        frac = float(resume["fault_fraction"])
        ratio = resume["pos_weight"]
        per_store = np.ndim(ratio) > 0
        ignored_fraction = float("nan")
    # one weight (a scalar tensor) or one per store (indexed by each sample's store)
    pos_weight = torch.tensor([float(w) for w in ratio] if per_store else float(ratio),
                              dtype=torch.float32, device=dev)
    recorded = pos_weight.tolist()  # float or list of floats, as the loss uses them
    model = build_unet(base).to(dev)
    opt = torch.optim.Adam(model.parameters(), lr=lr)
    t0, step, epoch, losses = time.perf_counter(), 0, 0, []
    budget = None if minutes is None else 60.0 * float(minutes)

    val = _validation_set(stores, target, split_fractions) if val_every else None
    best = {"f1": -1.0, "step": 0, "state": None, "bad": 0, "history": []}
    if resume is not None:
        model.load_state_dict(resume["model"])
        opt.load_state_dict(resume["optimizer"])
        step, epoch = int(resume["step"]), int(resume["epoch"])
        best.update(resume["best"])
        if len(resume.get("drawn", [])) == len(stores):
            draws.counts[:] = resume["drawn"]
        gen.manual_seed(seed + step)  # a different crop order than the one already trained on

    def state() -> dict[str, Any]:
        return training_state(model, opt, step=step, epoch=epoch, pos_weight=recorded,
                              fault_fraction=float(frac), best=best, drawn=draws.counts)

    bar = None
    if progress:
        bar = tqdm(total=steps, initial=min(step, steps or step), unit="step", desc="train")

    def done() -> bool:
        if best["bad"] >= patience:
            return True
        return step >= steps if steps is not None else time.perf_counter() - t0 >= budget

    def validate() -> None:
        counts = [None if x is None else
                  count_samples(predict_sections(model, x, device=str(dev)), y, 0.5, 2)
                  for x, y in zip(*val)]
        # pooled over every store's val sections: the selection criterion
        f1 = float(getattr(summarise(SampleCounts.concat([c for c in counts if c is not None])),
                           select))
        each = [None if c is None else round(float(getattr(summarise(c), select)), 4)
                for c in counts]
        best["history"].append((step, round(f1, 4)))
        if f1 > best["f1"]:
            best.update(f1=f1, step=step, bad=0, per_store=each,
                        state={k: v.detach().clone() for k, v in model.state_dict().items()})
            if checkpoint:
                torch.save(best["state"], checkpoint)
        else:
            best["bad"] += 1
        if log:
            per = ", ".join("-" if x is None else f"{x:.4f}" for x in each)
            per = f"  (per store {per})" if len(each) > 1 else ""
            log(f"  step {step:5d}  val {SELECT[select]}@2 {f1:.4f}{per}  "
                f"best {best['f1']:.4f} "
                f"(step {best['step']})")

    if log and len(parts) > 1:
        for s_, part, share in zip(stores, parts, shares):
            log(f"train: store {str(s_)!r}: {len(part)} samples "
                f"({len(np.unique(part.run_ids))} runs), share {share:.3f} of the batches")
    if log:
        log(f"train: {len(ds)} samples ({len(np.unique(ds.run_ids))} runs), crop {crop}, "
            f"fault fraction {frac:.4f}, pos_weight {_show(recorded)}, device {dev}, "
            + (f"{steps} steps" if steps is not None else f"budget {minutes:g} min"))
    while not done():
        ds.set_epoch(epoch)
        model.train()
        for item in loader:
            x, y = item[0].to(dev), item[1]
            pw = pos_weight[item[2].to(dev)].view(-1, 1, 1, 1) if per_store else pos_weight
            if ignore is None:
                y = (y > 0).float()[:, None].to(dev)
                if augment:
                    x, y = _augment(x, y, gen)
            else:
                y, keep = _split_ignore(y, target, ignore, ignore_values)
                # one tensor through the flips, so the mask moves with its label
                yk = torch.stack([(y > 0), keep], dim=1).float().to(dev)
                if augment:
                    x, yk = _augment(x, yk, gen)
                y, keep = yk[:, :1], yk[:, 1:]
            with torch.autocast(dev.type, enabled=use_amp):
                logits = model(x)
            logits = logits.float()
            if ignore is None:
                p = torch.sigmoid(logits)
                dice = 1 - (2 * (p * y).sum() + 1) / (p.sum() + y.sum() + 1)
                loss = torch.nn.functional.binary_cross_entropy_with_logits(
                    logits, y, pos_weight=pw) + dice
            else:
                loss = masked_loss(logits, y, keep, pw)
            opt.zero_grad()
            scaler.scale(loss).backward()
            scaler.step(opt)
            scaler.update()
            losses.append(float(loss.detach()))
            step += 1
            if bar is not None:
                bar.update(1)
                bar.set_postfix(loss=f"{losses[-1]:.3f}")
            if val is not None and step % int(val_every) == 0:
                validate()
                model.train()
            if save is not None and save_every and step % int(save_every) == 0:
                save(state())
            if log and step % 50 == 0:
                log(f"  step {step:5d}  epoch {epoch:3d}  loss {np.mean(losses[-50:]):.4f}  "
                    f"{time.perf_counter() - t0:6.0f} s")
            if done():
                break
        epoch += 1
    if bar is not None:
        bar.close()
    if save is not None:
        save(state())
    if val is not None and best["state"] is not None:
        model.load_state_dict(best["state"])
    info = {"steps": step, "epochs": epoch, "seconds": round(time.perf_counter() - t0, 1),
            "final_loss": float(np.mean(losses[-50:])) if losses else float("nan"),
            "pos_weight": ([round(w, 2) for w in recorded] if per_store
                           else round(recorded, 2)), "n_samples": len(ds),
            "n_runs": int(len(np.unique(ds.run_ids))), "device": str(dev), "amp": use_amp,
            "augment": bool(augment), "drawn_per_store": [int(c) for c in draws.counts]}
    if ignore is not None:
        info["ignored_fraction"] = round(float(ignored_fraction), 4)
    if val is not None:
        info.update(best_val_f1=round(best["f1"], 4), best_step=best["step"],
                    val_f1_per_store=best.get("per_store"),
                    stopped_early=best["bad"] >= patience, val_history=best["history"])
    if log:
        log(f"trained {step} steps ({epoch} epochs) in {info['seconds']:.0f} s, "
            f"final loss {info['final_loss']:.4f}")
    return model, info


def training_state(model: Any, opt: Any, *, step: int, epoch: int,
                   pos_weight: float | Sequence[float],
                   fault_fraction: float, best: Mapping[str, Any],
                   drawn: Sequence[int] = ()) -> dict[str, Any]:
    """What :func:`train_unet` needs to ``resume``: weights, optimiser, step, epoch, the loss's
    positive weight, the best validation model so far and the samples drawn from each store
    (plain types and tensors, so that ``torch.load(..., weights_only=True)`` reads it)."""
    kept = {"f1": float(best["f1"]), "step": int(best["step"]), "state": best["state"],
            "bad": int(best["bad"]), "history": [list(h) for h in best["history"]]}
    if best.get("per_store") is not None:
        kept["per_store"] = [None if x is None else float(x) for x in best["per_store"]]
    return {"model": model.state_dict(), "optimizer": opt.state_dict(), "step": int(step),
            "epoch": int(epoch),
            "pos_weight": (float(pos_weight) if np.ndim(pos_weight) == 0
                           else [float(w) for w in pos_weight]),
            "fault_fraction": float(fault_fraction), "best": kept,
            "drawn": [int(c) for c in drawn]}


def check_pos_weight(pos_weight: float | Sequence[float] | None, n_stores: int) -> bool:
    """Whether ``pos_weight`` is one weight per store (True) or one for all (False; None too).

    InputError, one line, when a weight is not a finite number greater than 0, or a list's
    length is not ``n_stores`` (a list of one is one weight per store of a single store).
    """
    if pos_weight is None:
        return False
    values = [pos_weight] if np.ndim(pos_weight) == 0 else list(pos_weight)
    for x in values:
        if not _positive(x):
            raise InputError(f"pos_weight = {x!r}; allowed: a number > 0 (or None: the "
                             "background / fault ratio)")
    if np.ndim(pos_weight) == 0:
        return False
    if len(values) != n_stores:
        raise InputError(f"pos_weight: {len(values)} weight(s) for {n_stores} store(s); give "
                         "one, or one per store in the stores' order")
    return True


def _positive(x: Any) -> bool:
    """A finite number greater than 0 (a bool is not a number here)."""
    ok = isinstance(x, (int, float, np.integer, np.floating)) and not isinstance(x, bool)
    return ok and bool(np.isfinite(x)) and x > 0


def _store_of(ends: np.ndarray, i: int) -> int:
    """The store of item ``i`` of a concatenation whose stores end at ``ends`` (cumsum)."""
    return int(np.searchsorted(ends, int(i), side="right"))


def _show(weight: float | Sequence[float]) -> str:
    """A loss weight for the log: ``45.3`` or ``[40.0, 5.0]``."""
    if np.ndim(weight) == 0:
        return f"{float(weight):.1f}"
    return "[" + ", ".join(f"{float(w):.1f}" for w in weight) + "]"


def check_weights(weights: Sequence[float] | None, n_stores: int) -> list[float]:
    """The shares ``w / sum(w)`` of the stores' weights (equal shares for None).

    InputError, one line, when their number is not ``n_stores`` or one is not a finite number
    greater than 0.
    """
    if weights is None:
        return [1.0 / n_stores] * n_stores
    w = list(weights)
    if len(w) != n_stores:
        raise InputError(f"--weights: {len(w)} weight(s) for {n_stores} store(s); give one per "
                         "store, in the stores' order")
    for i, x in enumerate(w):
        if not _positive(x):
            raise InputError(f"--weights: weight {i + 1} is {x!r}; each must be a finite number "
                             "greater than 0")
    total = float(sum(float(x) for x in w))
    return [float(x) / total for x in w]


def mix_sampler(sizes: Sequence[int], shares: Sequence[float], generator: Any) -> Any:
    """Indices into the concatenation of datasets of ``sizes``: each draw (with replacement)
    falls in dataset s with probability ``shares[s]`` and is uniform within it; ``sum(sizes)``
    draws per epoch. A torch ``WeightedRandomSampler`` drawing from ``generator``."""
    torch = import_torch("training")  # lazy: heavy (~2 s), see the module docstring
    # equal shares keep the per-sample weights 1 / size of the mix before weights existed
    equal = len(set(shares)) == 1
    w = torch.cat([torch.full((n,), (1.0 if equal else float(sh)) / n)
                   for n, sh in zip(sizes, shares)])
    return torch.utils.data.WeightedRandomSampler(w, num_samples=int(sum(sizes)),
                                                  generator=generator)


class _StoreDraws:
    """A sampler's indices into the stores' concatenation, passed on and counted per store."""

    def __init__(self, sampler: Any, sizes: Sequence[int]) -> None:
        self.sampler = sampler
        self.ends = np.cumsum(sizes)
        self.counts = np.zeros(len(sizes), np.int64)

    def __len__(self) -> int:
        return len(self.sampler)

    def __iter__(self) -> Any:
        for i in self.sampler:
            self.counts[_store_of(self.ends, i)] += 1
            yield i


def _validation_set(stores: list, target: str, split_fractions: tuple[float, float, float]
                    ) -> tuple[list[np.ndarray], list[np.ndarray]]:
    """Whole sections and 0/1 truth of the ``val`` split of each store (runs, not samples), one
    (M_s, H_s, W_s) array per store (stores may differ in section size), None for a store
    without val samples."""
    xs, ys = [], []
    for s in stores:
        ds = FaultSegDataset(s, inputs=("seismic",), targets=(target,), split="val",
                             split_fractions=split_fractions)
        pairs = [ds[i] for i in range(len(ds))]
        xs.append(np.stack([x[0].numpy() for x, _ in pairs]) if pairs else None)
        ys.append(np.stack([y.numpy() > 0 for _, y in pairs]) if pairs else None)
    if all(x is None for x in xs):
        raise InputError("val_every: the val split is empty (give split_fractions a val share)")
    return xs, ys


class _Tagged:
    """A concatenation's items ``(x, y)`` as ``(x, y, s)``: s the index of the store each
    item comes from (``sizes``: the stores' lengths, in order)."""

    def __init__(self, concat: Any, sizes: Sequence[int]) -> None:
        self.concat, self.ends = concat, np.cumsum(sizes)

    def __len__(self) -> int:
        return len(self.concat)

    def __getitem__(self, i: int) -> tuple[Any, Any, int]:
        x, y = self.concat[i]
        return x, y, _store_of(self.ends, i)


class _Mixed:
    """Several FaultSegDatasets trained on together (``len``, ``run_ids``, ``set_epoch``)."""

    def __init__(self, parts: list, concat: Any) -> None:
        self.parts, self.concat = parts, concat
        # run ids of different stores are different runs: offset them
        offsets = np.cumsum([0] + [int(np.max(p.run_ids)) + 1 for p in parts[:-1]])
        self.run_ids = np.concatenate([p.run_ids + o for p, o in zip(parts, offsets)])

    def __len__(self) -> int:
        return len(self.concat)

    def set_epoch(self, epoch: int) -> None:
        for p in self.parts:
            p.set_epoch(epoch)


def parse_ignore(text: str | None) -> tuple[str | None, list[int] | None]:
    """``--ignore fault_uncertain=1,2`` as the array's name and its values (None: any
    non-zero value); (None, None) for None.

    Raises
    ------
    InputError
        No name, or a value that is not an integer.
    """
    if text is None:
        return None, None
    name, sep, values = text.partition("=")
    try:
        vals = [int(v) for v in values.split(",")] if sep else None
    except ValueError:
        vals = []
    if not name or vals == []:
        raise InputError(f"--ignore {text!r}: give ARRAY or ARRAY=V1,V2 with integer values, "
                         "e.g. fault_uncertain=1,2")
    return name, vals


def masked_loss(logits: Any, y: Any, keep: Any, pos_weight: Any) -> Any:
    """The training loss over the kept pixels only: binary cross-entropy with ``pos_weight``
    averaged over the pixels where ``keep`` is 1, plus soft Dice ``1 - (2 sum(p y) + 1) /
    (sum(p) + sum(y) + 1)`` with ``p`` and ``y`` summed over those pixels. With every pixel
    kept it is the loss :func:`train_unet` uses without ``ignore``.

    Parameters
    ----------
    logits, y, keep : tensors of one shape; ``y`` and ``keep`` 0 or 1 (float).
    pos_weight : the positive class's weight: a scalar tensor, or one per sample of shape
        (B, 1, 1, 1).
    """
    torch = import_torch("training")
    p = torch.sigmoid(logits) * keep
    yk = y * keep
    dice = 1 - (2 * (p * yk).sum() + 1) / (p.sum() + yk.sum() + 1)
    per_px = torch.nn.functional.binary_cross_entropy_with_logits(
        logits, yk, pos_weight=pos_weight, reduction="none")
    return (per_px * keep).sum() / keep.sum().clamp_min(1.0) + dice


def _with_ignore(stores: list, target: str, ignore: str, read: Mapping[str, Any]) -> list:
    """The FaultSegDatasets of ``stores`` (``read``: their other arguments) with the ``ignore``
    array as a second target where the store holds it, and an all-zero one made up where it
    does not (so every item is alike).

    Raises
    ------
    InputError
        No store holds ``ignore``.
    """
    layouts = [store_layout(open_store(s, "r")) for s in stores]
    have = [ignore in lay.arrays for lay in layouts]
    if not any(have):
        held = sorted({a for lay in layouts for a in lay.arrays})
        raise InputError(f"ignore = {ignore!r}: no training store holds that array; they hold "
                         f"{', '.join(held)} (fault_uncertain is stored with [labels] "
                         "fault_uncertain = true)")
    out = []
    for s, h in zip(stores, have):
        out.append(FaultSegDataset(s, targets=(target, ignore) if h else (target,),
                                   transform=None if h else _NoneIgnored(target, ignore),
                                   **read))
    return out


class _NoneIgnored:
    """The item transform of a store without the ignore array: ``y`` becomes the dict of
    several targets, with an all-zero ignore array (a class, so that it pickles)."""

    def __init__(self, target: str, ignore: str) -> None:
        self.target, self.ignore = target, ignore

    def __call__(self, x: Any, y: Any) -> tuple[Any, dict[str, Any]]:
        torch = import_torch("training")
        return x, {self.target: y, self.ignore: torch.zeros(y.shape, dtype=torch.uint8)}


def _split_ignore(y: Mapping[str, Any], target: str, ignore: str,
                  values: Sequence[int] | None) -> tuple[Any, Any]:
    """(label, keep): the batch's ``target`` and the bool mask of the pixels the loss reads."""
    return y[target], ~ignored_pixels(y[ignore], values)


def ignored_pixels(u: Any, values: Sequence[int] | None) -> Any:
    """Where the ignore array ``u`` (a NumPy array or a torch tensor) takes one of ``values``
    (None: any non-zero value): the pixels left out of the loss, as a bool array of ``u``'s
    kind."""
    if values is None:
        return u != 0
    out = (u != 0) & (u == 0)  # all False, of u's kind and shape
    for v in values:
        out = out | (u == int(v))
    return out


def _augment(x: Any, y: Any, gen: Any) -> tuple[Any, Any]:
    """Per-crop left-right flip, polarity flip and amplitude scaling (x 0.5 .. 2)."""
    torch = import_torch("training")  # lazy: heavy (~2 s), see the module docstring

    n = x.shape[0]
    flip = torch.rand(n, generator=gen) < 0.5
    if flip.any():
        idx = flip.nonzero()[:, 0].to(x.device)
        x[idx] = torch.flip(x[idx], dims=[-1])
        y[idx] = torch.flip(y[idx], dims=[-1])
    sign = torch.where(torch.rand(n, generator=gen) < 0.5, -1.0, 1.0)
    scale = sign * torch.exp(torch.empty(n).uniform_(np.log(0.5), np.log(2.0), generator=gen))
    return x * scale.to(x.device, x.dtype)[:, None, None, None], y
