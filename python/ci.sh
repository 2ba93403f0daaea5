#!/usr/bin/env bash
# The Python package's CI: a fresh virtual environment, `pip install "./python[dask]" pytest
# numpy` (which builds the Rust code through maturin with the workspace's test settings, and
# installs Dask for contour_track.cluster and its tests), then pytest with its summary.
#
# The determinism tests compare the binding's boxes with `track run`'s: they use $TRACK_BIN, or
# the newest executable target/*/track of the repository (built here when there is none;
# `cargo doc` leaves a folder target/doc/track, which does not count).
set -euo pipefail
cd "$(dirname "$0")/.."
repo=$(pwd)
python=${PYTHON:-python3}
venv=$(mktemp -d "${TMPDIR:-/tmp}/contour-track-venv.XXXXXX")
trap 'rm -rf "$venv"' EXIT
if ! "$python" -m venv "$venv" 2>/dev/null; then
    # Debian's python3 lacks venv until python3-venv is installed.
    apt-get update && apt-get install -y --no-install-recommends python3-venv
    "$python" -m venv "$venv"
fi
has_track_bin() {
    local f
    for f in target/*/track; do
        [ -f "$f" ] && [ -x "$f" ] && return 0
    done
    return 1
}
if [ -z "${TRACK_BIN:-}" ] && ! has_track_bin; then
    cargo build -p track-app --locked
fi
export CONTOUR_TRACK_REQUIRE_TRACK_BIN=1
start=$(date +%s)
# The tests check behaviour, not speed: the extension is built into the workspace's target folder
# with the dev profile raised to the test profile's settings (optimised, with debug assertions;
# `cargo rustc --profile test`, which maturin runs, would build a test harness instead), so
# that every crate the workspace's tests compiled is reused (the Python package is a workspace
# member; python/Cargo.toml lines up the features of the shared dependencies) and only pyo3,
# numpy and the extension are compiled here. The numbers are the release build's (no fast-math
# anywhere; the determinism tests compare its boxes with `track`'s). `pip install ./python` for
# users builds the release profile.
export MATURIN_PEP517_ARGS="--profile dev" CARGO_PROFILE_DEV_OPT_LEVEL=3 \
    CARGO_PROFILE_DEV_DEBUG=line-tables-only
"$venv/bin/python" -m pip install --quiet --upgrade pip
"$venv/bin/python" -m pip install --quiet "$repo/python[dask]" pytest numpy
echo "python/ci.sh: pip install took $(( $(date +%s) - start )) s"
cd "$repo/python"
# The pytest script, not `python -m pytest`: the latter puts python/ on sys.path, where the
# contour_track source folder (without its compiled extension) would shadow the installed package.
"$venv/bin/pytest" -q -p no:cacheprovider tests
