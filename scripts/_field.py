"""What the figure scripts share about the F3 field section (../shared/field/README.md)."""

from __future__ import annotations

from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
FIELD = ROOT.parent / "shared" / "field" / "f3_inline.sgy"
ATTRIBUTION = ("F3 Netherlands data courtesy of dGB Earth Sciences, CC BY-SA 3.0; "
               "this figure is CC BY-SA 3.0")
