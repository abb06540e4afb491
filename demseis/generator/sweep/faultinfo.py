"""How the basement fault systems of a store are distributed (for ``demseis info``)."""

from __future__ import annotations

from collections import Counter
from pathlib import Path

from demseis.datasets import DoneParams, read_done_params, read_store_attrs
from demseis.generator.config.layout import param_codes

#: fault records ``fault<k>_*`` looked for (a store holds as many as its config allows)
_MAX_FAULTS = 64


def fault_distribution(path: str | Path, table: DoneParams | None = None) -> list[str]:
    """Lines counting the runs of a store by structure, by number of basement faults, and the
    faults by kind (one count per run: the samples with ``sample_in_run == 0`` of done
    runs). Empty if the store has no fault-system parameters (written before they existed).
    ``table``: the store's :func:`~demseis.datasets.read_done_params` (all parameters), if
    read already."""
    if table is None:  # done shards only (no cost per pending run); names it lacks are skipped
        table = read_done_params(path, ["structure", "n_basement_faults", "sample_in_run",
                                        *(f"fault{k}_kind" for k in range(_MAX_FAULTS))])
    params = table.values
    if not {"structure", "n_basement_faults", "sample_in_run"} <= set(params):
        return []
    codes = dict(read_store_attrs(path)).get("param_codes") or param_codes()  # the store's own
    # done shards only: every first sample is a finished run (n_basement_faults 0 is a run
    # without basement fault, structure "none")
    runs = params["sample_in_run"] == 0
    n_faults = params["n_basement_faults"]
    if not runs.any():
        return ["basement faults: no finished run"]
    structures = Counter(codes["structure"][int(c)] for c in params["structure"][runs])
    counts = Counter(int(c) for c in n_faults[runs])
    kinds: Counter[str] = Counter()
    k = 0
    while f"fault{k}_kind" in params:
        kind_codes = params[f"fault{k}_kind"][runs]
        kinds.update(codes["fault_kind"][int(c)] for c in kind_codes if c >= 0)
        k += 1

    def fmt(c: Counter) -> str:
        return ", ".join(f"{key}: {c[key]}" for key in sorted(c))

    return [f"basement faults over {int(runs.sum())} runs:",
            f"  structure   {fmt(structures)}",
            f"  faults/run  {fmt(counts)}",
            f"  fault kind  {fmt(kinds)} ({sum(kinds.values())} faults)"]


__all__ = ["fault_distribution"]
