"""Draw models that the field benchmark trained in separate runs side by side: one seed of each,
on chosen field sections and F3 (fault probability above 0.2; each panel's title gives the share
above 0.5), with the field benchmark's own drawing.

Each model is named ``NAME=RESULTS[:MODEL]``: the field benchmark's ``--results`` file and the
training set's name in it (optional when the file holds one). Its weights are read from the
benchmark's ``--cache`` (``models/<config digest>-<seed>.pt``), so nothing is trained; a model
that was not kept there is an error that names it.

    PYTHONPATH=$PWD python benchmarks/field_models_figure.py \\
        "planar control=planar.json:planar_steep" "mix, weight 15=pw15.json" --seed 0 \\
        --field t3=seismic_inline_300.png:mask_inline_300.png --f3 ../shared/field/f3_inline.sgy \\
        --out field_pos_weight.png
"""

from __future__ import annotations

import argparse
import json
import runpy
from pathlib import Path

import numpy as np

BENCH = Path(__file__).resolve().with_name("field_benchmark.py")


def parse_args(argv: list[str] | None) -> argparse.Namespace:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("model", nargs="+", metavar="NAME=RESULTS[:MODEL]")
    ap.add_argument("--seed", type=int, default=0, help="the seed drawn (default 0)")
    ap.add_argument("--field-dir", action="append", metavar="DIR",
                    help="a field set's folder, as the field benchmark reads it (repeatable)")
    ap.add_argument("--field", action="append", metavar="[NAME=]SECTION:MASK",
                    help="a field section and its mask, as the field benchmark reads them "
                         "(repeatable); every section is drawn at scale 1")
    ap.add_argument("--f3", metavar="PATH", help="an unlabelled section drawn last")
    ap.add_argument("--cache", default=str(Path.home() / ".cache" / "demseis-bench" / "field"),
                    help="the field benchmark's --cache")
    ap.add_argument("--title", default="fault probability (> 0.2)")
    ap.add_argument("--out", required=True, help="the PNG written")
    return ap.parse_args(argv)


def find_model(spec: str, seed: int, cache: Path) -> tuple[str, Path, int]:
    """(name, saved weights, U-Net width) of ``NAME=RESULTS[:MODEL]`` at ``seed``."""
    from demseis.errors import InputError

    name, sep, where = spec.partition("=")
    if not sep or not name:
        raise InputError(f"{spec!r}: expected NAME=RESULTS[:MODEL]")
    path, _, model = where.partition(":")
    if not Path(path).is_file():
        raise InputError(f"{spec!r}: no results file {path!r}")
    results = json.loads(Path(path).read_text())
    cells = [c for c in results.get("cells", []) if c["seed"] == seed
             and (not model or c["model"] == model)]
    models = sorted({c["model"] for c in cells})
    if len(models) != 1:
        raise InputError(f"{spec!r}: {path} holds seed {seed} of "
                         f"{', '.join(models) if models else 'no model'}"
                         + ("; name one as RESULTS:MODEL" if models else ""))
    configs = sorted({c["config"] for c in cells})
    if len(configs) > 1:
        raise InputError(f"{spec!r}: {path} holds seed {seed} of {models[0]} trained "
                         f"{len(configs)} ways ({', '.join(configs)}); draw from a results "
                         "file of one")
    fp = configs[0]
    saved = cache / "models" / f"{fp}-{seed}.pt"
    if not saved.is_file():
        raise InputError(f"{spec!r}: the weights {str(saved)!r} are not in --cache")
    return name, saved, int(results["configs"][fp]["base"])


def main(argv: list[str] | None = None) -> int:
    args = parse_args(argv)
    import torch

    from demseis.errors import InputError
    from demseis.learning.train import build_unet

    fb = runpy.run_path(str(BENCH), run_name="field_benchmark")
    cache = Path(args.cache).expanduser()
    found = [find_model(s, args.seed, cache) for s in args.model]
    data: dict = {}
    sections: list[tuple[str, np.ndarray, np.ndarray | None]] = [
        (f"{set_name}/{key}", *fb["cache_pair"](data, section, mask, True))
        for set_name, pairs in fb["field_sets"](args).items() for key, section, mask in pairs]
    if args.f3:
        sections.append(("F3", fb["cache_f3"](data, args.f3), None))
    if not sections:
        raise InputError("nothing to draw: give --field-dir, --field or --f3")
    panels = {}
    for name, saved, base in found:
        net = build_unet(base)
        net.load_state_dict(torch.load(saved, map_location="cpu", weights_only=True))
        net.eval()
        panels[name] = {s: fb["predict"](net, sec, 1.0) for s, sec, _ in sections}
    note = (" F3 Netherlands data courtesy of dGB Earth Sciences, CC BY-SA 3.0; the figure is "
            "CC BY-SA 3.0." if args.f3 else "")
    fb["draw"](Path(args.out), panels, sections, f"{args.title}, seed {args.seed}.{note}")
    print(json.dumps({"benchmark": "field_models_figure", "out": args.out, "seed": args.seed,
                      "models": {n: str(p) for n, p, _ in found}}))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
