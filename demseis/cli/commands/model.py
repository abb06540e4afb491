"""The handlers of ``demseis train`` and ``predict``; their parsers are in
:mod:`demseis.cli.model`."""

from __future__ import annotations

import argparse
import sys

from demseis.api import predict, train
from demseis.errors import InputError
from demseis.learning.train import parse_ignore
from demseis.plotting import plot_section


def _weights(text: str | None) -> list[float] | None:
    """``--weights 2,1`` as numbers; their count and sign are checked with the stores."""
    if text is None:
        return None
    try:
        return [float(w) for w in text.split(",")]
    except ValueError:
        raise InputError(f"--weights {text!r}: give one number per store, comma-separated, "
                         "e.g. 2,1") from None


def cmd_train(args: argparse.Namespace) -> int:
    quiet = args.quiet
    ignore, ignore_values = parse_ignore(args.ignore)
    metrics = train(args.store, args.out, weights=_weights(args.weights), steps=args.steps, crop=args.crop, batch=args.batch,
          base=args.base, lr=args.lr, seed=args.seed, device=args.device,
          val_every=args.val_every, save_every=args.save_every, resume=args.resume,
          threads=args.threads, progress=not quiet and sys.stderr.isatty(),
          log=None if quiet else print, ignore=ignore, ignore_values=ignore_values)
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
    out = predict(model, source, args.out, device=args.device, overwrite=args.overwrite,
                  progress=sys.stderr.isatty())
    print(f"wrote {out}")
    if args.png is not None:
        print(f"wrote {plot_section(source, args.png, pred=out)}")
    return 0
