#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# Web benchmarks: decoder size and decode speed side by side with npm draco3d, and
# streaming in headless Chromium over a 2 MB/s link. Needs bash scripts/web.sh (the package),
# build/bin/pmz-encode, build/bench/bench-stream, draco_encoder and the corpus.
#   bash web/bench/run.sh [MESH.off=corpus/bunny00-loop2.off] [OUT_DIR=bench-out/web]
set -euo pipefail
cd "$(dirname "$0")/../.."
mesh=${1:-corpus/bunny00-loop2.off}
out=${2:-bench-out/web}
name=$(basename "$mesh" .off)
mkdir -p "$out"
[ -f "$out/$name.pmz" ] || build/bin/pmz-encode "$mesh" -o "$out/$name.pmz"
if [ ! -f "$out/$name.drc" ]; then
  # Draco's OFF reader refuses these files: binary PLY with the same floats and faces.
  python3 - "$mesh" "$out/$name.ply" <<'PY'
import struct, sys
with open(sys.argv[1]) as f:
    assert f.readline().strip() == 'OFF'
    nv, nf = map(int, f.readline().split()[:2])
    vs = [struct.pack('<3f', *map(float, f.readline().split()[:3])) for _ in range(nv)]
    fs = [struct.pack('<B3i', 3, *map(int, f.readline().split()[1:4])) for _ in range(nf)]
with open(sys.argv[2], 'wb') as o:
    o.write(('ply\nformat binary_little_endian 1.0\nelement vertex %d\nproperty float x\n'
             'property float y\nproperty float z\nelement face %d\n'
             'property list uchar int vertex_indices\nend_header\n' % (nv, nf)).encode())
    o.write(b''.join(vs) + b''.join(fs))
PY
  draco_encoder -i "$out/$name.ply" -o "$out/$name.drc" -qp 14 -cl 10 >/dev/null
fi
node web/bench/decode_speed.mjs "$out/$name.pmz" "$out/$name.drc" 5 | tee "$out/decode_speed.json"
node web/bench/stream_chromium.mjs "$out/$name.pmz" 2000000 3 | tee "$out/stream_chromium.json"
