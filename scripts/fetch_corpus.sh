#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# Builds the benchmark corpus in ./corpus/ (gitignored; meshes are never committed) from the
# mesh collection of Debian's libcgal-demo package, plus one ~1M-face mesh.
#
# Usage: scripts/fetch_corpus.sh [BUILD_DIR]   (BUILD_DIR holds bench/bench-subdivide; default build)
#
# The set (14 meshes, closed and open, of different character):
#   CAD, sharp creases:   fandisk (12,946 faces, closed), blade (16,222, open: 240 border edges),
#                         mech-holes-shark (10,192, open, holes), turbine (18,460, closed, genus 11),
#                         cheese (17,786, closed, genus 133)
#   Scans:                bunny00 (75,408, closed), armadillo (52,000, closed),
#                         lion-head (16,674, open), mannequin-devil (25,888, open)
#   Organic:              camel (19,536), elephant (5,558, genus 3), man (34,986),
#                         ChineseDragon-10kv (19,994, open: 6 border edges)
#   Open, many holes:     elephant-with-holes (4,463 faces, 1,353 border edges)
#   Scale:                bunny00-loop2: two Loop subdivisions of bunny00 (OpenMesh LoopT),
#                         1,206,528 faces
# plus two small meshes the tests use and the benchmark does not (tests/bench/bench.py names its
# own list): cow (5,804 faces) and mushroom (4,608, open).
#
# When 'apt-get download' fails and we are root, the package lists are refreshed once and the
# download retried (a fresh machine may have none).
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:-build}
corpus=corpus
meshes=(fandisk blade mech-holes-shark turbine cheese bunny00 armadillo lion-head mannequin-devil
        camel elephant man ChineseDragon-10kv elephant-with-holes cow mushroom)

have_all=1
for m in "${meshes[@]}"; do [ -s "$corpus/$m.off" ] || have_all=0; done
if [ $have_all = 0 ]; then
  tmp=$(mktemp -d)
  trap 'rm -rf "$tmp"' EXIT
  download() { (cd "$tmp" && apt-get download libcgal-demo >/dev/null 2>&1); }
  if ! download; then
    if [ "$(id -u)" = 0 ]; then apt-get update >/dev/null 2>&1 || true; fi
    download || {
      echo "fetch_corpus: 'apt-get download libcgal-demo' failed (run apt-get update?)" >&2; exit 1; }
  fi
  dpkg-deb -x "$tmp"/libcgal-demo_*.deb "$tmp/pkg"
  tar xzf "$tmp/pkg/usr/share/doc/libcgal-dev/data.tar.gz" -C "$tmp" data/meshes
  mkdir -p "$corpus"
  for m in "${meshes[@]}"; do
    [ -s "$tmp/data/meshes/$m.off" ] || { echo "fetch_corpus: $m.off not in libcgal-demo" >&2; exit 1; }
    cp "$tmp/data/meshes/$m.off" "$corpus/$m.off"
  done
fi

big="$corpus/bunny00-loop2.off"
if [ ! -s "$big" ]; then
  tool="$build/bench/bench-subdivide"
  if [ ! -x "$tool" ]; then
    echo "fetch_corpus: $tool missing; build it first: ninja -C $build bench-subdivide" >&2
    exit 1
  fi
  "$tool" "$corpus/bunny00.off" "$big" 2 >/dev/null
fi
echo "fetch_corpus: $(ls "$corpus"/*.off | wc -l) meshes in $corpus/"
