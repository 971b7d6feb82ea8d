#!/usr/bin/env bash
# Runs the test suite on lavapipe with the Khronos validation layer on (any validation
# message fails a test), after installing what is missing. Extra arguments go to `cargo test`
# (`scripts/test.sh --statistical [CARGO ARGS] [-- HARNESS ARGS]` runs the statistical tier).
# This is the README's test command and CI's (.ci/run), kept within 12 minutes on the 2-core
# CI machine, build included.
#
# Two tiers (docs/DESIGN.md "Tests"). The long statistical tests, each a mean or an error of
# many renders against a reference (a minute or more of lavapipe each; together most of the
# first pass's 14 minutes when they were in it), carry `#[ignore = "statistical tier: ..."]`
# and run with `bash scripts/test.sh --statistical`. CI keeps what can find a change they
# would judge: tests/pixel_hashes.rs pins the bits of each of their configurations (method,
# strategy and settings, on their scenes or one lit the same way) at 24 x 16, so a change to
# their kernels fails CI until the hashes are recorded again, and
# scripts/record-pixel-hashes.sh records them only after the statistical tier has passed.
# What the pins cannot see is a fault that shows only at the tier's sizes and counts; the
# analytic tests (closed forms, furnaces, pdfs, tables), setting_maxima's means at every
# count's maximum and the cheaper statistical tests stay in CI.
#
# Without arguments, the GPU tests then run once more the way a discrete GPU runs them
# (docs/DESIGN.md "Staging" and "Subgroup widths"): IRAD_FORCE_STAGING=1 puts every buffer
# behind staging copies (device-local memory the host cannot map), and
# LP_NATIVE_VECTOR_WIDTH=128 makes lavapipe's subgroups 4 lanes wide instead of 8, so the
# staging path and the subgroup-width-dependent kernels (scans, env and luminaire tables, bir's
# resampling) run at both widths, pixel hashes included.
#
# That pass leaves out the cheaper statistical tests too (means of many renders against a
# closed form or the reference, ~70 s of the pass): lavapipe renders the same bits staged and
# at 4 lanes (every statistic they printed was the same to the last digit in both passes when
# this was measured), and what they could find there, a kernel that goes wrong staged or at
# 4 lanes, the pass's pixel hashes (their kernels: luminaire tables and estimators, the map
# sequence, the two-bounce clamp) and table tests (against f64 mirrors) find.
SECOND_PASS_SKIPS=(
  a_disk_luminaire_lights_the_floor_as_the_closed_form_says
  near_the_image_plane_the_filter_plane_estimator_takes_over
  dynamic_maps_change_every_frame
  the_compensated_two_bounce_clamp_keeps_the_mean
  roulette_over_lights_keeps_the_mean
)

# The statistical tier's test names: the first `fn` after each attribute. Each tests/NAME.rs is
# the module NAME of the one integration-test binary (tests/all.rs), so `--exact` matches
# NAME::fn.
statistical_tests() {
  awk '/#\[ignore = "statistical tier/ { want = 1; next }
       want && match($0, /fn [A-Za-z0-9_]+/) {
         module = FILENAME; sub(/^.*\//, "", module); sub(/\.rs$/, "", module)
         print module "::" substr($0, RSTART + 3, RLENGTH - 3); want = 0 }' tests/*.rs
}

# The second pass's tests: every test of these files (modules of tests/all.rs) but the skips.
SECOND_PASS_FILES=(prefix_sum bvh buffers reference ir bir bundles env lightfield tables
  pixel_hashes custom_method light_bvh)
second_pass_tests() {
  local files skips
  files=$(IFS='|'; echo "${SECOND_PASS_FILES[*]}")
  skips=$(IFS='|'; echo "${SECOND_PASS_SKIPS[*]}")
  cargo test --locked --test all -- --list --format terse 2>/dev/null \
    | sed -n 's/: test$//p' | grep -E "^($files)::" | grep -vE "::($skips)\$"
}

set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh --browser
# The browser tests (tests/browser.rs) fail rather than skip when chromium is missing.
export IRAD_REQUIRE_BROWSER=1
if [ "${1:-}" = "--statistical" ]; then
  shift
  mapfile -t names < <(statistical_tests)
  marked=$(grep -c '#\[ignore = "statistical tier' tests/*.rs | awk -F: '{ n += $2 } END { print n }')
  if [ "${#names[@]}" -eq 0 ] || [ "${#names[@]}" -ne "$marked" ]; then
    # With no names, --ignored would run every ignored test, the scene generators included.
    echo "scripts/test.sh: found ${#names[@]} statistical test names for $marked attributes" >&2
    exit 1
  fi
  # cargo's arguments, then the harness's (after a `--` of the caller's, if any).
  cargo_args=() harness_args=()
  while [ "$#" -gt 0 ] && [ "$1" != "--" ]; do cargo_args+=("$1"); shift; done
  [ "$#" -gt 0 ] && shift
  harness_args=("$@")
  echo "== the statistical tier: ${#names[@]} tests"
  exec cargo test --locked --test all "${cargo_args[@]}" -- "${harness_args[@]}" --ignored --exact "${names[@]}"
fi
cargo test --locked "$@"
if [ "$#" -eq 0 ]; then
  echo "== the GPU tests again, staged buffers and 4-lane subgroups"
  mapfile -t second < <(second_pass_tests)
  if [ "${#second[@]}" -eq 0 ]; then
    echo "scripts/test.sh: found no tests for the second pass" >&2
    exit 1
  fi
  IRAD_FORCE_STAGING=1 LP_NATIVE_VECTOR_WIDTH=128 cargo test --locked --test all \
    -- --exact "${second[@]}"
fi
