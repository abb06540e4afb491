"""docs/figures/realism_quick.png and the table of docs/realism.md: a store beside F3.

Runs `demseis.evaluation.realism_report.realism_report` on a store and the F3 field section
(by default the project's field reference, ../shared/field/f3_inline.sgy beside the
checkout), draws `demseis.plotting.plot_realism` with the F3 licence
line under it, and prints the report's Markdown table (what docs/realism.md shows):

    demseis generate --preset quick --out /tmp/quick.zarr --workers 1
    PYTHONPATH=$PWD python scripts/realism_figure.py /tmp/quick.zarr
        [--field ../shared/field/f3_inline.sgy] [--out docs/figures/realism_quick.png]
        [--max-samples 256] [--seed 0]

The figure contains the F3 section: "F3 Netherlands data courtesy of dGB Earth Sciences,
CC BY-SA 3.0"; the figure is itself CC BY-SA 3.0.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from _field import ATTRIBUTION, FIELD, ROOT  # scripts/_field.py

from demseis.evaluation.realism_report import realism_report, report_markdown
from demseis.plotting import plot_realism


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("store", type=Path)
    ap.add_argument("--field", type=Path, default=FIELD)
    ap.add_argument("--out", type=Path, default=ROOT / "docs" / "figures" / "realism_quick.png")
    ap.add_argument("--max-samples", type=int, default=256)
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args()
    report = realism_report(args.store, args.field, max_samples=args.max_samples, seed=args.seed)
    plot_realism(report, args.out, credit=ATTRIBUTION)
    print(report_markdown(report))
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
