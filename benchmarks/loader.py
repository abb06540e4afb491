"""DataLoader throughput of demseis' FaultSegDataset vs a NumPy memmap of the same data.

Prints one JSON line: median samples/s over ``--repeats`` epochs of random 256x256 crops
(seismic input, fault target) at 0 and 2 DataLoader workers, for the Zarr store read through
FaultSegDataset + ShardAwareSampler and for raw .npy memmaps of the same arrays (the limit),
measured side by side in one run. Same as ``python -m demseis_dev.bench loader``.

    PYTHONPATH=$PWD python benchmarks/loader.py [--shards 24 --samples-per-shard 32 ...]
"""

import sys

from demseis.cli import main

if __name__ == "__main__":
    raise SystemExit(main(["bench", "loader", *sys.argv[1:]]))
