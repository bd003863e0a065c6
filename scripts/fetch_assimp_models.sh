#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# Puts Debian's assimp-testmodels (textured OBJ/PLY/glTF samples and malformed files, used by the
# attribute tests) into ./corpus-assimp/ (gitignored; never committed). Tests skip without it.
#
# Usage: scripts/fetch_assimp_models.sh
set -euo pipefail
cd "$(dirname "$0")/.."
dest=corpus-assimp
if [ -d "$dest/glTF2" ] && [ -d "$dest/OBJ" ] && [ -d "$dest/PLY" ]; then
  echo "fetch_assimp_models: already in $dest/"
  exit 0
fi
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
(cd "$tmp" && apt-get download assimp-testmodels >/dev/null 2>&1) || {
  echo "fetch_assimp_models: 'apt-get download assimp-testmodels' failed (run apt-get update?)" >&2
  exit 1; }
dpkg-deb -x "$tmp"/assimp-testmodels_*.deb "$tmp/pkg"
mkdir -p "$dest"
for d in OBJ PLY glTF2 invalid; do
  rm -rf "${dest:?}/$d"
  cp -r "$tmp/pkg/usr/share/assimp/models/$d" "$dest/$d"
done
echo "fetch_assimp_models: $(find "$dest" -type f | wc -l) files in $dest/"
