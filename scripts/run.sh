#!/usr/bin/env bash
# The main job: installs what is missing, builds irad, lists the Vulkan devices and runs the
# GPU self-check. (Once the renderer lands, this renders the default scene.)
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
cargo build --release --locked --quiet
./target/release/irad info
./target/release/irad selfcheck
