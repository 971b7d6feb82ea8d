#!/usr/bin/env bash
# Installs the system packages irad needs when they are missing (idempotent; Debian):
# the Vulkan loader, lavapipe (Mesa's CPU Vulkan driver), glslang, SPIRV-Tools and the Khronos
# validation layer; with --browser also Chromium and its ChromeDriver, which the browser test of
# the HTML viewer drives (tests/browser.rs; scripts/test.sh asks for them). Needs root or sudo
# only when something is missing.
set -euo pipefail

missing=()
ldconfig -p 2>/dev/null | grep -q 'libvulkan\.so\.1' || missing+=(libvulkan1)
ls /usr/share/vulkan/icd.d/lvp_icd*.json >/dev/null 2>&1 || missing+=(mesa-vulkan-drivers)
command -v glslangValidator >/dev/null 2>&1 || missing+=(glslang-tools)
command -v spirv-val >/dev/null 2>&1 || missing+=(spirv-tools)
ls /usr/share/vulkan/explicit_layer.d/VkLayer_khronos_validation.json >/dev/null 2>&1 || missing+=(vulkan-validationlayers)
if [ "${1:-}" = "--browser" ]; then
  [ -x /usr/lib/chromium/chromium ] || command -v chromium >/dev/null 2>&1 || missing+=(chromium)
  command -v chromedriver >/dev/null 2>&1 || missing+=(chromium-driver)
fi

if ((${#missing[@]})); then
  echo "irad setup: installing ${missing[*]}" >&2
  if [ "$(id -u)" -eq 0 ]; then sudo=(); elif command -v sudo >/dev/null 2>&1; then sudo=(sudo); else
    echo "irad setup: missing ${missing[*]}; run as root or install them: apt-get install ${missing[*]}" >&2
    exit 1
  fi
  export DEBIAN_FRONTEND=noninteractive
  "${sudo[@]}" apt-get update -qq
  "${sudo[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi

if ! command -v cargo >/dev/null 2>&1; then
  echo "irad setup: cargo not found: install Rust (https://rustup.rs), then run this again" >&2
  exit 1
fi
