#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# Installs the Debian 12 packages pmz needs (only those missing), then configures and builds.
# Usage: scripts/setup.sh [BUILD_DIR] [extra cmake args...]
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:-build}
shift || true

packages=(build-essential cmake ninja-build pkg-config git
  libopenmesh-dev libcli11-dev googletest libgtest-dev
  libglfw3-dev libepoxy-dev libimgui-dev libstb-dev libcurl4-openssl-dev
  xvfb xauth libgl1-mesa-dri python3 parallel nginx time
  libmeshoptimizer-dev draco libopenmesh-apps python3-matplotlib
  clang-14 libclang-rt-14-dev clang-format ccache
  emscripten chromium libtinygltf-dev nlohmann-json3-dev)
# Debian's npm depends on Debian's nodejs and conflicts with a node installed another way
# (this kind of machine ships node 20 with its own npm): install them only when npm is absent.
command -v npm >/dev/null || packages+=(nodejs npm)
bash scripts/install_packages.sh setup "${packages[@]}"

# The project's git hooks (scripts/git-hooks: the commit subject's length), in a git work tree.
if git rev-parse --is-inside-work-tree >/dev/null 2>&1; then
  git config core.hooksPath scripts/git-hooks
fi

cmake -S . -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release "$@" >/dev/null
cmake --build "$build" -j "$(nproc)"
