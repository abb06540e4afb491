"""Where to read a model's probabilities: hand-picked field sections scored at 0.5, at the
model's own threshold and at Otsu's threshold of each section.

A network's probabilities run as high as its training labels were dense: a model trained on
the DEM ``field`` preset's labels puts most of a field section above 0.5. ``demseis train``
chooses a threshold on its validation runs and saves it with the model (``demseis threshold``
adds one to an older model); ``demseis predict --mask`` and ``--png`` draw faults from it, and
``demseis plot --pred`` draws at Otsu's threshold of the prediction's own values unless given
one. This benchmark scores each given model file on the field sets at the three:

- ``f1_at_0.5``, ``f1_at_model``, ``f1_at_otsu``: F1 (pooled over a set's sections, at
  ``--tolerance`` px, masks thinned to one-pixel lines) of the prediction thresholded at 0.5,
  at the model's threshold (0.5 for a model without one), and at Otsu's threshold of each
  section's probabilities (:func:`demseis.plotting.otsu_threshold`, the default of ``demseis
  plot``);
- ``share_at_*``: the share of the set's pixels marked so; with ``--f3``, F3's shares.

One JSON line per model, then one per ``--group`` (means over the models named it and a number,
and the paired differences of the model's threshold against the others)::

    PYTHONPATH=$PWD python benchmarks/model_threshold.py mix0=mix-0.pt mix1=mix-1.pt \\
        --field-dir ~/.cache/demseis-field/wrona-tutorial-03 \\
        --field-dir ~/.cache/demseis-field/gsb-cunha2020 --f3 ../shared/field/f3_inline.sgy \\
        --group mix
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _field_common import field_dir_pairs, read_pair, read_section, score_stack  # noqa: E402

RULES = ("0.5", "model", "otsu")


def readings(model, sets: dict, f3: np.ndarray | None, tolerance: float) -> dict:
    """The F1 and share of each field set, and F3's share, at each threshold rule."""
    from demseis.learning.model import model_threshold, predict_array
    from demseis.plotting import otsu_threshold

    t_model = model_threshold(model)[0]

    def marked(rule: str, p: np.ndarray) -> np.ndarray:
        """``p`` >= the rule's threshold, as 0/1 (Otsu's differs per section)."""
        t = otsu_threshold(p) if rule == "otsu" else (t_model if rule == "model" else 0.5)
        return (p >= t).astype(np.float32)

    out: dict = {"threshold": t_model, "field": {}}
    for name, pairs in sets.items():
        probs = [predict_array(model, sec) for sec, _ in pairs]
        truth = [mask for _, mask in pairs]
        got = {}
        for rule in RULES:  # every rule as 0/1 maps, scored at 0.5
            marks = [marked(rule, p) for p in probs]
            got[f"f1_at_{rule}"] = round(float(score_stack(marks, truth, tolerance).f1), 4)
            got[f"share_at_{rule}"] = round(float(np.mean([m.mean() for m in marks])), 5)
        out["field"][name] = got
    if f3 is not None:
        p = predict_array(model, f3)
        out["f3"] = {f"share_at_{rule}": round(float(marked(rule, p).mean()), 5)
                     for rule in RULES}
    return out


def in_group(name: str, prefix: str) -> bool:
    """``name`` is ``prefix`` followed by a number (a seed): ``mix3`` is in ``mix``, ``mixods3``
    is not."""
    return name.startswith(prefix) and name[len(prefix):].isdigit()


def group_line(prefix: str, lines: list[dict]) -> dict:
    """Means over the models named ``prefix`` and a number, and the model's threshold minus
    each other rule per model (mean, and in how many models it is higher)."""
    mine = [x for x in lines if in_group(x["model"], prefix)]
    out: dict = {"group": prefix, "models": [x["model"] for x in mine],
                 "threshold": round(float(np.mean([x["threshold"] for x in mine])), 4),
                 "field": {}}
    for name in mine[0]["field"]:
        vals = {k: np.array([x["field"][name][k] for x in mine]) for k in mine[0]["field"][name]}
        got = {k: round(float(v.mean()), 4) for k, v in vals.items()}
        for other in ("0.5", "otsu"):
            d = vals["f1_at_model"] - vals[f"f1_at_{other}"]
            got[f"model_minus_{other}"] = {"mean": round(float(d.mean()), 4),
                                           "higher": int((d > 0).sum()), "of": len(d)}
        out["field"][name] = got
    if "f3" in mine[0]:
        out["f3"] = {k: round(float(np.mean([x["f3"][k] for x in mine])), 5)
                     for k in mine[0]["f3"]}
    return out


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("models", nargs="+", metavar="NAME=MODEL.pt")
    ap.add_argument("--field-dir", action="append", required=True,
                    help="a folder of seismic_X / mask_X pairs (as the field benchmark reads)")
    ap.add_argument("--f3", default=None, help="an unlabelled SEG-Y section: shares only")
    ap.add_argument("--tolerance", type=float, default=3.0, help="px (default 3)")
    ap.add_argument("--group", action="append", default=[],
                    help="also print the means of the models named this and a number (a seed)")
    ap.add_argument("--threads", type=int, default=1, help="torch CPU threads")
    args = ap.parse_args(argv)
    import torch

    from demseis.errors import InputError
    from demseis.learning.model import load_model

    torch.set_num_threads(args.threads)
    sets = {Path(d).expanduser().name: [read_pair(s, m, thin_lines=True)
                                        for _, s, m in field_dir_pairs(d)]
            for d in args.field_dir}
    f3 = read_section(args.f3, "--f3") if args.f3 else None
    lines = []
    for arg in args.models:
        name, eq, path = arg.partition("=")
        if not eq or not name:
            raise InputError(f"{arg!r}: expected NAME=MODEL.pt")
        line = {"benchmark": "model_threshold", "model": name, "path": path,
                "tolerance_px": args.tolerance,
                **readings(load_model(path, "cpu"), sets, f3, args.tolerance)}
        print(json.dumps(line), flush=True)
        lines.append(line)
    for prefix in args.group:
        if not any(in_group(x["model"], prefix) for x in lines):
            raise InputError(f"--group {prefix!r}: no model is named it and a number")
        print(json.dumps({"benchmark": "model_threshold", **group_line(prefix, lines)}),
              flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
