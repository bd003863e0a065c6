#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Wraps a .pmz stream in a binary glTF 2.0 asset (docs/gltf-binding.md, draft).

The base mesh becomes an ordinary triangle primitive (POSITION, indices), so a loader without
the extension shows it; the whole .pmz stream follows in the BIN chunk as the last buffer view,
named by the primitive's PMZ_progressive_mesh extension.

    python3 scripts/pmz_to_glb.py --decoder build/bin/pmz-decode in.pmz -o out.glb
"""
import argparse
import json
import os
import struct
import subprocess
import sys
import tempfile

SIGNATURE = b"\x89PMZ\r\n\x1a\n"
EXTENSION = "PMZ_progressive_mesh"


def fail(path, reason):
    sys.stderr.write(f"pmz_to_glb: {path}: {reason}\n")
    sys.exit(1)


def varint(data, at):
    value = shift = 0
    for i in range(10):
        if at + i >= len(data):
            raise ValueError("varint runs past the end")
        b = data[at + i]
        value |= (b & 0x7F) << shift
        shift += 7
        if not b & 0x80:
            return value, at + i + 1
    raise ValueError("varint of more than 10 bytes")


def read_head(data):
    """HEAD's fields (spec/format.md section 4) from the first chunk."""
    if data[:8] != SIGNATURE:
        raise ValueError("not a .pmz stream")
    if len(data) < 9 or data[8] != 1:
        raise ValueError("first chunk is not HEAD")
    size, at = varint(data, 9)
    p, end = at + 4, at + 4 + size
    if end > len(data):
        raise ValueError("HEAD cut short")
    head = {"version": f"{data[p]}.{data[p + 1]}"}
    p += 2
    head["flags"], p = varint(data, p)
    head["position_bits"], head["curvature"], head["fine_curvature"], head["level"] = data[p : p + 4]
    p += 4
    for name in ("base_vertices", "base_faces", "total_splits", "full_faces"):
        head[name], p = varint(data, p)
    head["bbox_min"] = list(struct.unpack_from("<3f", data, p))
    head["bbox_max"] = list(struct.unpack_from("<3f", data, p + 12))
    return head


def read_ply(path):
    """Vertices (float xyz) and triangles of pmz-decode's binary little-endian PLY."""
    with open(path, "rb") as f:
        data = f.read()
    end = data.index(b"end_header\n") + len(b"end_header\n")
    header = data[:end].decode("ascii").splitlines()
    if "format binary_little_endian 1.0" not in header:
        raise ValueError("expected a binary little-endian PLY")
    counts = {}
    for line in header:
        words = line.split()
        if words[:1] == ["element"]:
            counts[words[1]] = int(words[2])
        if words[:2] == ["property", "list"] and words[2:4] not in (["uchar", "uint"], ["uchar", "int"]):
            raise ValueError("expected face lists of uchar count, int or uint indices")
    nv, nf = counts["vertex"], counts["face"]
    positions = struct.unpack_from(f"<{3 * nv}f", data, end)
    at = end + 12 * nv
    indices = []
    for _ in range(nf):
        if data[at] != 3:
            raise ValueError("a face that is not a triangle")
        indices.extend(struct.unpack_from("<3I", data, at + 1))
        at += 13
    return positions, indices


def pad4(b, fill):
    return b + fill * (-len(b) % 4)


def build_glb(stream, head, positions, indices):
    nv = len(positions) // 3
    pos_bytes = struct.pack(f"<{len(positions)}f", *positions)
    idx_bytes = struct.pack(f"<{len(indices)}I", *indices)
    # BIN: the base (positions, indices), then the stream last, so a loader reading the file
    # front to back draws the base before the stream's bytes arrive.
    views, blob = [], b""
    for data, target in ((pos_bytes, 34962), (idx_bytes, 34963), (stream, None)):
        blob = pad4(blob, b"\0")
        view = {"buffer": 0, "byteOffset": len(blob), "byteLength": len(data)}
        if target:
            view["target"] = target
        views.append(view)
        blob += data
    blob = pad4(blob, b"\0")
    lo = [min(positions[a::3]) for a in range(3)]
    hi = [max(positions[a::3]) for a in range(3)]
    gltf = {
        "asset": {"version": "2.0", "generator": "pmz scripts/pmz_to_glb.py"},
        "extensionsUsed": [EXTENSION],
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0}],
        "meshes": [
            {
                "primitives": [
                    {
                        "attributes": {"POSITION": 0},
                        "indices": 1,
                        "mode": 4,
                        "extensions": {
                            EXTENSION: {
                                "bufferView": 2,
                                "version": head["version"],
                                "fullVertexCount": head["base_vertices"] + head["total_splits"],
                                "fullFaceCount": head["full_faces"],
                                "fullBounds": {"min": head["bbox_min"], "max": head["bbox_max"]},
                            }
                        },
                    }
                ]
            }
        ],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": nv, "type": "VEC3",
             "min": lo, "max": hi},
            {"bufferView": 1, "componentType": 5125, "count": len(indices), "type": "SCALAR"},
        ],
        "bufferViews": views,
        "buffers": [{"byteLength": len(blob)}],
    }
    js = pad4(json.dumps(gltf, separators=(",", ":"), sort_keys=True).encode("utf-8"), b" ")
    total = 12 + 8 + len(js) + 8 + len(blob)
    return (struct.pack("<4sII", b"glTF", 2, total) + struct.pack("<I4s", len(js), b"JSON") + js
            + struct.pack("<I4s", len(blob), b"BIN\0") + blob)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("input")
    ap.add_argument("-o", "--output", required=True)
    ap.add_argument("--decoder", default="pmz-decode", help="pmz-decode binary")
    args = ap.parse_args()
    try:
        with open(args.input, "rb") as f:
            stream = f.read()
    except OSError as e:
        fail(args.input, e.strerror)
    try:
        head = read_head(stream)
    except (ValueError, IndexError, struct.error) as e:
        fail(args.input, str(e))
    with tempfile.TemporaryDirectory() as tmp:
        ply = os.path.join(tmp, "base.ply")
        # The level with base_vertices vertices is the base mesh (spec/format.md section 9).
        run = subprocess.run([args.decoder, args.input, "-o", ply, "--vertices",
                              str(max(head["base_vertices"], 1))], capture_output=True, text=True)
        if run.returncode != 0:
            fail(args.input, "pmz-decode failed: " + run.stderr.strip())
        positions, indices = read_ply(ply)
    if len(positions) // 3 != head["base_vertices"] or len(indices) // 3 != head["base_faces"]:
        fail(args.input, "the decoded base does not have HEAD's counts")
    glb = build_glb(stream, head, positions, indices)
    tmp_out = args.output + ".tmp"
    with open(tmp_out, "wb") as f:
        f.write(glb)
    os.replace(tmp_out, args.output)


if __name__ == "__main__":
    main()
