#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# Installs gltfpack (npm package gltfpack: meshoptimizer's glTF simplifier as WebAssembly) into
# BUILD_DIR/gltfpack for the textured benchmark (tests/bench/textured.py), which compares
# pmz-simplify with `gltfpack -si RATIO` at equal face counts.
# Usage: scripts/install_gltfpack.sh [BUILD_DIR]   (default build)
set -euo pipefail
cd "$(dirname "$0")/.."
dir=${1:-build}/gltfpack
if [ -f "$dir/node_modules/gltfpack/package.json" ]; then exit 0; fi
if ! command -v npm >/dev/null || ! command -v node >/dev/null; then
  echo "install_gltfpack: npm/node missing (apt-get install npm)" >&2
  exit 1
fi
mkdir -p "$dir"
npm install --prefix "$dir" --no-audit --no-fund --silent gltfpack@1.3.0 >/dev/null
echo "install_gltfpack: $(node -e "console.log(require('$PWD/$dir/node_modules/gltfpack/package.json').version)") in $dir"
