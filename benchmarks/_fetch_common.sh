# Sourced by the fetch_field*.sh scripts. fetch_start URL FOLDER DEFAULT_DEST [DEST]: DEST (the
# given one or DEFAULT_DEST, created) and TMP (removed on exit) are set, and the repository at
# URL, or at $FIELD_REPO (a mirror), is cloned into $TMP/repo at its newest commit with only
# FOLDER checked out (blobs fetched on demand).
fetch_start() {
    DEST=${4:-"$3"}
    TMP=$(mktemp -d)
    trap 'rm -rf "$TMP"' EXIT
    git clone --quiet --depth 1 --filter=blob:none --sparse "${FIELD_REPO:-$1}" "$TMP/repo"
    git -C "$TMP/repo" sparse-checkout set "$2"
    mkdir -p "$DEST"
}
