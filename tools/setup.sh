#!/usr/bin/env bash
# Installs what rangesynth needs on Debian, idempotently: the Vulkan loader, Mesa's lavapipe
# (software Vulkan), the Khronos validation layers and shaderc's static libraries (which
# build.rs links instead of building shaderc from source). With --python, also what building
# and testing the Python package needs (python3 with venv and pip) where python3 lacks it. Needs
# root or sudo only when something is missing.
set -euo pipefail
packages=(mesa-vulkan-drivers libvulkan1 vulkan-validationlayers vulkan-tools libshaderc-dev)
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ "${1:-}" = "--python" ] && ! python3 -c 'import venv, ensurepip' 2>/dev/null; then
  missing+=(python3 python3-venv python3-pip)
fi
if ((${#missing[@]})); then
  sudo=""
  [ "$(id -u)" -eq 0 ] || sudo=sudo
  echo "installing ${missing[*]}" >&2
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi
if ! command -v cargo >/dev/null; then
  echo "rangesynth needs a Rust toolchain (cargo 1.85 or newer, e.g. from rustup)" >&2
  exit 1
fi
