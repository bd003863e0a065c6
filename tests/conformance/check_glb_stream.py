#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Checks a GLB made by scripts/pmz_to_glb.py against the conformance vector it carries.

    check_glb_stream.py --decoder pmz-decode --stream vectors/NAME.pmz --expected NAME.expected X.glb

The PMZ_progressive_mesh buffer view must hold the vector byte for byte and be the last view;
the base primitive must be the vector's level 0 (the .expected file's hash); the stream, cut out
of the GLB and decoded with pmz-decode at every level the .expected file lists (the whole stream
included), must give that level's vertex and face counts and hash, and the full level the
extension's fullVertexCount and fullFaceCount, within fullBounds. One line per failure on
stderr, exit 1.
"""
import argparse
import hashlib
import json
import os
import struct
import subprocess
import sys
import tempfile

EXTENSION = "PMZ_progressive_mesh"
failures = []


def check(ok, what):
    if not ok:
        failures.append(what)
    return ok


def glb_parts(data):
    """The JSON object and the BIN chunk of a GLB 2.0 file."""
    magic, version, length = struct.unpack_from("<4sII", data, 0)
    if magic != b"glTF" or version != 2 or length != len(data):
        raise ValueError("not a GLB 2.0 file of its size")
    json_len, json_type = struct.unpack_from("<I4s", data, 12)
    bin_at = 20 + json_len
    bin_len, bin_type = struct.unpack_from("<I4s", data, bin_at)
    if json_type != b"JSON" or bin_type != b"BIN\0":
        raise ValueError("chunks are not JSON then BIN")
    return json.loads(data[20:bin_at]), data[bin_at + 8 : bin_at + 8 + bin_len]


def view_bytes(gltf, blob, index):
    view = gltf["bufferViews"][index]
    return blob[view.get("byteOffset", 0) : view.get("byteOffset", 0) + view["byteLength"]]


def level_hash(positions, indices):
    """The conformance level hash (tests/conformance/README.md): f32 positions, then u32 faces."""
    return hashlib.sha256(positions + indices).hexdigest()


def decoded_level(decoder, stream_path, vertices, work):
    """(vertex count, face count, positions bytes, indices bytes) of pmz-decode's binary PLY at the
    level with `vertices` vertices."""
    out = os.path.join(work, f"level{vertices}.ply")
    run = subprocess.run([decoder, stream_path, "-o", out, "--vertices", str(vertices)],
                         capture_output=True, text=True)
    if run.returncode != 0:
        raise ValueError("pmz-decode failed: " + run.stderr.strip())
    with open(out, "rb") as f:
        data = f.read()
    end = data.index(b"end_header\n") + len(b"end_header\n")
    counts = {}
    for line in data[:end].decode("ascii").splitlines():
        if line.startswith("element "):
            _, name, count = line.split()
            counts[name] = int(count)
    nv, nf = counts["vertex"], counts["face"]
    positions = data[end : end + 12 * nv]
    faces = data[end + 12 * nv :]
    if len(faces) != 13 * nf or any(faces[13 * f] != 3 for f in range(nf)):
        raise ValueError("faces are not uchar 3 + three u32 each")
    indices = b"".join(faces[13 * f + 1 : 13 * f + 13] for f in range(nf))
    return nv, nf, positions, indices


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("glb")
    ap.add_argument("--decoder", required=True)
    ap.add_argument("--stream", required=True, help="the .pmz the GLB was made from")
    ap.add_argument("--expected", required=True, help="the stream's conformance .expected file")
    args = ap.parse_args()
    with open(args.glb, "rb") as f:
        gltf, blob = glb_parts(f.read())
    with open(args.stream, "rb") as f:
        original = f.read()
    levels = []  # (level, vertices, faces, hash)
    total = -1  # splits of the whole stream
    with open(args.expected) as f:
        for line in f:
            words = line.split()
            if words[:1] == ["level"]:
                levels.append((int(words[1]), int(words[3]), int(words[5]), words[7]))
            if words[:2] == ["refined", "ok"]:
                total = int(words[2])
    if not check(levels and levels[0][0] == 0 and levels[-1][0] == total,
                 f"{args.expected}: no lines for level 0 and the full mesh"):
        return

    primitive = gltf["meshes"][0]["primitives"][0]
    ext = primitive["extensions"][EXTENSION]
    stream = view_bytes(gltf, blob, ext["bufferView"])
    check(stream == original, "the extension's buffer view is not the stream byte for byte")
    check(ext["bufferView"] == len(gltf["bufferViews"]) - 1, "the stream is not the last view")
    check("target" not in gltf["bufferViews"][ext["bufferView"]], "the stream's view has a target")

    # The base primitive: the stream's level 0.
    accessors = gltf["accessors"]
    base_positions = view_bytes(gltf, blob, accessors[primitive["attributes"]["POSITION"]]["bufferView"])
    base_indices = view_bytes(gltf, blob, accessors[primitive["indices"]]["bufferView"])
    _, v0, f0, h0 = levels[0]
    check(len(base_positions) == 12 * v0 and len(base_indices) == 12 * f0,
          f"base primitive: {len(base_positions) // 12} vertices, {len(base_indices) // 12} faces; "
          f"level 0 has {v0} and {f0}")
    check(level_hash(base_positions, base_indices) == h0, "base primitive differs from level 0")

    # The stream out of the GLB, decoded at every listed level, the last one the full mesh.
    with tempfile.TemporaryDirectory() as work:
        path = os.path.join(work, "stream.pmz")
        with open(path, "wb") as f:
            f.write(stream)
        for level, vertices, faces, want in levels:
            nv, nf, positions, indices = decoded_level(args.decoder, path, vertices, work)
            check((nv, nf) == (vertices, faces),
                  f"level {level}: {nv} vertices, {nf} faces; expected {vertices} and {faces}")
            check(level_hash(positions, indices) == want, f"level {level}: hash differs")
        full = levels[-1]
        check((full[1], full[2]) == (ext["fullVertexCount"], ext["fullFaceCount"]),
              f"full mesh: {full[1]} vertices, {full[2]} faces; the extension says "
              f"{ext['fullVertexCount']} and {ext['fullFaceCount']}")
        _, _, positions, _ = decoded_level(args.decoder, path, full[1], work)
        coords = struct.unpack(f"<{len(positions) // 4}f", positions)
        lo, hi = ext["fullBounds"]["min"], ext["fullBounds"]["max"]
        check(all(lo[i % 3] <= c <= hi[i % 3] for i, c in enumerate(coords)),
              "the full mesh leaves fullBounds")


if __name__ == "__main__":
    try:
        main()
    except (OSError, ValueError, KeyError, IndexError, struct.error) as e:
        failures.append(str(e))
    for line in failures:
        sys.stderr.write(f"check_glb_stream: {line}\n")
    sys.exit(1 if failures else 0)
