#!/usr/bin/env bash
# Install the Debian packages MotionCore needs, if any are missing.
# Idempotent: does nothing (and needs no network) when everything is present.
set -euo pipefail

PKGS=(
  build-essential cmake ninja-build
  verilator yosys nextpnr-ice40 fpga-icestorm jq
  z3 cvc5
  libsystemc-dev libeigen3-dev
  libgtest-dev libgmock-dev
  libcli11-dev nlohmann-json3-dev libtomlplusplus-dev
  gnuplot-nox
  clang-format clang-tidy ccache
  clang libclang-rt-dev  # make fuzz: clang++ and the libFuzzer runtime
  linuxcnc-uspace
  bcnc
)

missing=()
for p in "${PKGS[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

# Node.js runs cncjs, the sender of the client tests (label client). A
# node already on PATH (>= 18, cncjs's minimum) is used as it is: Debian's npm
# would conflict with a nodejs from elsewhere.
if ! command -v node >/dev/null || ! command -v npm >/dev/null; then
  missing+=(nodejs npm)
fi

SUDO=""
if [ "$(id -u)" -ne 0 ]; then
  SUDO="sudo"
fi
if [ ${#missing[@]} -gt 0 ]; then
  echo "deps.sh: installing ${missing[*]}" >&2
  export DEBIAN_FRONTEND=noninteractive
  $SUDO apt-get update -qq
  $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi

# cncjs from npm, for tests/test_grbl_cncjs.js: into a cache outside the tree
# (tests/grbl.cmake looks there; MC_CNCJS_DIR moves it), once per version.
CNCJS_VERSION=1.11.5
CNCJS_DIR="${MC_CNCJS_DIR:-$HOME/.cache/motioncore/cncjs-$CNCJS_VERSION}"
if ! grep -qs "\"version\": \"$CNCJS_VERSION\"" "$CNCJS_DIR/node_modules/cncjs/package.json"; then
  echo "deps.sh: installing cncjs $CNCJS_VERSION from npm into $CNCJS_DIR" >&2
  mkdir -p "$CNCJS_DIR"
  npm install --prefix "$CNCJS_DIR" --no-audit --no-fund --loglevel=error "cncjs@$CNCJS_VERSION" >&2
fi
