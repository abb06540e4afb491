"""How the basement fault systems of a store are distributed (for ``demseis info``)."""

from __future__ import annotations

from collections import Counter
from pathlib import Path

import zarr

from demseis.generator.layout import param_codes


def fault_distribution(path: str | Path) -> list[str]:
    """Lines counting the runs of a store by structure, by number of basement faults, and the
    faults by kind (one count per DEM run: the samples with ``sample_in_run == 0`` of done
    runs). Empty if the store has no fault-system parameters (written before they existed)."""
    root = zarr.open_group(str(path), mode="r")
    params = root["params"]
    codes = dict(root.attrs).get("param_codes") or param_codes()  # the store's own codes
    names = set(params.array_keys())
    if not {"structure", "n_basement_faults", "sample_in_run"} <= names:
        return []
    first = params["sample_in_run"][:] == 0
    n_faults = params["n_basement_faults"][:]
    runs = first & (n_faults > 0)  # a run not done yet holds zeros
    if not runs.any():
        return ["basement faults: no finished run"]
    structures = Counter(codes["structure"][int(c)] for c in params["structure"][:][runs])
    counts = Counter(int(c) for c in n_faults[runs])
    kinds: Counter[str] = Counter()
    k = 0
    while f"fault{k}_kind" in names:
        kind_codes = params[f"fault{k}_kind"][:][runs]
        kinds.update(codes["fault_kind"][int(c)] for c in kind_codes if c >= 0)
        k += 1

    def fmt(c: Counter) -> str:
        return ", ".join(f"{key}: {c[key]}" for key in sorted(c))

    return [f"basement faults over {int(runs.sum())} runs:",
            f"  structure   {fmt(structures)}",
            f"  faults/run  {fmt(counts)}",
            f"  fault kind  {fmt(kinds)} ({sum(kinds.values())} faults)"]


__all__ = ["fault_distribution"]
