"""Labels stage speed: strain_history on ~11k elements x 6 snapshots, label_maps per snapshot.

Run: PYTHONPATH=$PWD NUMBA_NUM_THREADS=1 python benchmarks/labels_strain.py  (one JSON line)
"""

import json
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # demseis_dev: the checkout's

from demseis_dev.bench import labels_benchmark as run_benchmark

if __name__ == "__main__":
    print(json.dumps(run_benchmark()))
