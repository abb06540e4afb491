#!/bin/sh
# Fetch the hand-picked field sections that benchmarks/field_benchmark.py scores against into a
# cache outside the repository (never into the repository, the package or the tests: the data's
# licence is unclear).
#
# tutorial-03 of github.com/thilowrona/seismic_deep_learning (an AGPL repository; the licence of
# its data is not stated): five inlines as display images (seismic_inline_<n>.png) with faults
# drawn by hand (mask_inline_<n>.png). The commit fetched is written to SOURCE_COMMIT beside them.
#
#     sh benchmarks/fetch_field.sh [DEST]    (default ~/.cache/demseis-field/wrona-tutorial-03)
#
# FIELD_REPO=URL_OR_PATH fetches from a mirror instead. Then: python benchmarks/field_benchmark.py ... --field-dir DEST
set -eu
. "$(dirname "$0")/_fetch_common.sh"
fetch_start https://github.com/thilowrona/seismic_deep_learning.git tutorial-03 \
    "$HOME/.cache/demseis-field/wrona-tutorial-03" "$@"
cp "$TMP"/repo/tutorial-03/seismic_inline_*.png "$TMP"/repo/tutorial-03/mask_inline_*.png "$DEST"/
git -C "$TMP/repo" rev-parse HEAD > "$DEST/SOURCE_COMMIT"
ls "$DEST"
