#!/usr/bin/env bash
# Runs the whole test suite on lavapipe with the Khronos validation layer on (any validation
# message fails a test), after installing what is missing. Extra arguments go to `cargo test`.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
cargo test --locked "$@"
