#!/bin/sh
# Fetch a second set of hand-picked field sections for benchmarks/field_benchmark.py into a cache
# outside the repository (never into the repository, the package or the tests: the data's
# licence is not stated).
#
# Great South Basin (offshore New Zealand) sections of Cunha et al. (2020), "Seismic fault
# detection in real data using transfer learning from a convolutional neural network
# pre-trained with synthetic seismic data", as stored in github.com/anyuzoey/
# CNNforFaultInterpretation (a GPL-3.0 repository), folder SFD-CNN-TL/gsbData: seismic
# gsb_<line>.npy (1, 76, W), 1000-1300 ms at 4 ms, with fault sticks interpreted in OpendTect
# and drawn one pixel wide (gsb_<line>_mask.npy). Six lines are written as
# seismic_<line>.npy / mask_<line>.npy (H, W); crl_2800 is left out, as its mask there is of
# another, undocumented origin. The commit fetched is written to SOURCE_COMMIT beside them.
#
#     sh benchmarks/fetch_field_gsb.sh [DEST]    (default ~/.cache/demseis-field/gsb-cunha2020)
#
# FIELD_REPO=URL_OR_PATH fetches from a mirror instead; PYTHON (default python3, with NumPy)
# converts the arrays. Then: python benchmarks/field_benchmark.py ... --field-dir DEST
set -eu
. "$(dirname "$0")/_fetch_common.sh"
fetch_start https://github.com/anyuzoey/CNNforFaultInterpretation.git SFD-CNN-TL/gsbData \
    "$HOME/.cache/demseis-field/gsb-cunha2020" "$@"
"${PYTHON:-python3}" - "$TMP/repo/SFD-CNN-TL/gsbData" "$DEST" <<'PY'
import sys
from pathlib import Path

import numpy as np

src, dest = Path(sys.argv[1]), Path(sys.argv[2])
for line in ("crl_2600", "crl_2700", "crl_2900", "crl_3000", "inl_1791", "inl_2011"):
    seismic = np.load(src / f"gsb_{line}.npy")
    mask = np.load(src / f"gsb_{line}_mask.npy")
    if seismic.shape != mask.shape or seismic.ndim != 3 or seismic.shape[0] != 1:
        sys.exit(f"gsb_{line}: seismic {seismic.shape} and mask {mask.shape}; expected two "
                 "(1, H, W) arrays")
    np.save(dest / f"seismic_{line}.npy", seismic[0].astype(np.float32))
    np.save(dest / f"mask_{line}.npy", (mask[0] > 0).astype(np.uint8))
PY
git -C "$TMP/repo" rev-parse HEAD > "$DEST/SOURCE_COMMIT"
ls "$DEST"
