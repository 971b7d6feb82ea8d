#!/usr/bin/env bash
# The main job: installs what is missing, builds irad, checks the GPU against the CPU, and
# renders the default scene (the embedded Cornell box) with the reference path tracer into
# out/cornell-box.{exr,png,json}. Extra arguments go to `irad render`
# (e.g. `scripts/run.sh scenes/spot-light/scene.toml --spp 256`).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
cargo build --release --locked --quiet
./target/release/irad selfcheck
./target/release/irad render "$@"
