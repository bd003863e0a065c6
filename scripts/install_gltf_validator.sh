#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# Installs the Khronos glTF validator (npm package gltf-validator) into BUILD_DIR/gltf-validator
# for the test that validates the .glb files pmz writes (GltfOutput.KhronosValidatorAccepts).
# Usage: scripts/install_gltf_validator.sh [BUILD_DIR]   (default build)
set -euo pipefail
cd "$(dirname "$0")/.."
dir=${1:-build}/gltf-validator
if [ -f "$dir/node_modules/gltf-validator/package.json" ]; then exit 0; fi
if ! command -v npm >/dev/null || ! command -v node >/dev/null; then
  echo "install_gltf_validator: npm/node missing (apt-get install npm)" >&2
  exit 1
fi
mkdir -p "$dir"
npm install --prefix "$dir" --no-audit --no-fund --silent gltf-validator >/dev/null
echo "install_gltf_validator: $(node -e "console.log(require('$PWD/$dir/node_modules/gltf-validator').version())") in $dir"
