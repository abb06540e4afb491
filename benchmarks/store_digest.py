"""Digest of a store's bytes, to compare stores across machines (one JSON line).

SHA-256 of every file of the store (path and content, in sorted order; the writer lock and
other hidden files left out), the whole store's and each top-level array's, with the library
versions and the CPU model: the same config and seed give the same digest on any x86-64 CPU
with the same library versions (docs/guide.md, "Across machines").

    python benchmarks/store_digest.py STORE
"""

from __future__ import annotations

import hashlib
import json
import platform
import sys
from pathlib import Path


def digest(root: Path) -> dict:
    """``{"sha256": whole store, "arrays": {top-level name: sha256}, "files": count}``."""
    whole = hashlib.sha256()
    parts: dict[str, hashlib._Hash] = {}
    n = 0
    for p in sorted(root.rglob("*")):
        rel = p.relative_to(root)
        if not p.is_file() or any(part.startswith(".") for part in rel.parts):
            continue
        data = p.read_bytes()
        for h in (whole, parts.setdefault(rel.parts[0] if len(rel.parts) > 1 else "", hashlib.sha256())):
            h.update(str(rel).encode())
            h.update(data)
        n += 1
    return {"sha256": whole.hexdigest(), "files": n,
            "arrays": {k or "(root)": v.hexdigest()[:16] for k, v in sorted(parts.items())}}


def _cpu_model() -> str:
    try:
        for row in Path("/proc/cpuinfo").read_text().splitlines():
            if row.startswith("model name"):
                return row.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or platform.machine()


def main(argv: list[str] | None = None) -> int:
    args = sys.argv[1:] if argv is None else argv
    if len(args) != 1 or not Path(args[0]).is_dir():
        raise SystemExit("usage: python benchmarks/store_digest.py STORE (a store directory)")
    import numba
    import numpy
    import scipy
    import zarr

    out = {"benchmark": "store_digest", "store": args[0], **digest(Path(args[0])),
           "cpu": _cpu_model(), "python": platform.python_version(), "numpy": numpy.__version__,
           "numba": numba.__version__, "scipy": scipy.__version__, "zarr": zarr.__version__}
    print(json.dumps(out))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
