"""DEM stepping kernel of this checkout against other checkouts, interleaved in one process.

The arguments of one ``run_steps`` call of a real run are captured (``--preset``, ``--config``,
``--run``, the ``--call``-th call: early calls settle the pack, later ones fault it), then each
checkout's ``demseis/dem/_kernels.py`` is loaded by path and runs ``--steps`` steps from copies
of that state, round after round (A B C A B C ...), so a shared machine's load falls on all
of them alike. Reports CPU-second medians and minima per checkout, each checkout's speed
relative to this one (> 1: faster than this one), and whether every checkout ended in the same
bits as this one. A checkout from before the per-element contact materials (scalar
``kn, ks, mu, c0, r0`` arguments, e.g. 1d22cda) runs uniform mechanics only.

Numba's cache is redirected to a scratch folder (the modules loaded by path would otherwise
write cache entries into the checkouts that the packages could not load).

    python benchmarks/dem_kernel_ab.py --other /path/to/checkout [--other ...]
        [--preset quick] [--config FILE.toml] [--run 1] [--call 30] [--steps 1000]
        [--rounds 40]

Prints ONE JSON line.
"""

from __future__ import annotations

import argparse
import importlib.util
import inspect
import json
import os
import shutil
import statistics
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


class _Captured(Exception):
    pass


def capture(preset: str, config: str | None, run: int, call: int) -> list:
    """Copies of the arguments of the ``call``-th ``run_steps`` call of run ``run``."""
    import numpy as np

    import demseis.dem._kernels as K
    from demseis.generator.config.sampling import plan_run
    from demseis.generator.config.settings import load_config
    from demseis.generator.engines import get_engine

    cfg = load_config(config, preset=preset)
    orig, seen, state = K.run_steps, [0], []

    def spy(*args):
        seen[0] += 1
        if seen[0] == call:
            state.extend(a.copy() if isinstance(a, np.ndarray) else a for a in args)
            raise _Captured
        return orig(*args)

    K.run_steps = spy
    try:
        get_engine("dem").simulate(cfg, plan_run(cfg, run))
    except _Captured:
        return state
    finally:
        K.run_steps = orig
    raise SystemExit(f"run {run} made only {seen[0]} run_steps calls; lower --call")


def load_kernels(name: str, checkout: Path):
    path = checkout / "demseis" / "dem" / "_kernels.py"
    spec = importlib.util.spec_from_file_location(name, path)
    mod = importlib.util.module_from_spec(spec)
    sys.modules[name] = mod  # Numba's cache pickles the module name
    spec.loader.exec_module(mod)
    return mod


def arguments_for(mod, state: list) -> list | None:
    """Fresh copies of ``state`` in the argument layout of ``mod.run_steps`` (None: it cannot
    run this state)."""
    import numpy as np

    args = [a.copy() if isinstance(a, np.ndarray) else a for a in state]
    names = list(inspect.signature(mod.run_steps.py_func).parameters)
    if "cmat" in names:
        return args
    # before per-element materials: (..., gravity, kn, ks, mu, c0, r0, wall_kn, wall_mu, ...)
    cmat, ks_ratio, c0_heal, wall_kn, _wall_ks, wall_mu = args[10:16]
    if cmat.shape[0] != 1 or c0_heal != 1.0:
        return None
    kn, mu, c0, r0 = (float(v) for v in cmat[0])
    return args[:10] + [kn, ks_ratio * kn, mu, c0, r0, wall_kn, wall_mu] + args[16:]


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--other", action="append", default=[], help="another checkout's root")
    ap.add_argument("--preset", default="quick")
    ap.add_argument("--config", default=None, help="TOML layered on the preset")
    ap.add_argument("--run", type=int, default=1)
    ap.add_argument("--call", type=int, default=30)
    ap.add_argument("--steps", type=int, default=1000)
    ap.add_argument("--rounds", type=int, default=40)
    a = ap.parse_args(argv)
    if "NUMBA_CACHE_DIR" not in os.environ:  # must be set before Numba is imported
        os.environ["NUMBA_CACHE_DIR"] = tempfile.mkdtemp(prefix="demseis-kernel-ab-")
        os.environ["_DEMSEIS_AB_SCRATCH"] = os.environ["NUMBA_CACHE_DIR"]
        os.execv(sys.executable, [sys.executable, *sys.argv])
    try:
        return _measure(a)
    finally:
        scratch = os.environ.get("_DEMSEIS_AB_SCRATCH")
        if scratch and scratch == os.environ["NUMBA_CACHE_DIR"]:
            shutil.rmtree(scratch, ignore_errors=True)


def _measure(a: argparse.Namespace) -> int:
    sys.path.insert(0, str(ROOT))
    state = capture(a.preset, a.config, a.run, a.call)
    checkouts = {"this": ROOT, **{f"other{i}": Path(p).resolve() for i, p in enumerate(a.other)}}
    mods = {}
    for name, root in checkouts.items():
        mod = load_kernels(f"_ab_kernels_{name}", root)
        if arguments_for(mod, state) is not None:
            mods[name] = mod
    for mod in mods.values():  # compile (scratch cache), outside the timing
        args = arguments_for(mod, state)
        args[0] = 10
        mod.run_steps(*args)
    cpu = {n: [] for n in mods}
    final = {}
    for _ in range(a.rounds):
        for name, mod in mods.items():
            args = arguments_for(mod, state)
            args[0] = a.steps
            c0 = time.process_time()
            status = mod.run_steps(*args)
            cpu[name].append(time.process_time() - c0)
            final[name] = (int(status[0]), int(status[1]), args[2].tobytes(), args[3].tobytes())
    med = {n: statistics.median(v) for n, v in cpu.items()}
    low = {n: min(v) for n, v in cpu.items()}
    out = {
        "benchmark": "dem_kernel_ab", "preset": a.preset, "config": a.config, "run": a.run,
        "call": a.call, "n_elements": int(state[2].shape[0]), "layered": state[10].shape[0] > 1,
        "steps": a.steps, "rounds": a.rounds,
        "checkouts": {n: str(p) for n, p in checkouts.items()},
        "skipped": sorted(set(checkouts) - set(mods)),
        "cpu_s_median": med, "cpu_s_min": low,
        "speed_vs_this_median": {n: med["this"] / v for n, v in med.items()},
        "speed_vs_this_min": {n: low["this"] / v for n, v in low.items()},
        "same_bits_as_this": {n: final[n] == final["this"] for n in final},
        "load_avg_1min": os.getloadavg()[0],
    }
    print(json.dumps(out))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
