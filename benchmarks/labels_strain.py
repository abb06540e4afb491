"""Labels stage speed: strain_history on ~11k elements x 6 snapshots, label_maps per snapshot.

Run: PYTHONPATH=$PWD NUMBA_NUM_THREADS=1 python benchmarks/labels_strain.py  (one JSON line)
"""

import json

from demseis.diagnostics.bench import labels_benchmark as run_benchmark

if __name__ == "__main__":
    print(json.dumps(run_benchmark()))
