"""Speed and memory of `demseis predict` on a 3-D SEG-Y cube; one JSON line per cube size.

Each cube (inlines x crosslines x samples, random amplitudes, IEEE float, inline-sorted) is
written to a temporary folder, then predicted in a fresh process by
``demseis.learning.model.predict_file`` with a U-Net of ``--base`` channels (untrained: speed
and memory do not depend on the weights), along every inline and every crossline. Reported:
the median wall seconds over ``--repeats`` runs, seconds per million samples, and the child
process's peak resident memory (``ru_maxrss``) beside the cube's size in memory, so that
whether memory grows with the cube can be read off the lines.

Usage: ``python benchmarks/predict_cube.py [--sizes 16x24x256,32x48x256] [--base 16]
[--repeats 3] [--device cpu]``.
"""

from __future__ import annotations

import argparse
import json
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

_CHILD = """
import json, resource, sys, time
import numpy as np, torch
from demseis.learning.model import predict_file
from demseis.learning.train import build_unet
torch.manual_seed(0)
net = build_unet({base}).to({device!r}).eval()
t0 = time.perf_counter()
predict_file(net, {inp!r}, {out!r}, overwrite=True)
sec = time.perf_counter() - t0
print(json.dumps({{"seconds": sec,
                   "peak_rss_mib": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024}}))
"""


def write_cube(path: Path, n_il: int, n_xl: int, n_s: int) -> None:
    """A random inline-sorted IEEE-float cube with inline/crossline numbers in its headers."""
    import numpy as np
    import segyio

    spec = segyio.spec()
    spec.ilines, spec.xlines = list(range(1, n_il + 1)), list(range(1, n_xl + 1))
    spec.samples = list(range(0, 4 * n_s, 4))
    spec.format, spec.sorting = 5, segyio.TraceSortingFormat.INLINE_SORTING
    rng = np.random.default_rng(0)
    with segyio.create(str(path), spec) as f:
        k = 0
        for il in spec.ilines:
            for xl in spec.xlines:
                f.header[k] = {segyio.su.iline: il, segyio.su.xline: xl}
                k += 1
        for il in spec.ilines:
            f.iline[il] = rng.normal(size=(n_xl, n_s)).astype(np.float32)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", default="16x24x256,32x48x256",
                    help="cubes as INLINESxCROSSLINESxSAMPLES, comma-separated")
    ap.add_argument("--base", type=int, default=16, help="U-Net base channels (demseis train's)")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--device", default="cpu")
    args = ap.parse_args(argv)
    for size in args.sizes.split(","):
        n_il, n_xl, n_s = (int(v) for v in size.lower().split("x"))
        with tempfile.TemporaryDirectory() as d:
            inp, out = Path(d) / "cube.sgy", Path(d) / "prob.sgy"
            write_cube(inp, n_il, n_xl, n_s)
            runs = []
            for _ in range(args.repeats):
                code = _CHILD.format(base=args.base, device=args.device, inp=str(inp),
                                     out=str(out))
                res = subprocess.run([sys.executable, "-c", code], check=True,
                                     capture_output=True, text=True)
                runs.append(json.loads(res.stdout.strip().splitlines()[-1]))
        n = n_il * n_xl * n_s
        secs = statistics.median(r["seconds"] for r in runs)
        print(json.dumps({
            "benchmark": "predict_cube", "cube": [n_il, n_xl, n_s], "samples": n,
            "cube_mib": round(4 * n / 2**20, 2), "base": args.base, "device": args.device,
            "repeats": args.repeats, "seconds_median": round(secs, 3),
            "seconds_per_million_samples": round(secs / (n / 1e6), 2),
            "peak_rss_mib_median": round(statistics.median(r["peak_rss_mib"] for r in runs), 1),
        }), flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
