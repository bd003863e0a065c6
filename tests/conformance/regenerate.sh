#!/bin/bash
# SPDX-License-Identifier: MIT
# Regenerates the conformance vectors from scratch: the source meshes, every encoder-made
# vector with its expected results, and the derived valid and invalid files. Only for a
# deliberate bitstream change (with the format version bump), or to add a vector.
#   bash tests/conformance/regenerate.sh [BUILD_DIR]   (default: build)
set -euo pipefail
cd "$(dirname "$0")/../.."
build=${1:-build}
cmake --build "$build" -j2 --target pmz-conformance pmz-encode >/dev/null
tool=$build/bin/pmz-conformance
dir=tests/conformance
rm -rf "$dir/meshes" "$dir/vectors" "$dir/derived"
"$tool" meshes "$dir/meshes"
mkdir -p "$dir/vectors"
grep -v '^#' "$dir/vectors.txt" | while read -r name mesh opts; do
  [ -n "$name" ] || continue
  # shellcheck disable=SC2086  # opts holds several options
  "$build/bin/pmz-encode" "$dir/meshes/$mesh" -o "$dir/vectors/$name.pmz" $opts >/dev/null
  "$tool" expect "$dir/vectors/$name.pmz" "valid: meshes/$mesh, pmz-encode ${opts:-(defaults)}"
done
"$tool" derive "$dir/vectors/sphere-q14.pmz" "$dir/derived"
python3 "$dir/derive_node_streams.py" "$dir/vectors/seamed-nodes.pmz" "$dir/derived" |
  while read -r name what; do
    "$tool" expect "$dir/derived/$name.pmz" "$what (derived from seamed-nodes.pmz)"
  done
rm -f "$dir"/derived/node-*.obj  # (a decoded level is kept for the valid vectors only)
ls "$dir/vectors" "$dir/derived" | grep -c '\.pmz$' | xargs echo "vectors:"
