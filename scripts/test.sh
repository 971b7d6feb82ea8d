#!/usr/bin/env bash
# Runs the test suite on lavapipe with the Khronos validation layer on (any validation
# message fails a test), after installing what is missing. Extra arguments go to `cargo test`.
# This is the README's test command and CI's (.ci/run), kept within 12 minutes on the 2-core
# CI machine, build included.
#
# Two tiers (docs/DESIGN.md "Tests"). The long statistical tests, each a mean or an error of
# many renders against a reference (minutes of lavapipe each; about 9 of the 14 minutes the
# first pass took when they were all in it), carry `#[ignore = "statistical tier: ..."]` and
# run with `bash scripts/test.sh --statistical`. CI keeps what can find a change they would
# judge: tests/pixel_hashes.rs pins the bits of every configuration they render (strategies,
# clamps, absorption, interleaving, alpha, shared samples, bundle directions, glossy
# suppression, the map sequence across restir's temporal reuse) at 24 x 16, so a change to any
# of their images fails CI until the hashes are recorded again, and
# scripts/record-pixel-hashes.sh records them only after the statistical tier has passed.
# The analytic tests (closed forms, furnaces, pdfs, tables), setting_maxima's means and the
# cheaper statistical tests stay in CI.
#
# Without arguments, the GPU tests then run once more the way a discrete GPU runs them
# (docs/DESIGN.md "Staging" and "Subgroup widths"): IRAD_FORCE_STAGING=1 puts every buffer
# behind staging copies (device-local memory the host cannot map), and
# LP_NATIVE_VECTOR_WIDTH=128 makes lavapipe's subgroups 4 lanes wide instead of 8, so the
# staging path and the subgroup-width-dependent kernels (scans, env and luminaire tables, bir's
# resampling) run at both widths, pixel hashes included.

# The statistical tier's test names, from their attributes.
statistical_tests() {
  grep -h -A1 '#\[ignore = "statistical tier' tests/*.rs | sed -n 's/^fn \([a-z0-9_]*\).*/\1/p'
}

set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
if [ "${1:-}" = "--statistical" ]; then
  shift
  mapfile -t names < <(statistical_tests)
  echo "== the statistical tier: ${#names[@]} tests"
  exec cargo test --locked "$@" -- --ignored --exact "${names[@]}"
fi
cargo test --locked "$@"
if [ "$#" -eq 0 ]; then
  echo "== the GPU tests again, staged buffers and 4-lane subgroups"
  IRAD_FORCE_STAGING=1 LP_NATIVE_VECTOR_WIDTH=128 cargo test --locked \
    --test prefix_sum --test bvh --test buffers --test reference --test ir --test bir \
    --test bundles --test env --test lightfield --test tables --test pixel_hashes \
    --test custom_method --test light_bvh
fi
