#!/usr/bin/env bash
# Records tests/data/pixel_hashes.txt anew, for a change that means to alter images (say which
# in its commit), after the statistical tier has passed on the change: the hashes stand in
# CI for the statistical tests (scripts/test.sh), so they are only recorded for images those
# tests have judged. Recorded on lavapipe, whatever GPU the machine has.
set -euo pipefail
cd "$(dirname "$0")/.."
IRAD_DEVICE=llvmpipe bash scripts/test.sh --statistical
IRAD_DEVICE=llvmpipe IRAD_RECORD_PIXEL_HASHES=1 cargo test --locked --test all -- pixel_hashes::
git --no-pager diff --stat -- tests/data/pixel_hashes.txt
