#!/usr/bin/env bash
# Builds the Python wheel with maturin into a fresh venv, installs it and runs the pytest suite
# (.ci/run calls this). Packages come from the registry: maturin, pytest, numpy, scipy, and the
# peers the tests compare with, hmmlearn and py-motmetrics.
set -euo pipefail
cd "$(dirname "$0")/.."
cargo fmt --check --manifest-path python/Cargo.toml
cargo clippy --release --all-targets --manifest-path python/Cargo.toml -- -D warnings
venv="${TT_VENV:-target/python-venv}"
python3 -m venv "$venv"
"$venv/bin/pip" install --quiet --upgrade pip
"$venv/bin/pip" install --quiet maturin pytest numpy scipy hmmlearn motmetrics
rm -rf target/wheels
"$venv/bin/maturin" build --release --quiet -m python/Cargo.toml -o target/wheels
"$venv/bin/pip" install --quiet --force-reinstall --no-deps target/wheels/tracking_toolkit-*.whl
# Run from outside the source folder so the installed package is the one imported.
cd python/tests
"../../$venv/bin/python" -m pytest -q -p no:cacheprovider .
