#!/usr/bin/env bash
# One command for a machine with a real GPU: `irad info`, `irad selfcheck`, the
# test suite on that device, then `irad bench rays`, `bench scan`, `bench env` and
# `bench lightfield` at 1024x768 and the standard suite at 1024 wide, everything written under
# out/gpu-check/<device>/ (one log per step, the benches' own outputs beside them).
#
#   scripts/gpu-check.sh                 # the device irad picks (the first discrete GPU)
#   scripts/gpu-check.sh --device 1      # or an index or part of a name, as `irad info` lists
#   IRAD_DEVICE=nvidia scripts/gpu-check.sh
#   GPU_CHECK_SKIP=suite,tests scripts/gpu-check.sh   # leave steps out (info selfcheck tests
#                                                     # rays scan env lightfield suite)
#
# Tests and CI never depend on a GPU; this script is how a GPU's figures are made. A step that
# fails is reported and the next one runs; the exit status is 1 when any failed.
set -uo pipefail
cd "$(dirname "$0")/.."

if [ "${1:-}" = "--device" ] && [ -n "${2:-}" ]; then
  export IRAD_DEVICE="$2"
elif [ -n "${1:-}" ]; then
  echo "usage: scripts/gpu-check.sh [--device INDEX|NAME]" >&2
  exit 2
fi
# irad and the tests both read IRAD_DEVICE (as --device).

# Packages: installed when missing and reachable; an offline machine goes on with what it has.
bash scripts/setup.sh || echo "gpu-check: setup could not install everything; going on" >&2
cargo build --release --locked --quiet || exit 1
irad=./target/release/irad

# The device's name, as irad would pick it, names the output folder.
name=$("$irad" info 2>/dev/null | sed -n 's/^\* [0-9]*: //p' | sed 's/ ([A-Za-z -]*, Vulkan [0-9].*//' | head -1)
slug=$(printf '%s' "${name:-unknown-device}" | tr -c 'A-Za-z0-9._-' '-' | sed 's/--*/-/g; s/-$//')
out="out/gpu-check/$slug"
mkdir -p "$out"
echo "gpu-check: device '${name:-?}', output in $out"

failed=()
step() {  # step NAME COMMAND...: runs it, its output into $out/NAME.log
  local step_name=$1
  shift
  case ",${GPU_CHECK_SKIP:-}," in *",$step_name,"*) echo "== $step_name: skipped"; return ;; esac
  echo "== $step_name: $*"
  local start=$SECONDS
  if "$@" >"$out/$step_name.log" 2>&1; then
    echo "   ok in $((SECONDS - start)) s"
  else
    echo "   FAILED in $((SECONDS - start)) s (see $out/$step_name.log)"
    failed+=("$step_name")
  fi
  tail -n 5 "$out/$step_name.log" | sed 's/^/   | /'
}

step info "$irad" info
step selfcheck "$irad" selfcheck
# The tests pick IRAD_DEVICE (tests/common/mod.rs), with the validation layer on when installed.
step tests cargo test --release --locked
step rays "$irad" bench rays
step scan "$irad" bench scan
step env "$irad" bench env --resolution 1024x768
step lightfield "$irad" bench lightfield --resolution 1024x768
step suite "$irad" bench suite scenes/suites/standard.toml \
  -o "$out/standard" --cache "$out/references"

if ((${#failed[@]})); then
  echo "gpu-check: failed steps: ${failed[*]} (logs in $out)"
  exit 1
fi
echo "gpu-check: every step passed; logs and results in $out"
