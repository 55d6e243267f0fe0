#!/usr/bin/env bash
# Install the Debian packages MotionCore needs, if any are missing.
# Idempotent: does nothing (and needs no network) when everything is present.
set -euo pipefail

PKGS=(
  build-essential cmake ninja-build
  verilator yosys nextpnr-ice40 fpga-icestorm jq
  libsystemc-dev libeigen3-dev
  libgtest-dev libgmock-dev
  libcli11-dev nlohmann-json3-dev libtomlplusplus-dev
  gnuplot-nox
  clang-format clang-tidy ccache
  clang libclang-rt-dev  # make fuzz: clang++ and the libFuzzer runtime
  linuxcnc-uspace
)

missing=()
for p in "${PKGS[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  exit 0
fi

echo "deps.sh: installing ${missing[*]}" >&2
SUDO=""
if [ "$(id -u)" -ne 0 ]; then
  SUDO="sudo"
fi
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
