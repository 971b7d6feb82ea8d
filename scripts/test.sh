#!/usr/bin/env bash
# Runs the whole test suite on lavapipe with the Khronos validation layer on (any validation
# message fails a test), after installing what is missing. Extra arguments go to `cargo test`.
#
# Without arguments, the GPU tests then run once more the way a discrete GPU runs them
# (docs/DESIGN.md "Staging" and "Subgroup widths"): IRAD_FORCE_STAGING=1 puts every buffer
# behind staging copies (device-local memory the host cannot map), and
# LP_NATIVE_VECTOR_WIDTH=128 makes lavapipe's subgroups 4 lanes wide instead of 8, so the
# staging path and the subgroup-width-dependent kernels (scans, env and luminaire tables, bir's
# resampling) run at both widths.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
cargo test --locked "$@"
if [ "$#" -eq 0 ]; then
  echo "== the GPU tests again, staged buffers and 4-lane subgroups"
  IRAD_FORCE_STAGING=1 LP_NATIVE_VECTOR_WIDTH=128 cargo test --locked \
    --test prefix_sum --test bvh --test buffers --test reference --test ir --test bir \
    --test bundles --test compensation --test env --test lightfield --test tables \
    --test pixel_hashes
fi
