"""The handlers of ``demseis train``, ``predict`` and ``threshold``; their parsers are in
:mod:`demseis.cli.model`."""

from __future__ import annotations

import argparse
import sys

from demseis.api import predict, train
from demseis.errors import InputError
from demseis.learning.model import (check_outputs, load_model, model_threshold, pretrained_path,
                                    set_threshold)
from demseis.learning.train import parse_ignore
from demseis.plotting import plot_section


def _numbers(flag: str, text: str, hint: str) -> list[float]:
    """The comma-separated numbers of option ``flag``; InputError ``flag 'text': hint``."""
    try:
        return [float(w) for w in text.split(",")]
    except ValueError:
        raise InputError(f"{flag} {text!r}: {hint}") from None


def _weights(text: str | None) -> list[float] | None:
    """``--weights 2,1`` as numbers; their count and sign are checked with the stores."""
    if text is None:
        return None
    return _numbers("--weights", text, "give one number per store, comma-separated, e.g. 2,1")


def _pos_weight(text: str | None) -> float | list[float] | None:
    """``--pos-weight 15`` as a number, ``--pos-weight 20,10`` as one per store; their count
    and sign are checked with the stores."""
    if text is None:
        return None
    values = _numbers("--pos-weight", text,
                      "give a number, or one per store comma-separated, e.g. 20,10")
    return values[0] if len(values) == 1 else values


def cmd_train(args: argparse.Namespace) -> int:
    quiet = args.quiet
    ignore, ignore_values = parse_ignore(args.ignore)
    metrics = train(args.store, args.out, weights=_weights(args.weights), steps=args.steps,
                    crop=args.crop, batch=args.batch, base=args.base, lr=args.lr,
                    seed=args.seed, device=args.device, val_every=args.val_every,
                    save_every=args.save_every, resume=args.resume, threads=args.threads,
                    progress=not quiet and sys.stderr.isatty(), log=None if quiet else print,
                    ignore=ignore, ignore_values=ignore_values, select=args.select,
                    pos_weight=_pos_weight(args.pos_weight))
    for text in metrics.get("warnings", []):
        print(f"demseis: warning: {text}", file=sys.stderr)
    return 0


def cmd_predict(args: argparse.Namespace) -> int:
    if len(args.paths) > 2:
        raise InputError(f"predict takes [MODEL] IN, got {len(args.paths)} paths: "
                         + " ".join(args.paths))
    if len(args.paths) == 2:
        if args.model is not None:
            raise InputError("give the model once: predict MODEL IN, or predict IN --model "
                             "MODEL")
        model, source = args.paths
    else:
        model, source = args.model, args.paths[0]
    check_outputs(source, args.out, mask=args.mask, overwrite=args.overwrite,
                  threshold=args.threshold)
    net = load_model(pretrained_path() if model is None else model, args.device)
    threshold, how = model_threshold(net)
    if args.threshold is not None:
        threshold, how = args.threshold, "given"
    out = predict(net, source, args.out, overwrite=args.overwrite, progress=sys.stderr.isatty(),
                  mask=args.mask, threshold=threshold)
    print(f"wrote {out}")
    if args.mask is not None:
        print(f"wrote {args.mask} (1 where the probability reaches {threshold:g}, {how})")
    if args.png is not None:
        print(f"wrote {plot_section(source, args.png, pred=out, threshold=threshold, how=how)}")
    return 0


def cmd_threshold(args: argparse.Namespace) -> int:
    chosen = set_threshold(args.model, args.store, device=args.device)
    print(f"threshold {chosen['threshold']:g}: F1 {chosen['f1']:.3f} at "
          f"{chosen['tolerance_px']} px on {chosen['samples']} samples of {chosen['runs']} "
          f"validation run(s); saved in {args.model}")
    return 0
