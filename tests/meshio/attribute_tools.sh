#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# Tool behaviour with attributes and bad attribute input (ctest encode_attribute_tools):
# pmz-encode says which attributes it encoded, pmz-decode and pmz-simplify keep them (and says so when the
# output format cannot), both report
# triangulation, and refuse a bad glTF with one line naming it, writing nothing.
# usage: attribute_tools.sh PMZ_ENCODE PMZ_SIMPLIFY WORK_DIR
set -euo pipefail
encode=$1 simplify=$2 work=$3
rm -rf "$work" && mkdir -p "$work" && cd "$work"
fail() { echo "FAIL: $*" >&2; exit 1; }

cat > quad.obj <<'OBJ'
mtllib quad.mtl
v 0 0 0
v 1 0 0
v 1 1 0
v 0 1 0
v 2 0 0
vt 0 0
vt 1 0
vt 1 1
vt 0 1
vn 0 0 1
usemtl paper
f 1/1/1 2/2/1 3/3/1 4/4/1
f 2/2/1 5/1/1 3/3/1
OBJ
printf 'newmtl paper\nKd 1 1 1\nmap_Kd paper.png\n' > quad.mtl
"$encode" quad.obj -o quad.pmz > encode.out 2> encode.err || fail "pmz-encode quad.obj: $(cat encode.err)"
[ -s quad.pmz ] || fail "no quad.pmz"
grep -qx "pmz-encode: quad.obj: triangulated 1 polygon into 2 triangles" encode.err ||
  fail "no triangulation line: $(cat encode.err)"
# Format 8.0 encodes them: the summary line says which.
grep -q "; attributes: texture coordinates, normals, 1 material, [0-9]* bytes$" encode.out ||
  fail "no attribute summary: $(cat encode.out)"
if grep -q attributes encode.err; then fail "attribute warning: $(cat encode.err)"; fi
# pmz-decode writes them back: OBJ with its MTL beside it, PLY, glb; OFF says what it drops.
decode=$(dirname "$encode")/pmz-decode
"$decode" quad.pmz -o back.obj 2> decode.err || fail "pmz-decode back.obj: $(cat decode.err)"
grep -q "^mtllib back.mtl" back.obj && grep -q "^usemtl paper" back.obj &&
  grep -q "^vt " back.obj && grep -q "^vn " back.obj || fail "back.obj lost its attributes"
grep -q "^map_Kd paper.png" back.mtl || fail "back.mtl: $(cat back.mtl 2>&1)"
# The MTL is written as safely as the output: through a symlink (kept, its target updated).
mkdir -p linked && printf 'old\n' > linked/target.mtl && ln -s target.mtl linked/back.mtl
"$decode" quad.pmz -o linked/back.obj 2> decode.err || fail "pmz-decode linked/back.obj: $(cat decode.err)"
[ -L linked/back.mtl ] || fail "pmz-decode replaced the symlinked MTL by a file"
grep -q "^map_Kd paper.png" linked/target.mtl || fail "the MTL's link target was not updated"
"$decode" quad.pmz -o back.ply 2> decode.err || fail "pmz-decode back.ply: $(cat decode.err)"
grep -aq "^property float texture_u" back.ply && grep -aq "^property float nx" back.ply ||
  fail "back.ply lost its attributes"
"$decode" quad.pmz -o back.glb 2> decode.err || fail "pmz-decode back.glb: $(cat decode.err)"
[ "$(head -c 4 back.glb)" = glTF ] || fail "back.glb is not a glb"
"$decode" quad.pmz -o back.off 2> decode.err || fail "pmz-decode back.off: $(cat decode.err)"
grep -qx "pmz-decode: back.off: .off holds positions and triangles only; the attributes (texture coordinates, normals, 1 material) are not written (use .obj, .ply or .glb)" decode.err ||
  fail "no pmz-decode .off attribute line: $(cat decode.err)"
"$decode" quad.pmz -o - --format obj > stdout.obj 2> decode.err || fail "pmz-decode to stdout"
grep -q "^usemtl paper" stdout.obj || fail "stdout.obj lost its materials"

# pmz-simplify keeps the attributes (simplified along its seams); OFF cannot hold them: one line.
"$simplify" quad.obj -o small.obj --faces 2 2> simplify.err || fail "pmz-simplify: $(cat simplify.err)"
if grep -q "attributes" simplify.err; then fail "pmz-simplify attribute line for .obj: $(cat simplify.err)"; fi
grep -q "^vt " small.obj && grep -q "^vn " small.obj && grep -q "^usemtl paper" small.obj &&
  grep -q "^mtllib small.mtl" small.obj && grep -q "^map_Kd paper.png" small.mtl ||
  fail "small.obj lost its attributes"
"$simplify" quad.obj -o small.off --faces 2 2> simplify.err || fail "pmz-simplify: $(cat simplify.err)"
grep -qx "pmz-simplify: small.off: .off holds positions and triangles only; the attributes (texture coordinates, normals, 1 material) are not written (use .obj, .ply or .glb)" simplify.err ||
  fail "no pmz-simplify .off attribute line: $(cat simplify.err)"

# A plain mesh gets no attribute line.
printf 'v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n' > plain.obj
"$encode" plain.obj -o plain.pmz 2> plain.err || fail "pmz-encode plain.obj"
if grep -q attributes plain.err; then fail "attribute line for a plain mesh"; fi

# A glTF whose index points past its vertices: one line, non-zero exit, nothing written.
python3 - <<'PY'
import base64, json, struct
data = struct.pack('<9f', 0, 0, 0, 1, 0, 0, 0, 1, 0) + struct.pack('<4H', 0, 1, 9, 0)
doc = {'asset': {'version': '2.0'}, 'meshes': [{'primitives': [{'attributes': {'POSITION': 0}, 'indices': 1}]}],
       'accessors': [{'bufferView': 0, 'componentType': 5126, 'count': 3, 'type': 'VEC3'},
                     {'bufferView': 1, 'componentType': 5123, 'count': 3, 'type': 'SCALAR'}],
       'bufferViews': [{'buffer': 0, 'byteLength': 36}, {'buffer': 0, 'byteOffset': 36, 'byteLength': 6}],
       'buffers': [{'byteLength': len(data), 'uri': 'data:application/octet-stream;base64,' + base64.b64encode(data).decode()}]}
open('bad.gltf', 'w').write(json.dumps(doc))
PY
if "$encode" bad.gltf -o bad.pmz 2> bad.err; then fail "bad.gltf accepted"; fi
[ "$(wc -l < bad.err)" = 1 ] || fail "bad.gltf: not one line: $(cat bad.err)"
grep -q "^pmz-encode: bad.gltf: mesh 0 primitive 0 index 2 is 9, but POSITION has 3 vertices" bad.err ||
  fail "bad.gltf message: $(cat bad.err)"
[ ! -e bad.pmz ] || fail "bad.pmz written"
[ -z "$(ls -A | grep -i tmp || true)" ] || fail "temporary file left"
echo "attribute tools: ok"
